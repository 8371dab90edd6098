"""skfem-npfem: the nodal-integration particle finite element method for scikit-fem.

Quick start::

    import skfem_npfem as npfem
    summary = npfem.run_scene("elastic-column", {"spacing": 0.25})
    print(summary["metrics"]["sigma_v_rel_l2"])

The subpackages follow one step's data flow: particles (:mod:`.particles`, with
:mod:`.materials` and the walls of :mod:`.boundary`) -> their mesh and smoothing
cells (:mod:`.mesh`) -> the cone program, solved and read back (:mod:`.step`) ->
the time loop with output and checkpoints (:mod:`.run`, files in :mod:`.io`).
Ready problems are :mod:`.scenes`; :mod:`.baseline` holds the methods N-PFEM is
compared with, :mod:`.sweeps` runs parameter studies on Dask, :mod:`.viz` draws,
:mod:`.cli` is the command line.  Every public name is available flat from the
package.
"""

from __future__ import annotations

from . import _compat

__version__ = "0.1.0"

# High level: ready scenes and the time loop.
from .run.simulation import AtRest, Simulation
from .scenes import SCENES, get_scene, run_scene

# isort: split
# Building blocks: particles, meshes, materials, smoothing, boundaries, the step.
from .boundary import Contacts, RigidWall, floor, wall_x
from .materials import (
    DruckerPrager,
    LinearElastic,
    Material,
    MohrCoulomb,
    Tresca,
    VonMises,
    compliance_matrix,
)
from .mesh.delaunay import Triangulation, alpha_shape
from .mesh.smoothing import NodalIntegration, nodal_integration, p1_gradients
from .mesh.sources import AlphaShapeMesher, FixedMesh, main_body
from .particles import Particles
from .step.conic import StepSolution, solve_step
from .step.model import Model
from .step.program import StepData
from .step.solver import SolverOptions
from .step.stages import StepRecord, StepResult, advance
from .sweeps import sweep

# isort: split
from .errors import (
    CheckpointError,
    NpfemError,
    ParameterError,
    RunInterrupted,
    SolverError,
)

#: High level: ready scenes and the time loop.
__all__ = ["SCENES", "AtRest", "Simulation", "__version__", "get_scene", "run_scene"]
#: Particles and their meshes.
__all__ += [
    "AlphaShapeMesher",
    "FixedMesh",
    "Particles",
    "Triangulation",
    "alpha_shape",
    "main_body",
]
#: Materials.
__all__ += [
    "DruckerPrager",
    "LinearElastic",
    "Material",
    "MohrCoulomb",
    "Tresca",
    "VonMises",
    "compliance_matrix",
]
#: Smoothing cells.
__all__ += ["NodalIntegration", "nodal_integration", "p1_gradients"]
#: Boundaries.
__all__ += ["Contacts", "RigidWall", "floor", "wall_x"]
#: The step.
__all__ += [
    "Model",
    "SolverOptions",
    "StepData",
    "StepRecord",
    "StepResult",
    "StepSolution",
    "advance",
    "solve_step",
    "sweep",
]
#: Errors.
__all__ += [
    "CheckpointError",
    "NpfemError",
    "ParameterError",
    "RunInterrupted",
    "SolverError",
]


# The flat modules of earlier releases, now in subpackages: ``import
# skfem_npfem.conic`` and the like keep working (with a DeprecationWarning)
# for one release.
_MOVED = {
    "pfem": "mesh.sources",
    "remesh": "mesh.delaunay",
    "surface": "mesh.surface",
    "smoothing": "mesh.smoothing",
    "axisymmetric": "mesh.axisymmetric",
    "model": "step.model",
    "program": "step.program",
    "families": "step.families",
    "stabilisation": "step.stabilisation",
    "volume": "step.volume",
    "conic": "step.conic",
    "solver": "step.solver",
    "backends": "step.backends",
    "kinematics": "step.kinematics",
    "simulation": "run.simulation",
    "runcontrol": "run.control",
    "plot": "viz.plot",
    "figures": "viz.figures",
    "render": "viz.render",
    "scenery": "viz.scenery",
}
_compat.install_aliases(__name__, _MOVED)
