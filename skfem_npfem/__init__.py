"""skfem-npfem: the nodal-integration particle finite element method for scikit-fem.

Quick start::

    import skfem_npfem as npfem
    summary = npfem.run_scene("elastic-column", {"spacing": 0.25})
    print(summary["metrics"]["sigma_v_rel_l2"])

The subpackages follow one step's data flow: particles (:mod:`.particles`, with
:mod:`.materials` and the walls of :mod:`.boundary`) -> their mesh and smoothing
cells (:mod:`.mesh`) -> the cone program, solved and read back (:mod:`.step`) ->
the time loop with output and checkpoints (:mod:`.run`, files in :mod:`.io`).
:mod:`.limit` finds the collapse multiplier and the factor of safety on the
step's operator and cones.  Ready problems are :mod:`.scenes`; :mod:`.baseline`
holds the methods N-PFEM is compared with, :mod:`.metrics` the stress roughness
they are measured by, :mod:`.sweeps` runs parameter studies on Dask, :mod:`.viz`
draws, :mod:`.cli` is the command line.  Every public name is available flat
from the package.

A scikit-fem mesh goes in and comes out: :meth:`Particles.from_mesh` puts a
particle on every node of a ``MeshTri``/``MeshTet``, the same mesh is the mesh
source of :func:`advance`, and :meth:`Step.to_skfem` returns the step's mesh
with the particle fields as P1 degrees of freedom.  ``__all__`` groups the
names by what a user does (the API reference follows it).
"""

from __future__ import annotations

from ._version import __version__
from .boundary import (
    BodyOfRevolution,
    Contacts,
    RigidBody,
    RigidPlane,
    RigidWall,
    floor,
    wall_x,
)
from .errors import (
    CheckpointError,
    NpfemError,
    ParameterError,
    RunInterrupted,
    SolverError,
)
from .io import ResultWriter, read_pvd, read_step
from .limit import (
    LimitResult,
    SafetyResult,
    limit_analysis,
    reduced_strength,
    strength_reduction,
)
from .loads import surface_load
from .materials import (
    DruckerPrager,
    LinearElastic,
    Material,
    MohrCoulomb,
    Tresca,
    VonMises,
    compliance_matrix,
)
from .mesh.axisymmetric import (
    AxisymmetricIntegration,
    AxisymmetricMohrCoulomb,
    axisymmetric_integration,
)
from .mesh.delaunay import Triangulation, alpha_shape
from .mesh.smoothing import NodalIntegration, nodal_integration, p1_gradients
from .mesh.sources import AlphaShapeMesher, FixedMesh, main_body
from .metrics import stress_roughness
from .particles import Particles
from .run.refining import Refiner
from .run.rest import AtRest
from .run.simulation import Simulation
from .scenes import SCENES, get_scene, run_scene
from .step.conic import ConeSolution, solve_step
from .step.model import Model
from .step.program import ConeInput
from .step.records import Step, StepRecord, StepState, skfem_fields
from .step.solver import SolverOptions
from .step.stages import advance
from .sweeps import sweep
from .water import Water, WaterTable

#: Run a scene.
__all__ = [
    "SCENES",
    "AtRest",
    "Refiner",
    "Simulation",
    "__version__",
    "get_scene",
    "run_scene",
]
#: Output: the VTU series of a run (``Simulation(..., writer=ResultWriter(dir))``).
__all__ += ["ResultWriter"]
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
__all__ += [
    "BodyOfRevolution",
    "Contacts",
    "RigidBody",
    "RigidPlane",
    "RigidWall",
    "floor",
    "surface_load",
    "wall_x",
]
#: Water: pore pressure and effective stress.
__all__ += ["Water", "WaterTable"]
#: One step.
__all__ += [
    "ConeInput",
    "ConeSolution",
    "Model",
    "SolverOptions",
    "Step",
    "StepRecord",
    "StepState",
    "advance",
    "solve_step",
]
#: Limit analysis: collapse multipliers and factors of safety in one program.
__all__ += [
    "LimitResult",
    "SafetyResult",
    "limit_analysis",
    "reduced_strength",
    "strength_reduction",
]
#: Sweeps.
__all__ += ["sweep"]
#: Post-processing.
__all__ += ["read_pvd", "read_step", "skfem_fields", "stress_roughness"]
#: Errors.
__all__ += [
    "CheckpointError",
    "NpfemError",
    "ParameterError",
    "RunInterrupted",
    "SolverError",
]
