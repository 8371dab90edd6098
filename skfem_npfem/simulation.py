"""The (P)FEM time loop: particles in, particles out.

:func:`advance` performs one step: build a mesh from the particles (a fixed
connectivity or a fresh Delaunay/alpha-shape triangulation), assemble the nodal
integration on it, solve the cone program, and return *new* particles updated
from the solution.  The mesh is then forgotten: nothing is mapped between meshes.

:class:`Simulation` drives many steps: fixed or adaptive time step (halve and
retry when the solver fails, grow back after successes), an end time or a
stopping rule, callbacks, progress reporting, VTU output as steps finish, and
checkpoints to resume from.
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from skfem import MeshTet, MeshTri

from .axisymmetric import axisymmetric_integration
from .boundary import RigidWall
from .conic import Contacts, SolverOptions, StepData, solve_step
from .errors import NpfemError, ParameterError, SolverError
from .materials import Material
from .particles import Particles
from .smoothing import NodalIntegration, nodal_integration

__all__ = [
    "AtRest",
    "FixedMesh",
    "Model",
    "Simulation",
    "StepRecord",
    "advance",
    "energies",
    "project_to_walls",
    "rotate_stress",
]


@dataclass
class Model:
    """Physics and numerics shared by all steps of a run.

    Parameters
    ----------
    dim : int
        2 (plane strain) or 3.
    materials : list of Material
        Referenced by :attr:`Particles.material`.
    gravity : float
        Gravitational acceleration along ``-e_d``, m/s^2.
    mode : {"dynamic", "static"}
        Include inertia (theta1/theta2 scheme) or solve quasi-static steps.
    theta1, theta2 : float
        Time-integration parameters in [1/2, 1] (1, 1: backward Euler, the PFEM
        default; 1/2, 1/2: trapezoidal, energy conserving, elastic waves only).
    walls : list of RigidWall
        Rigid planes the particles may touch.
    objective_rotation : bool
        Rotate stresses with the smoothed spin (Hughes-Winget, exactly orthogonal).
    update_geometry : bool
        Move the particles by each increment (updated Lagrangian, large
        deformation).  False keeps the initial geometry (small-strain analysis, as
        in limit-load benchmarks); displacements still accumulate in ``u``.
    stress_scale : float or None
        Stress scale for non-dimensionalisation (None: automatic).
    solver : SolverOptions
        Clarabel settings.
    axisymmetric : bool
        2D only: the mesh is the ``(r, z)`` half-section of a body of revolution
        about ``x = 0`` (:mod:`skfem_npfem.axisymmetric`).  Stresses are
        ``(rr, zz, tt, rz)`` with the hoop component in the ``zz`` slot, the
        cells are weighted by ``2 pi r`` and particle masses must be the full-ring
        masses ``rho V_i`` of those cells.  Needs cones with ``sigma_tt`` as a
        variable (Drucker-Prager, von Mises); particles on the axis should have
        ``u_r`` fixed.
    """

    dim: int
    materials: list[Material]
    gravity: float = 9.81
    mode: str = "dynamic"
    theta1: float = 1.0
    theta2: float = 1.0
    walls: list[RigidWall] = field(default_factory=list)
    objective_rotation: bool = True
    update_geometry: bool = True
    stress_scale: float | None = None
    solver: SolverOptions = field(default_factory=SolverOptions)
    axisymmetric: bool = False

    def __post_init__(self) -> None:
        if self.dim not in (2, 3):
            raise ParameterError("dim", self.dim, "2 or 3")
        if not self.materials:
            raise ParameterError("materials", self.materials, "at least one material")
        for m in self.materials:
            m.check_dim(self.dim)
        if self.mode not in ("dynamic", "static"):
            raise ParameterError("mode", self.mode, "'dynamic' or 'static'")
        for name in ("theta1", "theta2"):
            val = getattr(self, name)
            if not (isinstance(val, int | float) and 0.5 <= val <= 1.0):
                raise ParameterError(name, val, "a number in [0.5, 1]")
        s = self.stress_scale
        if s is not None and not (
            isinstance(s, int | float) and math.isfinite(s) and s > 0
        ):
            raise ParameterError("stress_scale", s, "a stress > 0 (Pa) or None")
        g = self.gravity
        if not (isinstance(g, int | float) and math.isfinite(g) and g >= 0):
            raise ParameterError("gravity", g, "a finite number >= 0 (m/s^2)")
        for w in self.walls:
            if w.normal.size != self.dim:
                raise ParameterError("walls", w, f"walls must be {self.dim}D")
        if not isinstance(self.axisymmetric, bool):
            raise ParameterError("axisymmetric", self.axisymmetric, "True or False")
        if self.axisymmetric:  # axisymmetric N-PFEM (axisymmetric.py)
            self._check_axisymmetric()

    def _check_axisymmetric(self) -> None:
        """Axisymmetry is 2D, and every plastic cone must see sigma_tt."""
        if self.dim != 2:
            raise ParameterError(
                "axisymmetric", True, "only with dim=2 (the (r, z) half-section)"
            )
        for m in self.materials:
            if m.plastic and not m.needs_zz(2):
                raise ParameterError(
                    "materials",
                    type(m).__name__,
                    "a cone with the hoop stress as a variable in axisymmetry: "
                    "DruckerPrager or VonMises (plane-strain Mohr-Coulomb/Tresca "
                    "ignore sigma_tt)",
                )

    @property
    def components(self) -> tuple[int, ...]:
        """Full-Voigt components carried as cone variables."""
        if self.dim == 3:
            return (0, 1, 2, 3, 4, 5)
        if self.axisymmetric or any(m.needs_zz(2) for m in self.materials):
            return (0, 1, 2, 3)
        return (0, 1, 3)

    @property
    def gravity_vector(self) -> np.ndarray:
        """Gravity as a vector (along ``-e_d``)."""
        g = np.zeros(self.dim)
        g[-1] = -self.gravity
        return g


class MeshSource(Protocol):
    """Turns particle positions into a mesh for one step."""

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(active_index (N_a,), local_t (d+1, ne))`` for positions x."""
        ...


