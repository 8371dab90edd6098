"""skfem-npfem: the nodal-integration particle finite element method for scikit-fem.

Quick start::

    import skfem_npfem as npfem
    summary = npfem.run_scene("elastic-column", {"spacing": 0.25})
    print(summary["metrics"]["sigma_v_rel_l2"])
"""

from __future__ import annotations

__version__ = "0.1.0"

from .boundary import RigidWall, floor, wall_x
from .conic import Contacts, SolverOptions, StepData, StepSolution, solve_step
from .errors import CheckpointError, NpfemError, ParameterError, SolverError
from .materials import (
    DruckerPrager,
    LinearElastic,
    Material,
    MohrCoulomb,
    Tresca,
    VonMises,
    compliance_matrix,
)
from .particles import Particles
from .pfem import AlphaShapeMesher, main_body
from .remesh import Triangulation, alpha_shape
from .scenes import SCENES, get_scene, run_scene
from .simulation import AtRest, FixedMesh, Model, Simulation, StepRecord, advance
from .smoothing import NodalIntegration, nodal_integration, p1_gradients
from .sweeps import sweep

__all__ = [
    "SCENES",
    "AlphaShapeMesher",
    "AtRest",
    "CheckpointError",
    "Contacts",
    "DruckerPrager",
    "FixedMesh",
    "LinearElastic",
    "Material",
    "Model",
    "MohrCoulomb",
    "NodalIntegration",
    "NpfemError",
    "ParameterError",
    "Particles",
    "RigidWall",
    "Simulation",
    "SolverError",
    "SolverOptions",
    "StepData",
    "StepRecord",
    "StepSolution",
    "Tresca",
    "Triangulation",
    "VonMises",
    "__version__",
    "advance",
    "alpha_shape",
    "compliance_matrix",
    "floor",
    "get_scene",
    "main_body",
    "nodal_integration",
    "p1_gradients",
    "run_scene",
    "solve_step",
    "sweep",
    "wall_x",
]
