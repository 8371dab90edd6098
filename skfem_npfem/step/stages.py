"""One step: particles in, particles out.

:func:`advance` runs the data flow of one N-PFEM step in three stages:

1. :func:`build_operators` -- the mesh of this step (from the mesh source), the
   nodal integration on it (:mod:`skfem_npfem.mesh.smoothing`; axisymmetric models:
   :mod:`skfem_npfem.mesh.axisymmetric`), the wall contacts
   (:mod:`skfem_npfem.boundary`) and the :class:`~skfem_npfem.step.program.ConeInput`;
2. :func:`~skfem_npfem.step.conic.solve_step` -- the cone program;
3. :func:`update_particles` -- *new* particles from the solution (stress
   rotation, plastic strain, velocities, ballistic particles, walls).

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
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from skfem import Mesh, MeshTet, MeshTri

from .._deprecated import renamed
from ..boundary import Contacts, project_to_walls, wall_contacts
from ..errors import ParameterError
from ..mesh.axisymmetric import axisymmetric_integration
from ..mesh.delaunay import p1_mesh
from ..mesh.smoothing import FULL_VOIGT, NodalIntegration, nodal_integration
from ..mesh.sources import MeshSource, as_mesh_source
from ..particles import Particles
from .conic import ConeSolution, solve_step
from .kinematics import energies, equivalent_strain, rotate_stress
from .model import Model
from .program import ConeInput, StrainOperator
from .volume import volume_eigenstrain, volume_strains

__all__ = [
    "Step",
    "StepOperators",
    "StepRecord",
    "advance",
    "build_operators",
    "move_particles",
    "skfem_fields",
    "strain_operator",
    "update_particles",
]


@dataclass
class StepRecord:
    """The record of one step kept in a run's history: scalars only.

    :attr:`Step.record` of each step; ``Simulation.records`` and the JSON
    summary's ``history`` hold one per step.

    Attributes
    ----------
    step : int
        Index of the step (1 for the first).
    time : float
        Time at the end of the step, s.
    dt : float
        Time step used, s (after any halving).
    status : str
        Clarabel's status (``"Solved"``, ``"AlmostSolved"``; explicit methods
        report their own).
    iterations : int
        Interior-point iterations (0 for an elastic program: one KKT solve).
    timings : dict of str to float
        Wall time per phase, s: ``mesh``, ``assembly``, ``setup``, ``solve``,
        ``update``, ``output``.
    n_active : int
        Particles in the step's mesh.
    n_inactive : int
        Particles outside it (moved ballistically).
    mesh_volume : float
        Area (2D, m^2 per m) or volume (3D, m^3) of the step's mesh.
    n_contacts : int
        Contact candidates of the step.
    retries : int
        Times the step was halved and repeated after a solver failure.
    """

    step: int
    time: float
    dt: float
    status: str
    iterations: int
    timings: dict[str, float]
    n_active: int
    n_inactive: int
    mesh_volume: float
    n_contacts: int
    retries: int = 0
    #: Sum of the particle masses, kg (exactly conserved).
    mass: float = float("nan")
    #: ``1/2 sum m |v|^2`` at the end of the step, J.
    kinetic_energy: float = float("nan")
    #: ``sum m g x_d`` at the end of the step (zero at ``x_d = 0``), J.
    potential_energy: float = float("nan")
    #: ``mesh_volume / (mesh volume of the first step) - 1``.
    volume_change: float = float("nan")
    #: Clarabel's linear solver of the step (``""`` if unknown).
    linear_solver: str = ""
    #: Scene diagnostics (numbers) added by callbacks, e.g. ``runout``, and
    #: ``volume_correction_strain`` (a list, one number per material) when the
    #: volume correction is on.
    extra: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def of_step(
        cls,
        step: int | None,
        dt: float,
        new: Particles,
        gravity: float,
        active: np.ndarray,
        operator: StrainOperator,
        sol: ConeSolution,
        timings: dict[str, float],
        **extra: Any,
    ) -> StepRecord:
        """The record of a finished step of any method.

        Solver status, mesh size and volume, contacts (``sol.lambda_n``) and
        the energies of the new particles; ``extra`` goes to :attr:`extra`,
        ``time`` is set by the time loop.
        """
        return cls(
            step=-1 if step is None else step,
            time=float("nan"),
            dt=dt,
            status=sol.status,
            iterations=sol.iterations,
            timings=timings,
            n_active=int(active.size),
            n_inactive=int(new.n - active.size),
            mesh_volume=float(operator.volumes.sum()),
            n_contacts=int(sol.lambda_n.size),
            linear_solver=str(sol.sizes.get("linear_solver", "")),
            extra=dict(extra),
            **energies(new, gravity),
        )

    def as_dict(self) -> dict[str, Any]:
        """Plain dict of the diagnostics (for JSON); ``extra`` is merged in."""
        out = {k: v for k, v in vars(self).items() if k != "extra"}
        out.update({k: v for k, v in self.extra.items() if k not in out})
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> StepRecord:
        """Inverse of :meth:`as_dict` (unknown keys go to ``extra``)."""
        names = {f.name for f in fields(cls)} - {"extra"}
        known = {k: v for k, v in d.items() if k in names}
        known["extra"] = {k: v for k, v in d.items() if k not in names}
        return cls(**known)


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
        Wall of each contact candidate of ``data.contacts``.
    data : ConeInput
        The cone step's input.
    volume_strains : ndarray (n_materials,) or None
        Volumetric eigenstrain of the volume correction per material
        (:func:`~skfem_npfem.step.volume.volume_strains`; None when it is off).
    """

    active: np.ndarray
    local_t: np.ndarray
    operator: NodalIntegration
    wall_ids: np.ndarray
    data: ConeInput
    volume_strains: np.ndarray | None = None

    @property
    def contacts(self) -> Contacts:
        """Contact candidates (node indices local to :attr:`active`)."""
        return self.data.contacts