@dataclass
class FixedMesh:
    """Keep the initial connectivity (small-deformation problems, no remeshing).

    Parameters
    ----------
    t : ndarray (d+1, ne)
        Connectivity over all particles (every particle in an element).
    """

    t: np.ndarray

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=np.int64)
        self._active = np.unique(self.t)
        self._signs: np.ndarray | None = None

    def _check_orientation(self, x: np.ndarray) -> None:
        """Refuse a folded mesh: an element whose orientation has flipped."""
        d = x.shape[1]
        if self.t.shape[0] != d + 1:
            return
        v = x[self.t[1:]] - x[self.t[0]][None]  # (d, ne, d)
        signs = np.sign(np.linalg.det(np.moveaxis(v, 0, 1)))
        if self._signs is None:
            self._signs = signs
            return
        flipped = (signs * self._signs) < 0
        if np.any(flipped):
            e = int(np.flatnonzero(flipped)[0])
            raise NpfemError(
                f"{int(flipped.sum())} element(s) of the fixed mesh turned inside "
                f"out (first: element {e}); the deformation is too large for a "
                "fixed connectivity: reduce dt or use remeshing (AlphaShapeMesher)"
            )

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # noqa: D102
        n = x.shape[0]
        if self.t.size and (self.t.min() < 0 or self.t.max() >= n):
            raise ParameterError(
                "t",
                f"indices {int(self.t.min())}..{int(self.t.max())}",
                f"particle indices in 0..{n - 1}",
            )
        self._check_orientation(x)
        if self._active.size != x.shape[0]:
            local = np.searchsorted(self._active, self.t)
            return self._active, local
        return self._active, self.t


@dataclass
class StepRecord:
    """Diagnostics of one step (also written to the JSON summary)."""

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
    #: Scene diagnostics (numbers) added by callbacks, e.g. ``runout``.
    extra: dict[str, Any] = field(default_factory=dict)
    # Not serialised: the solution and mesh of the step (for scene metrics).
    solution: Any = field(default=None, repr=False, compare=False)
    active: Any = field(default=None, repr=False, compare=False)
    local_t: Any = field(default=None, repr=False, compare=False)

    def as_dict(self) -> dict[str, Any]:
        """Plain dict of the scalar diagnostics (for JSON); ``extra`` is merged in."""
        skip = ("solution", "active", "local_t", "extra")
        out = {k: v for k, v in vars(self).items() if k not in skip}
        out.update({k: v for k, v in self.extra.items() if k not in out})
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> StepRecord:
        """Inverse of :meth:`as_dict` (unknown keys go to ``extra``)."""
        names = {f.name for f in fields(cls)} - {"solution", "active", "local_t"}
        known = {k: v for k, v in d.items() if k in names}
        known["extra"] = {k: v for k, v in d.items() if k not in names}
        return cls(**known)


