"""Baselines beside N-PFEM: FEM with remapping and the explicit smoothed PFEM.

Both advance the same particles as :func:`skfem_npfem.simulation.advance`, on
the same meshes (``mesh_source``), with the same walls and materials:

* :class:`FemRemap` - the classical PFEM: stress and plastic strain at the
  Gauss points of scikit-fem P1/P2 elements, moved to each new mesh by a
  transfer operator, and the same cone program as N-PFEM;
* :class:`SPFEM` - nodal integration with explicit central differences and a
  closed-form return mapping.

Building blocks: :mod:`.operators` (Gauss-point operators from scikit-fem
bases), :mod:`.program` (the cone program on stress points), :mod:`.transfer`
(nearest / patch recovery), :mod:`.returnmap` (closed-form return to the
library's cones).
"""

from .fem_remap import FemRemap, GaussState
from .methods import METHOD_OPTIONS, METHODS, make_method
from .operators import GaussMesh, StressPoints, from_nodal_integration, gauss_mesh
from .program import GaussStepData, solve_gauss_step
from .returnmap import ReturnResult, return_map
from .spfem import SPFEM, stable_time_step
from .transfer import TRANSFERS, locate, recover_nodal, transfer_values

__all__ = [
    "METHODS",
    "METHOD_OPTIONS",
    "SPFEM",
    "TRANSFERS",
    "FemRemap",
    "GaussMesh",
    "GaussState",
    "GaussStepData",
    "ReturnResult",
    "StressPoints",
    "from_nodal_integration",
    "gauss_mesh",
    "locate",
    "make_method",
    "recover_nodal",
    "return_map",
    "solve_gauss_step",
    "stable_time_step",
    "transfer_values",
]
