"""skfem-npfem: the nodal-integration particle finite element method for scikit-fem.

Quick start::

    import skfem_npfem as npfem
    summary = npfem.run_scene("elastic-column", {"spacing": 0.25})
    print(summary["metrics"]["sigma_v_rel_l2"])

One step's data flow, one module per stage: particles (:mod:`.particles`) ->
mesh source (:mod:`.pfem`, :mod:`.remesh`) -> smoothing cells
(:mod:`.smoothing`) -> cone program (:mod:`.program`, :mod:`.families`,
:mod:`.conic`, :mod:`.solver`) -> particle update (:mod:`.step`,
:mod:`.kinematics`, :mod:`.boundary`); the time loop is :mod:`.simulation`,
files are :mod:`.io`'s.  Every public name is available flat from the package.
"""

from __future__ import annotations

__version__ = "0.1.0"

# High level: ready scenes and the time loop.
from .scenes import SCENES, get_scene, run_scene
from .simulation import AtRest, Simulation

# isort: split
# Building blocks: particles, meshes, materials, smoothing, boundaries, the step.
from .boundary import Contacts, RigidWall, floor, wall_x
from .conic import StepSolution, solve_step
from .io import ResultWriter
from .materials import (
    DruckerPrager,
    LinearElastic,
    Material,
    MohrCoulomb,
    Tresca,
    VonMises,
    compliance_matrix,
)
from .model import Model
from .particles import Particles
from .pfem import AlphaShapeMesher, FixedMesh, main_body
from .program import StepData
from .remesh import Triangulation, alpha_shape
from .smoothing import NodalIntegration, nodal_integration, p1_gradients
from .solver import SolverOptions
from .step import StepRecord, StepResult, advance
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
#: Output: the VTU series of a run (``Simulation(..., writer=ResultWriter(dir))``).
__all__ += ["ResultWriter"]
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