@dataclass
class Step:
    """One finished step: its mesh, its fields, the cone solution and its record.

    :func:`advance` returns it beside the new particles; a
    :class:`~skfem_npfem.Simulation` hands it to the callbacks and the writer
    and keeps only :attr:`record`.  :meth:`to_skfem` gives the step's mesh as
    a scikit-fem mesh with the particle fields as P1 degrees of freedom.
    Formerly ``StepResult`` (that name still works, with a deprecation
    warning).

    Attributes
    ----------
    record : StepRecord
        The scalar diagnostics (kept by :class:`~skfem_npfem.Simulation`).
    solution : ConeSolution
        The cone solution on the active particles (``du``, ``sigma``,
        ``reaction``, contact forces, sizes).
    active : ndarray (N_a,) int
        Particles of the step's mesh: node ``i`` is particle ``active[i]``.
    local_t : ndarray (d+1, ne) int
        Its connectivity in positions of ``active``.
    operator : StrainOperator
        Its strain operator (N-PFEM: the smoothing cells; FEM-remap: the
        Gauss points of its elements).
    particles : Particles or None
        The particles at the end of the step (the first value :func:`advance`
        returns); needed by :attr:`mesh` and :meth:`to_skfem`.
    """

    record: StepRecord
    solution: ConeSolution
    active: np.ndarray
    local_t: np.ndarray
    operator: StrainOperator
    particles: Particles | None = None

    @property
    def cells(self) -> np.ndarray:
        """Global connectivity (ne, d+1) of the step's mesh."""
        return self.active[self.local_t].T

    @property
    def mesh(self) -> MeshTri | MeshTet:
        """The step's mesh as a scikit-fem ``MeshTri``/``MeshTet``.

        Its nodes are the active particles at their end-of-step positions
        (node ``i`` is particle ``active[i]``; particles outside the mesh are
        not in it), its elements those the step was solved on.
        """
        if self.particles is None:
            raise ParameterError(
                "step.particles",
                None,
                "the particles at the end of the step (advance sets them)",
            )
        return p1_mesh(self.particles.x[self.active], self.local_t)

    def to_skfem(self) -> tuple[MeshTri | MeshTet, dict[str, np.ndarray]]:
        """The step's mesh and the particle fields as scikit-fem P1 DOFs.

        Returns
        -------
        mesh : skfem.MeshTri or skfem.MeshTet
            :attr:`mesh`.
        fields : dict of str to ndarray
            End-of-step particle values on the mesh nodes, ready for
            ``Basis(mesh, ElementTriP1()).interpolate(fields[name])``
            (:func:`skfem_fields` lists them): ``stress_xx``, ``stress_yy``,
            ... (Pa, tension positive), ``plastic_strain_eq``,
            ``displacement_x``, ... (m), ``velocity_x``, ... (m/s), each of
            shape (N_a,); ``displacement`` and ``velocity`` of shape
            (d N_a,) for ``ElementVector(ElementTriP1())``.

        Examples
        --------
        The integral of the vertical stress over a soil column of height
        ``H = 2`` and width ``W = 1`` (exact: ``-rho g H^2 W / 2``):

        >>> import numpy as np
        >>> from skfem import Basis, ElementTriP1, Functional, MeshTri
        >>> import skfem_npfem as npfem
        >>> soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=2000.0)
        >>> column = MeshTri.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 2, 5))
        >>> x = column.p.T
        >>> fixed = np.zeros(x.shape, bool)
        >>> fixed[x[:, 1] == 0.0] = True  # fixed base
        >>> fixed[(x[:, 0] == 0.0) | (x[:, 0] == 1.0), 0] = True  # smooth sides
        >>> p = npfem.Particles.from_mesh(column, soil, fixed=fixed)
        >>> model = npfem.Model(dim=2, materials=[soil], mode="static")
        >>> p, step = npfem.advance(p, model, dt=1.0, mesh_source=column)
        >>> mesh, fields = step.to_skfem()
        >>> basis = Basis(mesh, ElementTriP1())
        >>> integral = Functional(lambda w: w["s"])
        >>> s = integral.assemble(basis, s=basis.interpolate(fields["stress_yy"]))
        >>> round(float(s) / (-2000.0 * 9.81 * 2.0**2 * 1.0 / 2), 3)
        0.998
        """
        mesh = self.mesh  # refuses a step without its particles
        return mesh, skfem_fields(self.particles, self.active)


