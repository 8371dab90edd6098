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
files are :mod:`.io`'s.  Every public name is available flat from the package;
``__all__`` groups them by what a user does (the API reference follows it).

A scikit-fem mesh goes in and comes out: :meth:`Particles.from_mesh` puts a
particle on every node of a ``MeshTri``/``MeshTet``, the same mesh is the mesh
source of :func:`advance`, and :meth:`Step.to_skfem` returns the step's mesh
with the particle fields as P1 degrees of freedom.
"""

from __future__ import annotations

__version__ = "0.1.0"

from ._deprecated import RENAMED as _RENAMED
from ._deprecated import renamed as _renamed

# isort: split
from .axisymmetric import (
    AxisymmetricIntegration,
    AxisymmetricMohrCoulomb,
    axisymmetric_integration,
)
from .boundary import Contacts, RigidWall, floor, wall_x
from .conic import ConeSolution, solve_step
from .errors import (
    CheckpointError,
    NpfemError,
    ParameterError,
    RunInterrupted,
    SolverError,
)
from .io import read_pvd, read_step
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
from .program import ConeInput
from .remesh import Triangulation, alpha_shape
from .scenes import SCENES, get_scene, run_scene
from .simulation import AtRest, Simulation
from .smoothing import NodalIntegration, nodal_integration, p1_gradients
from .solver import SolverOptions
from .step import Step, StepRecord, advance, skfem_fields
from .sweeps import sweep

#: Run a scene.
__all__ = ["SCENES", "AtRest", "Simulation", "__version__", "get_scene", "run_scene"]
#: Build particles and meshes.
__all__ += [
    "AlphaShapeMesher",
    "AxisymmetricIntegration",
    "FixedMesh",
    "NodalIntegration",
    "Particles",
    "Triangulation",
    "alpha_shape",
    "axisymmetric_integration",
    "main_body",
    "nodal_integration",
    "p1_gradients",
]
#: Materials.
__all__ += [
    "AxisymmetricMohrCoulomb",
    "DruckerPrager",
    "LinearElastic",
    "Material",
    "MohrCoulomb",
    "Tresca",
    "VonMises",
    "compliance_matrix",
]
#: Boundaries.
__all__ += ["Contacts", "RigidWall", "floor", "wall_x"]
#: One step.
__all__ += [
    "ConeInput",
    "ConeSolution",
    "Model",
    "SolverOptions",
    "Step",
    "StepRecord",
    "advance",
    "solve_step",
]
#: Sweeps.
__all__ += ["sweep"]
#: Post-processing.
__all__ += ["read_pvd", "read_step", "skfem_fields"]
#: Errors.
__all__ += [
    "CheckpointError",
    "NpfemError",
    "ParameterError",
    "RunInterrupted",
    "SolverError",
]


def __getattr__(name: str) -> object:
    """Old names of the step types, with a ``DeprecationWarning``.

    ``StepData`` is :class:`ConeInput`, ``StepSolution`` :class:`ConeSolution`
    and ``StepResult`` :class:`Step` (the same classes: ``isinstance`` keeps
    working); they go in the next release.
    """
    return _renamed(
        __name__, name, {old: globals()[new] for old, new in _RENAMED.items()}
    )
