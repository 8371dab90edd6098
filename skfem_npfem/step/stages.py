"""One step: particles in, particles out.

:func:`advance` runs the data flow of one N-PFEM step in three stages:

1. :func:`build_operators` -- the mesh of this step (from the mesh source), the
   nodal integration on it (:mod:`skfem_npfem.mesh.smoothing`; axisymmetric models:
   :mod:`skfem_npfem.mesh.axisymmetric`), the contacts of the model's
   boundaries, walls and rigid bodies (:mod:`skfem_npfem.boundary`), and the
   :class:`~skfem_npfem.step.program.ConeInput`;
2. :func:`~skfem_npfem.step.conic.solve_step` -- the cone program;
3. :func:`update_particles` -- *new* particles from the solution (stress
   rotation, plastic strain, velocities, ballistic particles, put back from
   walls and bodies).

The mesh is then forgotten: nothing is mapped between meshes.  The step's
arrays (solution, mesh, operator) travel in a :class:`Step` that the
caller uses and drops; only the scalar :class:`StepRecord` is kept for the run.

The step's types, from the inside out:
:class:`~skfem_npfem.step.program.ConeInput` (the cone program's input) ->
:class:`~skfem_npfem.step.conic.ConeSolution` (the solver's raw solution) ->
:class:`Step` (what :func:`advance` returns: mesh, fields, solution) ->
:class:`StepRecord` (its scalars, kept in the run's history).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from time import perf_counter
from typing import Any

import numpy as np
from skfem import Mesh

from .._deprecated import renamed
from ..boundary import Boundary, ContactNodes, Contacts
from ..boundary.protocol import (
    put_back,
    record,
    step_contacts,
    with_columns,
    without_spanned,
)
from ..errors import ParameterError
from ..mesh.axisymmetric import axisymmetric_integration
from ..mesh.delaunay import p1_mesh
from ..mesh.smoothing import NodalIntegration, nodal_integration
from ..mesh.sources import MeshSource, as_mesh_source
from ..particles import Particles
from .conic import ConeSolution, solve_step
from .kinematics import equivalent_strain, rotate_stress
from .model import Model
from .program import ConeInput
from .records import Step, StepRecord, StepState, skfem_fields
from .volume import volume_eigenstrain, volume_strains

__all__ = [
    "Step",
    "StepOperators",
    "StepRecord",
    "StepState",
    "advance",
    "build_operators",
    "move_particles",
    "skfem_fields",
    "strain_operator",
    "update_particles",
]


@dataclass
class StepOperators:
    """What :func:`build_operators` makes of the particles for one step.

    Attributes
    ----------
    active : ndarray (N_a,) int
        Particles in the mesh (the mesh nodes).
    local_t : ndarray (d+1, ne) int
        Connectivity in node numbers ``0 .. N_a-1``.
    operator : NodalIntegration
        Smoothing cells of the mesh.
    wall_ids : ndarray (nc,) int
        Wall or body (lagged-force column) of each contact candidate of
        ``data.contacts``.
    data : ConeInput
        The cone step's input.
    volume_strains : ndarray (n_materials,) or None
        Volumetric eigenstrain of the volume correction per material
        (:func:`~skfem_npfem.step.volume.volume_strains`; None when it is off).
    time : float
        Time at the start of the step, s (where the model's bodies are).
    dropped : int
        Elements of the mesh source's mesh dropped because they span a body.

    Notes
    -----
    With rigid bodies, :attr:`wall_ids` numbers the bodies after the walls
    (``len(model.walls) + k`` for body ``k``): the columns of
    :attr:`Particles.wall_force`.
    """

    active: np.ndarray
    local_t: np.ndarray
    operator: NodalIntegration
    wall_ids: np.ndarray
    data: ConeInput
    volume_strains: np.ndarray | None = None
    time: float = 0.0
    dropped: int = 0

    @property
    def contacts(self) -> Contacts:
        """Contact candidates (node indices local to :attr:`active`)."""
        return self.data.contacts


def build_operators(
    p: Particles,
    model: Model,
    dt: float,
    mesh_source: MeshSource,
    start: StepState | None = None,
    boundaries: Sequence[Boundary] | None = None,
) -> StepOperators:
    """Stage 1: the mesh, smoothing cells, contacts and cone-step data of a step.

    ``start`` is the state at the start of the step (its time: where the
    model's rigid bodies are; the volume correction's filter state);
    ``boundaries`` those of the model (default ``model.boundaries``): the
    elements they span are dropped and their contact rows join the program.
    """
    start = StepState() if start is None else start
    boundaries = model.boundaries if boundaries is None else boundaries
    active, local_t = mesh_source(p.x)
    active, local_t, dropped = without_spanned(
        boundaries, p.x, active, local_t, start.time
    )
    mesh = p1_mesh(p.x[active], local_t)
    op, h = strain_operator(mesh, model)
    mass = model.node_masses(p.mass[active], p.material[active], op.volumes)
    strains = volume_strains(
        model.volume_correction,
        p.mass[active],
        p.material[active],
        op.volumes,
        np.array([m.rho for m in model.materials], float),
        start.volume_strain,
    )
    nodes = ContactNodes.of_particles(p, active, local_t)
    contacts, wall_ids = step_contacts(boundaries, nodes, dt, h, start.time)
    data = ConeInput(
        operator=op,
        materials=model.materials,
        material=p.material[active],
        sigma_n=p.stress[active],
        force=model.external_force(p.x.shape[0], active, mass),
        fixed=p.fixed[active],
        du_prescribed=p.v_prescribed[active] * dt,
        contacts=contacts,
        dt=dt,
        mass=mass,
        v_n=p.v[active],
        theta1=model.theta1,
        theta2=model.theta2,
        dynamic=model.mode == "dynamic",
        stress_scale=model.stress_scale,
        stabilisation=model.stabilisation,
        stabilisation_mode=model.stabilisation_mode,
        a_n=p.a[active],
        eigenstrain=volume_eigenstrain(
            strains,
            p.material[active],
            p.stress.shape[1],
            (0, 1, 2) if model.dim == 3 or model.axisymmetric else (0, 1),
        ),
    )
    return StepOperators(
        active, local_t, op, wall_ids, data, strains, float(start.time), dropped
    )


def strain_operator(mesh, model: Model) -> tuple[NodalIntegration, float]:
    """The step's strain operator on ``mesh`` and the particle spacing ``h``.

    Plane strain and 3D: :func:`~skfem_npfem.mesh.smoothing.nodal_integration`.
    Axisymmetric models (``model.axisymmetric``) get the ``2 pi r``-weighted
    cells with the hoop strain (:mod:`skfem_npfem.mesh.axisymmetric`); their spacing
    comes from the planar cell areas, not from the (m^3) ring volumes.
    """
    if model.axisymmetric:
        op = axisymmetric_integration(mesh, model.components)
        return op, op.length_scale
    op = nodal_integration(mesh, model.components)
    return op, float(np.mean(op.volumes)) ** (1.0 / model.dim)


def update_particles(
    p: Particles,
    model: Model,
    dt: float,
    ops: StepOperators,
    sol: ConeSolution,
    boundaries: Sequence[Boundary] | None = None,
) -> tuple[Particles, list[Any]]:
    """Stage 3: new particles from the solution of the step.

    Active particles take the increment, the (rotated) stress and the plastic
    strain of the solution; particles outside every element (free flight) carry
    no stress; all move as in :func:`move_particles`, which puts back those
    that crossed a boundary (default ``model.boundaries``).  Returns the new
    particles and each boundary's mark
    (:func:`~skfem_npfem.boundary.protocol.put_back`).
    """
    boundaries = model.boundaries if boundaries is None else boundaries
    active = ops.active
    stress = p.stress.copy()
    sig = sol.sigma
    if model.objective_rotation:
        sig = rotate_stress(sig, ops.operator.gradient(sol.du))
    stress[active] = sig
    # A particle outside every element is a grain in free flight: it carries no
    # stress (a stale one would come back into the body when it lands).
    inactive = np.ones(p.n, bool)
    inactive[active] = False
    stress[inactive] = 0.0
    eps_p = p.eps_p.copy()
    eps_p[active] += equivalent_strain(sol.deps_p)
    wall_force = np.zeros_like(p.wall_force)
    if ops.contacts.size:
        nodes, w, _ = ops.contacts.weights()
        np.add.at(
            wall_force,
            (active[nodes], ops.wall_ids[:, None]),
            w * sol.lambda_n[:, None],
        )
    motion, marks = move_particles(
        p, model, dt, active, sol.du, ops.data.dynamic, boundaries, ops.time + dt
    )
    new = p.replace(**motion, stress=stress, eps_p=eps_p, wall_force=wall_force)
    return new, marks


def move_particles(
    p: Particles,
    model: Model,
    dt: float,
    active: np.ndarray,
    du_active: np.ndarray,
    dynamic: bool,
    boundaries: Sequence[Boundary],
    t_end: float,
) -> tuple[dict[str, np.ndarray], list[Any]]:
    """Positions, velocities, accelerations and displacements after a step.

    Active particles take the increments ``du_active`` of the step's solution
    (theta-scheme velocities and accelerations in dynamic steps); the others
    move ballistically under gravity (docs/theory.md, "Nodal integration",
    inactive particles); particles that crossed one of ``boundaries`` (behind
    a wall, inside a body at ``t_end``) are put back on it
    (:func:`~skfem_npfem.boundary.protocol.put_back`).  Shared by every method
    that moves the particles with the nodal increments of an implicit step
    (N-PFEM, FEM-remap).

    Returns
    -------
    dict
        ``x``, ``v``, ``a``, ``u`` of the new particles.
    list
        Each boundary's mark (a body group's penetration depths); None each
        when the geometry is not updated.
    """
    g = model.gravity_vector
    du = np.zeros_like(p.x)
    du[active] = du_active
    th1, th2 = model.theta1, model.theta2
    inactive = np.ones(p.n, bool)
    inactive[active] = False
    if np.any(inactive):
        du[inactive] = dt * p.v[inactive] + th2 * dt**2 * g
    if dynamic:
        v = p.v + (du - dt * p.v) / (th2 * dt)
        a = ((v - p.v) / dt - (1 - th1) * p.a) / th1
    else:
        v = du / dt
        a = np.zeros_like(p.a)
    if np.any(inactive):
        v[inactive] = p.v[inactive] + dt * g
        a[inactive] = g
    if not model.update_geometry:
        return {"x": p.x, "v": v, "a": a, "u": p.u + du}, [None] * len(boundaries)
    # Accumulate du itself (x - p.x would lose increments below ~1e-16 |x|);
    # only the projections go through the positions.
    x, v, u, marks = put_back(boundaries, p.x + du, v, p.u + du, inactive, t_end)
    return {"x": x, "v": v, "a": a, "u": u}, marks


def advance(
    p: Particles,
    model: Model,
    dt: float,
    mesh_source: MeshSource | Mesh | np.ndarray,
    step: int | None = None,
    start: StepState | None = None,
) -> tuple[Particles, Step]:
    """Advance the particles by one step.

    Parameters
    ----------
    p : Particles
        State at the start of the step.
    model : Model
        Materials, loads, walls and solver settings.
    dt : float
        Time step, s (pseudo-time in static mode).
    mesh_source : callable, skfem.Mesh or ndarray (d+1, ne)
        ``x -> (active_index, local_t)`` (for example
        :class:`~skfem_npfem.mesh.sources.FixedMesh` or
        :class:`~skfem_npfem.mesh.sources.AlphaShapeMesher`); a scikit-fem
        ``MeshTri``/``MeshTet`` whose nodes are the particles (as made by
        :meth:`~skfem_npfem.Particles.from_mesh`), or its connectivity, is
        ``FixedMesh(mesh)``.
    step : int, optional
        Step index (used in error messages).
    start : StepState, optional
        The state at the start of the step besides the particles: the time
        (where the model's rigid bodies are) and the volume correction's
        filter state; the previous step's ``step.state``.  None: time 0, no
        filter state (the start of a run).  :class:`~skfem_npfem.Simulation`
        passes it.

    Returns
    -------
    Particles, Step
        New particles, and the step (its :class:`StepRecord` as ``.record``,
        the solution and the mesh, the state at its end as ``.state`` for the
        next step's ``start``; ``step.to_skfem()`` gives the mesh and the
        fields for scikit-fem).  With the volume correction on, the
        record's ``extra["volume_correction_strain"]`` holds this step's
        volumetric eigenstrain per material (as ``step.state.volume_strain``).
        With rigid bodies it holds, per
        body ``<name>``: ``<name>_x``, ``<name>_y`` (displacement of the body
        at the end of the step, m), ``<name>_force_x``, ``<name>_force_y``
        (force of the soil on the body, N per m in plane strain, N of the
        ring in axisymmetry, where ``force_x`` is 0), ``<name>_moment``
        (N m per m, about its reference point; 0 in axisymmetry) and
        ``<name>_penetration`` (the deepest a particle got inside it before
        being put back on its outline, m); and ``dropped_elements``.  A 3D
        body (:class:`~skfem_npfem.RigidPlane`,
        :class:`~skfem_npfem.BodyOfRevolution`) has ``<name>_x``, ``_y``,
        ``_z``, ``<name>_force_x``, ``_y``, ``_z`` (N, on the modelled part:
        a quarter domain carries a quarter of the load), ``<name>_moment_x``,
        ``_y``, ``_z`` (N m) and ``<name>_penetration``.

    Raises
    ------
    SolverError
        If the cone program fails; ``p`` is untouched.
    ParameterError
        For a bad ``dt``, particles of another dimension than the model, or a
        mesh source that is none of the above.

    Examples
    --------
    A soil column under gravity, two quasi-static steps on a scikit-fem mesh:

    >>> import numpy as np
    >>> from skfem import MeshTri
    >>> import skfem_npfem as npfem
    >>> soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=2000.0)
    >>> mesh = MeshTri.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 2, 5))
    >>> p = npfem.Particles.from_mesh(mesh, soil, fixed=mesh.p[1] == 0.0)
    >>> model = npfem.Model(dim=2, materials=[soil], mode="static")
    >>> p, step = npfem.advance(p, model, dt=1.0, mesh_source=mesh)
    >>> step.record.status, step.record.n_active
    ('Solved', 15)
    >>> p, step = npfem.advance(p, model, 1.0, mesh, start=step.state)
    >>> step.state.time
    2.0
    """
    if not (math.isfinite(dt) and dt > 0):
        raise ParameterError("dt", dt, "a finite time step > 0 (s)")
    if p.dim != model.dim:
        raise ParameterError(
            "particles",
            f"{p.dim}D positions",
            f"{model.dim}D positions for a {model.dim}D model",
        )
    mesh_source = as_mesh_source(mesh_source)
    start = StepState() if start is None else start
    boundaries = model.boundaries
    p = with_columns(boundaries, p)
    t0 = perf_counter()
    ops = build_operators(p, model, dt, mesh_source, start, boundaries)
    t1 = perf_counter()
    sol = solve_step(ops.data, model.solver, step=step)
    t2 = perf_counter()
    new, marks = update_particles(p, model, dt, ops, sol, boundaries)
    timings = {"mesh": t1 - t0, **sol.timings, "update": perf_counter() - t2}
    rec = StepRecord.of_step(
        step, dt, new, model.gravity, ops.active, ops.operator, sol, timings
    )
    rec.n_contacts = ops.contacts.size
    if ops.volume_strains is not None:
        rec.extra["volume_correction_strain"] = [float(x) for x in ops.volume_strains]
    record(
        boundaries,
        rec.extra,
        ops.contacts,
        ops.wall_ids,
        (sol.lambda_n, sol.lambda_t),
        p.x[ops.active],
        ops.time + dt,
        marks,
        ops.dropped,
    )
    end = start.after(dt, ops.volume_strains)
    return new, Step(rec, sol, ops.active, ops.local_t, ops.operator, new, end)


def __getattr__(name: str) -> object:
    """Old names (``StepResult``), with a ``DeprecationWarning``."""
    return renamed(__name__, name, {"StepResult": Step})