def skfem_fields(particles: Particles, nodes: np.ndarray) -> dict[str, np.ndarray]:
    """Particle fields as scikit-fem P1 DOF arrays on a mesh of ``nodes``.

    Node ``i`` of the mesh is particle ``nodes[i]``, so the P1 DOF ``i`` of a
    scalar field is that particle's value; a vector field is node-major
    (``u_0x, u_0y, u_1x, ...``), the DOF order of
    ``ElementVector(ElementTriP1())``.

    Parameters
    ----------
    particles : Particles
        The particles (positions are not used).
    nodes : ndarray (N_a,) int
        The particles that are the mesh's nodes, in node order.

    Returns
    -------
    dict of str to ndarray
        ``stress_<c>`` for each full-Voigt component ``c`` (``xx, yy, zz,
        xy`` in 2D; also ``yz, zx`` in 3D), ``plastic_strain_eq``,
        ``displacement_<k>`` and ``velocity_<k>`` for ``k`` in ``x, y(, z)``,
        all (N_a,); ``displacement`` and ``velocity`` (d N_a,).

    Examples
    --------
    >>> import skfem_npfem as npfem
    >>> p = npfem.Particles.create([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], 1.0)
    >>> sorted(skfem_fields(p, np.array([2, 0, 1])))[:4]
    ['displacement', 'displacement_x', 'displacement_y', 'plastic_strain_eq']
    """
    nodes = np.asarray(nodes, dtype=np.int64)
    d = particles.dim
    out = {
        f"stress_{c}": particles.stress[nodes, k].copy()
        for k, c in enumerate(FULL_VOIGT[d])
    }
    out["plastic_strain_eq"] = particles.eps_p[nodes].copy()
    for name, arr in (("displacement", particles.u), ("velocity", particles.v)):
        vec = arr[nodes]
        out.update({f"{name}_{'xyz'[k]}": vec[:, k].copy() for k in range(d)})
        out[name] = vec.reshape(-1).copy()
    return out