def rotate_stress(stress: np.ndarray, grad_du: np.ndarray) -> np.ndarray:
    """Rotate stresses by the exactly orthogonal Hughes-Winget (Cayley) rotation.

    ``R = (I - W/2)^-1 (I + W/2)`` with ``W = skew(grad du)``; ``s <- R s R^T``.
    Orthogonality keeps every invariant, so a stress inside a yield cone stays
    inside (a first-order Jaumann update does not).

    Parameters
    ----------
    stress : ndarray (N, n_full)
        Full Voigt stresses.
    grad_du : ndarray (N, d, d)
        Smoothed gradients of the displacement increment.

    Returns
    -------
    ndarray (N, n_full)
    """
    n, d, _ = grad_du.shape
    W = np.zeros((n, 3, 3))
    W[:, :d, :d] = 0.5 * (grad_du - np.swapaxes(grad_du, 1, 2))
    eye = np.eye(3)
    R = np.linalg.solve(eye - 0.5 * W, eye + 0.5 * W)
    S = voigt_to_tensor(stress)
    return tensor_to_voigt(R @ S @ np.swapaxes(R, 1, 2), stress.shape[1])


def voigt_to_tensor(s: np.ndarray) -> np.ndarray:
    """Full Voigt (N, 4|6) stresses to (N, 3, 3) tensors."""
    n = s.shape[0]
    T = np.zeros((n, 3, 3))
    T[:, 0, 0], T[:, 1, 1], T[:, 2, 2] = s[:, 0], s[:, 1], s[:, 2]
    T[:, 0, 1] = T[:, 1, 0] = s[:, 3]
    if s.shape[1] == 6:
        T[:, 1, 2] = T[:, 2, 1] = s[:, 4]
        T[:, 2, 0] = T[:, 0, 2] = s[:, 5]
    return T


def tensor_to_voigt(T: np.ndarray, size: int) -> np.ndarray:
    """(N, 3, 3) tensors to full Voigt vectors of length ``size`` (4 or 6)."""
    cols = [T[:, 0, 0], T[:, 1, 1], T[:, 2, 2], T[:, 0, 1]]
    if size == 6:
        cols += [T[:, 1, 2], T[:, 2, 0]]
    return np.stack(cols, axis=1)


def energies(p: Particles, model: Model) -> dict[str, float]:
    """Total mass (kg), kinetic and gravitational potential energy (J) of particles.

    The potential energy is ``sum m g x_d`` (zero at ``x_d = 0``; gravity acts
    along ``-e_d``).

    Examples
    --------
    >>> from skfem_npfem.materials import LinearElastic
    >>> p = Particles.create([[0.0, 2.0]], [3.0], v=[[1.0, 0.0]])
    >>> e = energies(p, Model(dim=2, materials=[LinearElastic(1e6, 0.3)], gravity=10))
    >>> e["mass"], e["kinetic_energy"], e["potential_energy"]
    (3.0, 1.5, 60.0)
    """
    m = p.mass
    return {
        "mass": float(m.sum()),
        "kinetic_energy": float(0.5 * np.sum(m * np.sum(p.v * p.v, axis=1))),
        "potential_energy": float(model.gravity * np.sum(m * p.x[:, -1])),
    }


