"""Baselines beside N-PFEM: FEM with remapping and the explicit smoothed PFEM.

Both advance the same particles as :func:`skfem_npfem.advance`, on the
same meshes (``mesh_source``), with the same walls and materials, and return
the same ``(particles, Step)``, so :class:`~skfem_npfem.Simulation`
runs them as its ``stepper`` (the scenes' ``--set method=``):

* :class:`FemRemap` - the classical PFEM: stress and plastic strain at the
  Gauss points of scikit-fem P1/P2 elements, moved to each new mesh by a
  transfer operator, and the library's cone step
  (:func:`skfem_npfem.step.conic.solve_step`) with the Gauss points as stress points;
* :class:`SPFEM` - nodal integration with explicit central differences and a
  closed-form return mapping.

Building blocks: :mod:`.operators` (Gauss-point operators from scikit-fem
bases), :mod:`.fem_nodes` (P1/P2 nodal data), :mod:`.transfer` (nearest /
patch recovery), :mod:`.returnmap` (closed-form return to the library's
cones).  A method is chosen by name in :mod:`skfem_npfem.scenes.methods`,
which also records each step's stress roughness (:mod:`skfem_npfem.metrics`).
"""

from .fem_remap import FemRemap, GaussState
from .operators import GaussMesh, StressPoints, gauss_mesh
from .returnmap import ReturnResult, return_map
from .spfem import SPFEM, stable_time_step
from .transfer import TRANSFERS, locate, recover_nodal, transfer_values

__all__ = [
    "SPFEM",
    "TRANSFERS",
    "FemRemap",
    "GaussMesh",
    "GaussState",
    "ReturnResult",
    "StressPoints",
    "gauss_mesh",
    "locate",
    "recover_nodal",
    "return_map",
    "stable_time_step",
    "transfer_values",
]