def build_operators(
    p: Particles,
    model: Model,
    dt: float,
    mesh_source: MeshSource,
    volume_state: Sequence[float] | None = None,
) -> StepOperators:
    """Stage 1: the mesh, smoothing cells, contacts and cone-step data of a step.

    ``volume_state`` is the previous step's ``volume_correction_strain`` (the
    volume correction's filter state, one number per material).
    """
    active, local_t = mesh_source(p.x)
    mesh = p1_mesh(p.x[active], local_t)
    op, h = strain_operator(mesh, model)
    mass = model.node_masses(p.mass[active], p.material[active], op.volumes)
    strains = volume_strains(
        model.volume_correction,
        p.mass[active],
        p.material[active],
        op.volumes,
        np.array([m.rho for m in model.materials], float),
        volume_state,
    )
    contacts, wall_ids = wall_contacts(model.walls, p, active, dt, h, model.gravity)
    data = ConeInput(
        operator=op,
        materials=model.materials,
        material=p.material[active],
        sigma_n=p.stress[active],
        force=mass[:, None] * model.gravity_vector[None, :],
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
    return StepOperators(active, local_t, op, wall_ids, data, strains)


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
    p: Particles, model: Model, dt: float, ops: StepOperators, sol: ConeSolution
) -> Particles:
    """Stage 3: new particles from the solution of the step.

    Active particles take the increment, the (rotated) stress and the plastic
    strain of the solution; particles outside every element (free flight) carry
    no stress; all move as in :func:`move_particles`.
    """
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
        wall_force[active[ops.contacts.node], ops.wall_ids] = sol.lambda_n
    motion = move_particles(p, model, dt, active, sol.du, ops.data.dynamic)
    return p.replace(**motion, stress=stress, eps_p=eps_p, wall_force=wall_force)


def move_particles(
    p: Particles,
    model: Model,
    dt: float,
    active: np.ndarray,
    du_active: np.ndarray,
    dynamic: bool,
) -> dict[str, np.ndarray]:
    """Positions, velocities, accelerations and displacements after a step.

    Active particles take the increments ``du_active`` of the step's solution
    (theta-scheme velocities and accelerations in dynamic steps); the others
    move ballistically under gravity (formulation.md §2); particles behind a
    wall are put back on it.  Shared by every method that moves the particles
    with the nodal increments of an implicit step (N-PFEM, FEM-remap).

    Returns
    -------
    dict
        ``x``, ``v``, ``a``, ``u`` of the new particles.
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
    if model.update_geometry:
        moved = p.x + du
        x, v = project_to_walls(model.walls, moved, v, friction=inactive)
        # Accumulate du itself (x - p.x would lose increments below ~1e-16 |x|);
        # only the wall projection goes through the positions.
        u = p.u + du + (x - moved)
    else:
        x, u = p.x, p.u + du
    return {"x": x, "v": v, "a": a, "u": u}


def advance(
    p: Particles,
    model: Model,
    dt: float,
    mesh_source: MeshSource | Mesh | np.ndarray,
    step: int | None = None,
    volume_state: Sequence[float] | None = None,
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
    volume_state : sequence of float, optional
        The previous step's ``record.extra["volume_correction_strain"]`` (the
        state of the volume correction's filter, one number per material);
        None at the start of a run.  Only read when
        ``model.volume_correction > 0``; :class:`~skfem_npfem.Simulation`
        passes it.

    Returns
    -------
    Particles, Step
        New particles, and the step (its :class:`StepRecord` as ``.record``,
        the solution and the mesh; ``step.to_skfem()`` gives the mesh and the
        fields for scikit-fem).  With the volume correction on, the
        record's ``extra["volume_correction_strain"]`` holds this step's
        volumetric eigenstrain per material.

    Raises
    ------
    SolverError
        If the cone program fails; ``p`` is untouched.
    ParameterError
        For a bad ``dt``, particles of another dimension than the model, or a
        mesh source that is none of the above.

    Examples
    --------
    A soil column under gravity, one quasi-static step on a scikit-fem mesh:

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
    t0 = time.perf_counter()
    ops = build_operators(p, model, dt, mesh_source, volume_state)
    t1 = time.perf_counter()
    sol = solve_step(ops.data, model.solver, step=step)
    t2 = time.perf_counter()
    new = update_particles(p, model, dt, ops, sol)
    timings = {"mesh": t1 - t0, **sol.timings, "update": time.perf_counter() - t2}
    rec = StepRecord.of_step(
        step, dt, new, model.gravity, ops.active, ops.operator, sol, timings
    )
    rec.n_contacts = ops.contacts.size
    if ops.volume_strains is not None:
        rec.extra["volume_correction_strain"] = [float(x) for x in ops.volume_strains]
    return new, Step(rec, sol, ops.active, ops.local_t, ops.operator, new)


def __getattr__(name: str) -> object:
    """Old names (``StepResult``), with a ``DeprecationWarning``."""
    return renamed(__name__, name, {"StepResult": Step})