def project_to_walls(
    walls: list[RigidWall],
    x: np.ndarray,
    v: np.ndarray,
    friction: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Put particles behind a wall back on it (:meth:`RigidWall.project`).

    For the particles flagged in ``friction`` (the ballistic ones, which have no
    contact rows) the wall also applies a Coulomb impulse: the tangential
    velocity shrinks by ``mu`` times the normal velocity the wall removed (an
    impact, or ``g dt`` per step while resting), never past zero.  Without it a
    grain that left the body would slide on a rough floor for ever.
    """
    for wall in walls:
        vn_old = v @ wall.normal
        x, v_new = wall.project(x, v)
        if friction is not None and wall.mu > 0 and v_new is not v:
            dvn = (v_new @ wall.normal - vn_old) * friction
            hit = np.flatnonzero(dvn > 0)
            if hit.size:
                vt = v_new[hit] - (v_new[hit] @ wall.normal)[:, None] * wall.normal
                speed = np.linalg.norm(vt, axis=1)
                keep = np.zeros_like(speed)
                moving = speed > 0
                keep[moving] = (
                    np.maximum(speed[moving] - wall.mu * dvn[hit][moving], 0.0)
                    / speed[moving]
                )
                v_new[hit] -= (1.0 - keep)[:, None] * vt
        v = v_new
    return x, v


def equivalent_strain(deps: np.ndarray) -> np.ndarray:
    """``sqrt(2/3 e:e)`` of full-Voigt strains (engineering shear)."""
    normal = deps[:, :3]
    dev = normal - normal.mean(axis=1, keepdims=True)
    shear = deps[:, 3:]
    return np.sqrt(
        2.0 / 3.0 * (np.sum(dev**2, axis=1) + 0.5 * np.sum(shear**2, axis=1))
    )


def _contacts(
    model: Model, p: Particles, active: np.ndarray, dt: float, h: float
) -> tuple[Contacts, np.ndarray, np.ndarray]:
    """Contact candidates of the active particles against every wall.

    A particle is a candidate when its gap is below ``h + 2|v| dt + g dt^2`` so
    that fast particles cannot tunnel through a wall within one step.  The gap
    handed to the cone program includes the normal part of any prescribed
    displacement increment of the particle (the program only sees the free dofs).
    The friction bound is ``mu`` times the particle's lagged normal force
    :attr:`Particles.wall_force` of the wall.
    """
    d = model.dim
    if p.wall_force.shape[1] < len(model.walls):
        raise ParameterError(
            "wall_force",
            p.wall_force.shape,
            f"one column per wall ({len(model.walls)}): create the particles with "
            "Particles.create(..., n_walls=len(model.walls))",
        )
    nodes, normals, gaps, bounds, wall_ids = [], [], [], [], []
    x, v = p.x[active], p.v[active]
    fixed = p.fixed[active]
    du_pres = np.where(fixed, p.v_prescribed[active] * dt, 0.0)
    reach = h + 2.0 * np.linalg.norm(v, axis=1) * dt + model.gravity * dt**2
    for w_id, wall in enumerate(model.walls):
        g = wall.gap(x)
        cand = np.flatnonzero(g < reach)
        # A particle whose dofs along the normal are all fixed needs no contact row.
        cand = cand[~np.all(fixed[cand][:, np.abs(wall.normal) > 0], axis=1)]
        nodes.append(cand)
        normals.append(np.broadcast_to(wall.normal, (cand.size, d)))
        gaps.append(np.maximum(g[cand], 0.0) + du_pres[cand] @ wall.normal)
        # Lagged normal force; values at the solver's noise level (a node that
        # was only a candidate, lambda_n ~ +-1e-8 of the load) give no friction
        # rather than a near-degenerate |lambda_t| <= tiny constraint.
        lam = p.wall_force[active[cand], w_id]
        noise = 1e-8 * np.max(np.abs(p.wall_force[:, w_id]), initial=0.0)
        bounds.append(np.where(lam > noise, wall.mu * lam, 0.0))
        wall_ids.append(np.full(cand.size, w_id))
    if not nodes:
        return Contacts.empty(d), np.zeros(0, int), np.zeros(0, int)
    c = Contacts(
        node=np.concatenate(nodes),
        normal=np.concatenate(normals),
        gap=np.concatenate(gaps),
        mu_lambda=np.concatenate(bounds),
    )
    return c, np.concatenate(wall_ids), c.node


def _integration(mesh, model: Model) -> tuple[NodalIntegration, float]:
    """Nodal-integration operators of one step's mesh and the particle spacing.

    Axisymmetric models get the ``2 pi r``-weighted operators with the hoop
    strain (:mod:`skfem_npfem.axisymmetric`); their spacing comes from the planar
    cell areas, not from the (m^3) ring volumes.
    """
    if model.axisymmetric:
        ni = axisymmetric_integration(mesh, model.components)
        return ni, ni.length_scale
    ni = nodal_integration(mesh, model.components)
    return ni, float(np.mean(ni.volumes)) ** (1.0 / model.dim)


def advance(
    p: Particles,
    model: Model,
    dt: float,
    mesh_source: MeshSource,
    step: int | None = None,
) -> tuple[Particles, StepRecord]:
    """Advance the particles by one step.

    Parameters
    ----------
    p : Particles
        State at the start of the step.
    model : Model
        Materials, loads, walls and solver settings.
    dt : float
        Time step, s (pseudo-time in static mode).
    mesh_source : callable
        ``x -> (active_index, local_t)`` (for example :class:`FixedMesh` or the
        alpha-shape remesher).
    step : int, optional
        Step index (used in error messages).

    Returns
    -------
    Particles, StepRecord
        New particles and the step diagnostics.

    Raises
    ------
    SolverError
        If the cone program fails; ``p`` is untouched.
    """
    if not (math.isfinite(dt) and dt > 0):
        raise ParameterError("dt", dt, "a finite time step > 0 (s)")
    d = model.dim
    if p.dim != d:
        raise ParameterError(
            "particles", f"{p.dim}D positions", f"{d}D positions for a {d}D model"
        )
    t0 = time.perf_counter()
    active, local_t = mesh_source(p.x)
    xa = p.x[active]
    pts, conn = np.ascontiguousarray(xa.T), np.ascontiguousarray(local_t)
    # sort_t=False: scikit-fem would otherwise reorder (and flip) triangles.
    mesh = MeshTri(pts, conn, sort_t=False) if d == 2 else MeshTet(pts, conn)
    ni, h = _integration(mesh, model)
    t_mesh = time.perf_counter() - t0
    mass = p.mass[active]
    g = model.gravity_vector
    force = mass[:, None] * g[None, :]
    contacts, wall_ids, c_nodes = _contacts(model, p, active, dt, h)
    dynamic = model.mode == "dynamic"
    fixed = p.fixed[active]
    data = StepData(
        ni=ni,
        materials=model.materials,
        material=p.material[active],
        sigma_n=p.stress[active],
        force=force,
        fixed=fixed,
        du_prescribed=p.v_prescribed[active] * dt,
        contacts=contacts,
        dt=dt,
        mass=mass,
        v_n=p.v[active],
        theta1=model.theta1,
        theta2=model.theta2,
        dynamic=dynamic,
        stress_scale=model.stress_scale,
    )
    sol = solve_step(data, model.solver, step=step)
    t1 = time.perf_counter()

    # ---- update the particles (active ones from the solution) ----
    du = np.zeros_like(p.x)
    du[active] = sol.du
    stress = p.stress.copy()
    sig = sol.sigma
    if model.objective_rotation:
        sig = rotate_stress(sig, ni.gradient(sol.du))
    stress[active] = sig
    eps_p = p.eps_p.copy()
    eps_p[active] += equivalent_strain(sol.deps_p)
    th1, th2 = model.theta1, model.theta2
    inactive = np.ones(p.n, bool)
    inactive[active] = False
    if np.any(inactive):
        # Ballistic motion under gravity (formulation.md §2).
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
    wall_force = np.zeros_like(p.wall_force)
    if contacts.size:
        wall_force[active[c_nodes], wall_ids] = sol.lambda_n
    new = p.replace(
        x=x,
        v=v,
        a=a,
        u=u,
        stress=stress,
        eps_p=eps_p,
        wall_force=wall_force,
    )
    timings = {"mesh": t_mesh, **sol.timings, "update": time.perf_counter() - t1}
    rec = StepRecord(
        step=-1 if step is None else step,
        time=float("nan"),
        dt=dt,
        status=sol.status,
        iterations=sol.iterations,
        timings=timings,
        n_active=int(active.size),
        n_inactive=int(p.n - active.size),
        mesh_volume=float(ni.volumes.sum()),
        n_contacts=contacts.size,
        **energies(new, model),
        solution=sol,
        active=active,
        local_t=local_t,
    )
    return new, rec


class Simulation:
    """Run many steps with output, checkpoints and adaptive time stepping.

    Parameters
    ----------
    particles : Particles
        Initial state.
    model : Model
        Physics and solver settings.
    mesh_source : callable
        See :func:`advance`.
    dt : float
        Initial (and maximum) time step, s.
    adaptive : bool
        On a solver failure halve ``dt`` and retry (down to ``dt_min``); grow it back
        by 2x after ``grow_after`` consecutive successes.
    dt_min : float or None
        Smallest step allowed (default ``dt / 64``).
    max_displacement : float or None
        Displacement-based step control: keep the largest particle displacement
        per step below ``max_displacement * h`` (h: the mean particle spacing of
        the step's mesh).  The step that exceeds it is kept and the next step is
        shortened to ``0.9 * dt * limit / max|du|`` (never below ``dt_min``); the
        step grows back (at most 2x per step, never above the initial ``dt``)
        while the displacement stays below the limit.  None: off.
    writer : ResultWriter or None
        Receives a VTU per output step.
    output_every : int
        Write every k-th step (the last step is always written).
    checkpoint_dir : path or None
        Folder for ``checkpoint_XXXXXX.npz`` files.
    checkpoint_every : int
        Steps between checkpoints.
    callbacks : list of callables
        ``f(sim, particles, record)`` after every step; return True to stop.
    progress : bool or None
        Progress line on stderr (None: only when stderr is a terminal).
    meta : dict
        Stored in checkpoints (scene name, parameters).
    """

    def __init__(
        self,
        particles: Particles,
        model: Model,
        mesh_source: MeshSource,
        dt: float,
        *,
        adaptive: bool = False,
        dt_min: float | None = None,
        grow_after: int = 4,
        max_displacement: float | None = None,
        writer: Any = None,
        output_every: int = 1,
        checkpoint_dir: str | Path | None = None,
        checkpoint_every: int = 0,
        callbacks: list[Callable[..., Any]] | None = None,
        progress: bool | None = None,
        meta: dict | None = None,
        extra_point_data: Callable[[Particles], dict[str, np.ndarray]] | None = None,
    ) -> None:
        if not (isinstance(dt, int | float) and math.isfinite(dt) and dt > 0):
            raise ParameterError("dt", dt, "a finite time step > 0 (s)")
        self.particles = particles
        self.model = model
        self.mesh_source = mesh_source
        self.dt_max = float(dt)
        self.dt = float(dt)
        self.adaptive = adaptive
        self.dt_min = float(dt_min) if dt_min is not None else dt / 64.0
        self.grow_after = grow_after
        if max_displacement is not None and not (
            isinstance(max_displacement, int | float)
            and math.isfinite(max_displacement)
            and max_displacement > 0
        ):
            raise ParameterError(
                "max_displacement", max_displacement, "a number > 0 (fraction of h)"
            )
        self.max_displacement = max_displacement
        self.writer = writer
        self.output_every = max(1, int(output_every))
        self.checkpoint_dir = Path(checkpoint_dir) if checkpoint_dir else None
        self.checkpoint_every = int(checkpoint_every)
        self.callbacks = list(callbacks or [])
        self.progress = sys.stderr.isatty() if progress is None else progress
        self.meta = dict(meta or {})
        self.extra_point_data = extra_point_data
        self.time = 0.0
        self.step = 0
        self.records: list[StepRecord] = []
        self._successes = 0
        self.last_record: StepRecord | None = None
        #: Mass and energies of the initial state (see :func:`energies`).
        self.initial = energies(particles, model)

    # -- output ---------------------------------------------------------------
    def point_data(self, p: Particles, active: np.ndarray | None) -> dict:
        """Point data written to the VTU files."""
        act = np.zeros(p.n, bool)
        if active is not None:
            act[active] = True
        data = {
            "displacement": p.u,
            "velocity": p.v,
            "stress": p.stress,
            "plastic_strain_eq": p.eps_p,
            "mass": p.mass,
            "active": act,
        }
        # Mesh sources that know the free surface (AlphaShapeMesher) report it
        # for the mesh the step was solved on.
        free = getattr(self.mesh_source, "free_surface", None)
        flags = free() if callable(free) else None
        if flags is not None:
            data["free_surface"] = flags
        if self.extra_point_data is not None:
            data.update(self.extra_point_data(p))
        return data

    def write_output(self, cells_global: np.ndarray | None, active) -> None:
        """Write the current particles as one VTU step."""
        if self.writer is None:
            return
        self.writer.write(
            self.step,
            self.time,
            self.particles.x,
            cells_global,
            self.point_data(self.particles, active),
        )

    def save_checkpoint(self) -> Path | None:
        """Write ``checkpoint_<step>.npz`` (see :mod:`skfem_npfem.io`)."""
        if self.checkpoint_dir is None:
            return None
        from .io import checkpoint_path, save_checkpoint

        self.checkpoint_dir.mkdir(parents=True, exist_ok=True)
        meta = {
            **self.meta,
            "step": self.step,
            "time": self.time,
            "dt": self.dt,
            "successes": self._successes,
            "initial": self.initial,
            "records": [_jsonable(r.as_dict()) for r in self.records],
        }
        return save_checkpoint(
            checkpoint_path(self.checkpoint_dir, self.step),
            self.particles.arrays(),
            meta,
        )

    def restore(self, path: str | Path) -> dict:
        """Continue from a checkpoint written by :meth:`save_checkpoint`.

        Restores the particles, step, time, the adaptive time-step state and the
        step records, so that the continued run repeats the uninterrupted one
        step for step.  Returns the checkpoint's metadata.
        """
        from .io import load_checkpoint

        arrays, meta = load_checkpoint(path)
        self.particles = Particles.from_arrays(arrays)
        self.step = int(meta["step"])
        self.time = float(meta["time"])
        self.dt = float(meta["dt"])
        self._successes = int(meta.get("successes", 0))
        self.initial = dict(meta.get("initial", self.initial))
        self.records = [StepRecord.from_dict(r) for r in meta.get("records", [])]
        self.last_record = self.records[-1] if self.records else None
        return meta

    # -- loop -----------------------------------------------------------------
    def run(
        self,
        *,
        steps: int | None = None,
        t_end: float | None = None,
        stop: Callable[[Simulation], bool] | None = None,
    ) -> list[StepRecord]:
        """Advance until a step count, an end time or a stop rule is reached.

        The run stops after ``steps`` more steps, at ``t_end``, or when
        ``stop(sim)`` returns True, whichever comes first.

        Returns
        -------
        list of StepRecord
            All records of the run so far.
        """
        if steps is None and t_end is None and stop is None:
            raise ParameterError("steps", None, "give steps, t_end or a stop rule")
        if self.step == 0 and self.writer is not None and not self.writer.entries:
            # The initial state, with the mesh the first step will be built on.
            active, local_t = self.mesh_source(self.particles.x)
            self.write_output(active[local_t].T, active)
        start = time.perf_counter()
        n_target = None if steps is None else self.step + int(steps)
        while True:
            if n_target is not None and self.step >= n_target:
                break
            if t_end is not None and self.time >= t_end * (1 - 1e-12):
                break
            if stop is not None and self.records and stop(self):
                break  # a resumed run that had already stopped
            dt = self.dt
            if t_end is not None and t_end - self.time < dt * (1 - 1e-9):
                # Land on t_end, but never shorten a step by round-off only.
                dt = t_end - self.time
            new, rec = self._try_step(dt)
            self.particles = new
            self.step += 1
            self.time += rec.dt
            rec.step, rec.time = self.step, self.time
            v0 = self.records[0].mesh_volume if self.records else rec.mesh_volume
            rec.volume_change = rec.mesh_volume / v0 - 1.0 if v0 > 0 else 0.0
            self.records.append(rec)
            self.last_record = rec
            last = (n_target is not None and self.step >= n_target) or (
                t_end is not None and self.time >= t_end * (1 - 1e-12)
            )
            t_out = time.perf_counter()
            if self.writer is not None and (self.step % self.output_every == 0 or last):
                self.write_output(self._cells(rec), rec.active)
            stop_now = any(bool(cb(self, new, rec)) for cb in self.callbacks)
            if stop is not None and stop(self):
                stop_now = True
            if self.checkpoint_every and (
                self.step % self.checkpoint_every == 0 or stop_now or last
            ):
                self.save_checkpoint()
            rec.timings["output"] = time.perf_counter() - t_out
            if self.progress:
                self._print_progress(rec, start, n_target, t_end)
            if stop_now:
                break
        if self.progress:
            print(file=sys.stderr)
        return self.records

    def _cells(self, rec: StepRecord) -> np.ndarray:
        """Global connectivity (ne, d+1) of the mesh the last step was solved on."""
        return rec.active[rec.local_t].T

    def _try_step(self, dt: float) -> tuple[Particles, StepRecord]:
        retries = 0
        while True:
            try:
                new, rec = self._advance(dt)
            except SolverError as err:
                if not self.adaptive or dt / 2 < self.dt_min:
                    saved = self.save_checkpoint()
                    # Keep the solver's own advice (e.g. "use displacement
                    # control" for a static overload) and add the loop's context.
                    advice = str(err).split("; ", 1)[1] if "; " in str(err) else ""
                    where = f"dt={dt:g} s" + (
                        f" (floor {self.dt_min:g} s)" if self.adaptive else ""
                    )
                    if saved is not None:
                        where += f"; results up to step {self.step} are on disk"
                    raise SolverError(
                        err.status,
                        self.step + 1,
                        err.iterations,
                        "; ".join(s for s in (advice, where) if s),
                    ) from err
                dt /= 2.0
                retries += 1
                self._successes = 0
                continue
            rec.retries = retries
            if self.adaptive:
                self._successes += 1
                if retries:
                    self.dt = dt
                elif self._successes >= self.grow_after and self.dt < self.dt_max:
                    self.dt = min(2 * self.dt, self.dt_max)
                    self._successes = 0
            if self.max_displacement is not None:
                self._displacement_control(new, rec, dt)
                if retries:  # do not grow straight after a failure
                    self.dt = min(self.dt, dt)
            return new, rec

    def _displacement_control(self, new: Particles, rec: StepRecord, dt: float):
        """Set the next step from the largest displacement of this one."""
        h = (rec.mesh_volume / max(rec.n_active, 1)) ** (1.0 / new.dim)
        du = float(np.max(np.linalg.norm(new.x - self.particles.x, axis=1)))
        limit = self.max_displacement * h
        rec.extra["max_displacement_ratio"] = du / limit
        if du > limit:
            self.dt = max(0.9 * dt * limit / du, self.dt_min)
        elif du > 0:
            self.dt = min(self.dt_max, 2 * dt, 0.9 * dt * limit / du)

    def _advance(self, dt: float) -> tuple[Particles, StepRecord]:
        return advance(
            self.particles, self.model, dt, self.mesh_source, step=self.step + 1
        )

    def _print_progress(self, rec, start, n_target, t_end) -> None:
        done = (
            rec.step / n_target if n_target else (self.time / t_end if t_end else 0.0)
        )
        el = time.perf_counter() - start
        eta = el * (1 - done) / done if done > 0 else float("nan")
        msg = (
            f"\rstep {rec.step:5d}  t={self.time:.4g} s  dt={rec.dt:.3g}  "
            f"{rec.status} ({rec.iterations} it)  {100 * done:5.1f}%  "
            f"elapsed {el:6.1f} s  eta {eta:6.1f} s"
        )
        print(msg, end="", file=sys.stderr, flush=True)

    def summary(self) -> dict[str, Any]:
        """Solver statistics of the run (steps, iterations, time per phase)."""
        recs = self.records
        phases: dict[str, float] = {}
        for r in recs:
            for k, v in r.timings.items():
                phases[k] = phases.get(k, 0.0) + v
        its = [r.iterations for r in recs]
        keys = sorted({k for r in recs for k in r.timings})
        median = {
            k: float(np.median([r.timings.get(k, 0.0) for r in recs])) for k in keys
        }
        step_times = [sum(r.timings.values()) for r in recs]
        return {
            "steps": len(recs),
            "time": self.time,
            "ipm_iterations_total": int(sum(its)),
            "ipm_iterations_max": int(max(its, default=0)),
            "ipm_iterations_mean": float(np.mean(its)) if its else 0.0,
            "statuses": sorted({r.status for r in recs}),
            "retries": int(sum(r.retries for r in recs)),
            "wall_time": phases,
            "step_time_median": float(np.median(step_times)) if recs else 0.0,
            "step_time_median_by_phase": median,
            "n_particles": int(self.particles.n),
            "mass_change": (
                float(recs[-1].mass / self.initial["mass"] - 1.0) if recs else 0.0
            ),
            "volume_change": float(recs[-1].volume_change) if recs else 0.0,
            "max_kinetic_energy": float(
                max((r.kinetic_energy for r in recs), default=0.0)
            ),
            "linear_solvers": sorted(
                {
                    r.solution.sizes.get("linear_solver", "")
                    for r in recs
                    if r.solution is not None
                }
            ),
            "peak_memory_mb": peak_memory_mb(),
        }


def peak_memory_mb() -> float:
    """Peak resident memory of this process so far, MiB (0 where unknown)."""
    try:
        import resource
    except ImportError:  # pragma: no cover - not on Windows
        return 0.0
    kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return float(kib) / (1024.0 if sys.platform != "darwin" else 1024.0**2)


@dataclass
class AtRest:
    """Stop rule for :meth:`Simulation.run`: the flow has come to rest.

    Stops once ``time >= min_time`` and the kinetic energy of the last step is
    at most ``fraction`` times a reference energy:

    * ``"max_kinetic"``: the largest kinetic energy of the run so far;
    * ``"potential_drop"``: the potential energy released since the start,
      ``E_p(0) - E_p(t)`` (never stops while nothing has fallen).

    It reads only :attr:`Simulation.records`, so a resumed run stops at the same
    step as an uninterrupted one.

    Examples
    --------
    >>> rule = AtRest(fraction=0.01, min_time=0.2)
    >>> rule.reference
    'max_kinetic'
    """

    fraction: float = 1e-3
    min_time: float = 0.0
    reference: str = "max_kinetic"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.fraction) and 0 < self.fraction < 1):
            raise ParameterError("fraction", self.fraction, "a number in (0, 1)")
        if not (math.isfinite(self.min_time) and self.min_time >= 0):
            raise ParameterError("min_time", self.min_time, "a time >= 0 (s)")
        if self.reference not in ("max_kinetic", "potential_drop"):
            raise ParameterError(
                "reference", self.reference, "'max_kinetic' or 'potential_drop'"
            )

    def __call__(self, sim: Simulation) -> bool:  # noqa: D102
        recs = sim.records
        if not recs or sim.time < self.min_time * (1 - 1e-12):
            return False
        if self.reference == "max_kinetic":
            ref = max(r.kinetic_energy for r in recs)
        else:
            ref = sim.initial["potential_energy"] - recs[-1].potential_energy
        return ref > 0 and recs[-1].kinetic_energy <= self.fraction * ref


def _jsonable(obj: Any) -> Any:
    """Convert numpy scalars in nested dicts/lists to plain Python (NaN -> None)."""
    return json.loads(
        json.dumps(obj, default=lambda o: o.item() if hasattr(o, "item") else str(o)),
        parse_constant=lambda _: None,
    )
