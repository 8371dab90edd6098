"""SPFEM: the smoothed PFEM with explicit time stepping.

Same particles, meshes and nodal (smoothing-cell) integration as N-PFEM
(:func:`skfem_npfem.mesh.smoothing.nodal_integration` gives ``G`` and ``V_i``), but
the step is the classical explicit one instead of a cone program.  One call of
:meth:`SPFEM.advance` covers the same time step ``dt`` as one N-PFEM step, on
the same mesh (built once, from the positions at the start of the step, as
N-PFEM builds its operator), in ``n`` explicit substeps of ``dt / n`` below the
stable step:

1. accelerations from the lumped (particle) masses,
   ``a = (m g - G s) / m``;
2. central difference, velocities at half steps with optional
   mass-proportional damping ``alpha`` (1/s) treated centred:
   ``v_{k+1/2} = ((1 - alpha h/2) v_{k-1/2} + h a) / (1 + alpha h/2)``
   (this keeps the undamped stability limit ``omega h <= 2``); prescribed
   dofs take their prescribed velocity;
3. rigid walls by *kinematic* contact: a particle that would end behind a wall
   is put back on it, its inward normal velocity removed and its tangential
   velocity reduced by ``mu`` times the normal velocity removed (never past
   zero) - the Coulomb rule the library applies to its ballistic particles
   (:func:`skfem_npfem.boundary.project_to_walls`), here with the normal
   impulse of the same substep rather than a lagged force;
4. strain increment from the smoothed strain of the substep's displacement,
   elastic trial stress and the closed-form return to the library's cones
   (:func:`~skfem_npfem.baseline.returnmap.return_map`, frozen friction and
   tension cut-off included), Hughes-Winget rotation with the smoothed spin.

No stress regularisation.  The stored particle velocity is the half-step
velocity.  ``theta1``/``theta2`` of the model are not used.

Stable step: ``dt_stable = min_i V_i^(1/d) / c_p,i`` with the smoothing-cell
size ``V_i^(1/d)`` and the P-wave speed ``c_p = sqrt(M / rho_i)`` (``M`` the
constrained modulus, ``rho_i = m_i / V_i``).  Checked against the exact limit
``2 / omega_max`` of the nodally integrated stiffness
(``tests/baseline/test_spfem.py``): the exact limit was 1.3-2.6 times larger
on lattice, jittered, random-Delaunay and alpha-shape meshes in 2D and 3D.
The substep is ``explicit_dt`` if given, else :data:`SAFETY` times the stable
step of each step's mesh.  A given ``explicit_dt`` above the stable step is
refused before any step (:meth:`SPFEM.check`); during a run (cells shrink as a
body compresses) a step stops with the same error only once it exceeds the
current mesh's estimate by more than :data:`MID_RUN_MARGIN` (25 %, inside the
estimate's measured margin of at least 29 %).  Every record reports
``substeps``, ``stable_dt`` and ``cfl``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from time import perf_counter

import numpy as np

from ..boundary import project_to_walls
from ..errors import ParameterError
from ..mesh.delaunay import p1_mesh
from ..mesh.smoothing import NodalIntegration, nodal_integration
from ..mesh.sources import MeshSource, mesh_particles
from ..particles import Particles
from ..step.conic import ConeSolution
from ..step.kinematics import equivalent_strain, rotate_stress
from ..step.model import Model
from ..step.stages import Step, StepRecord, StepState
from .returnmap import elastic_trial, return_map

__all__ = ["MID_RUN_MARGIN", "SAFETY", "SPFEM", "stable_time_step"]

#: During a run, a given ``explicit_dt`` may exceed the current mesh's
#: stable-step estimate by this factor before :meth:`SPFEM.advance` stops.
MID_RUN_MARGIN = 1.25
#: Default substep as a fraction of the stable step of the step's mesh.
SAFETY = 0.9


def stable_time_step(
    ni: NodalIntegration, model: Model, mass: np.ndarray, material: np.ndarray
) -> float:
    """``min_i V_i^(1/d) / c_p,i`` of one mesh (see the module docstring).

    Parameters
    ----------
    ni : NodalIntegration
        Smoothing cells of the mesh.
    model : Model
    mass : ndarray (N,)
        Particle masses of the mesh nodes, kg.
    material : ndarray (N,) int
        Material ids of the mesh nodes.
    """
    modulus = np.array([m.p_wave_modulus for m in model.materials])[material]
    rho = mass / ni.volumes
    size = ni.volumes ** (1.0 / ni.dim)
    return float(np.min(size / np.sqrt(modulus / rho)))


def _positive(name: str, value, allow_none: bool = False):
    """``value`` if it is a finite number > 0 (``>= 0`` for damping)."""
    if value is None and allow_none:
        return None
    ok = not isinstance(value, bool) and isinstance(value, int | float)
    ok = (
        ok and math.isfinite(value) and (value >= 0 if name == "damping" else value > 0)
    )
    if not ok:
        unit = "1/s" if name == "damping" else "s"
        limit = ">= 0" if name == "damping" else "> 0"
        raise ParameterError(name, value, f"a finite number {limit} ({unit})")
    return value


@dataclass(frozen=True)
class SPFEM:
    """Explicit smoothed PFEM (see the module docstring).

    Parameters
    ----------
    damping : float
        Mass-proportional damping coefficient ``alpha``, 1/s (0: none).  The
        damping ratio of a mode of circular frequency ``omega`` is
        ``alpha / (2 omega)``.
    explicit_dt : float or None
        Explicit substep, s (None: :data:`SAFETY` x the stable step of each
        step's mesh).

    Examples
    --------
    >>> SPFEM(damping=10.0).damping
    10.0
    """

    damping: float = 0.0
    explicit_dt: float | None = None

    def __post_init__(self) -> None:
        _positive("damping", self.damping)
        _positive("explicit_dt", self.explicit_dt, allow_none=True)

    def initial_state(self, p: Particles, mesh_source: MeshSource) -> Particles:
        """The particles themselves (SPFEM keeps its state on them)."""
        return p

    def stable_dt(self, p: Particles, model: Model, mesh_source: MeshSource) -> float:
        """Stable time step on the mesh ``mesh_source`` gives for ``p``, s."""
        active, local_t = mesh_particles(mesh_source, p)
        ni = nodal_integration(p1_mesh(p.x[active], local_t))
        return stable_time_step(ni, model, p.mass[active], p.material[active])

    def check(self, p: Particles, model: Model, mesh_source: MeshSource) -> float:
        """Refuse a static model or an ``explicit_dt`` above the stable step.

        Called before any step (the scenes do); returns the stable step of
        the initial mesh.
        """
        if model.mode != "dynamic":
            raise ParameterError(
                "mode",
                model.mode,
                "dynamic: SPFEM is explicit (quasi-static problems: npfem or "
                "fem-remap)",
            )
        _refuse_bodies(model)
        stable = self.stable_dt(p, model, mesh_source)
        if self.explicit_dt is not None and self.explicit_dt > stable:
            raise ParameterError(
                "explicit_dt",
                self.explicit_dt,
                f"at most the stable explicit step {stable:.4g} s "
                "(smallest smoothing-cell size / P-wave speed); omit it for "
                f"{SAFETY:g} x the stable step",
            )
        return stable

    def advance(
        self,
        p: Particles,
        model: Model,
        dt: float,
        mesh_source: MeshSource,
        step: int | None = None,
        start: StepState | None = None,
    ) -> tuple[Particles, Step]:
        """Advance by ``dt`` in explicit substeps on one mesh.

        Same signature and result as :func:`skfem_npfem.advance`;
        ``result.record.extra`` holds ``substeps``, ``stable_dt``,
        ``explicit_dt`` and ``cfl``.

        ``start`` (the state at the start of the step) only gives the time
        of the returned ``result.state``: SPFEM refuses rigid bodies and has
        no volume correction, the rest of what reads it.

        Raises
        ------
        ParameterError
            A static model, a model with rigid bodies or dead loads, or a given
            ``explicit_dt`` above :data:`MID_RUN_MARGIN` times the stable step
            of this step's mesh.
        """
        if model.mode != "dynamic":
            raise ParameterError("mode", model.mode, "dynamic: SPFEM is explicit")
        _refuse_bodies(model)
        model.refuse_loads("SPFEM")
        if not (math.isfinite(dt) and dt > 0):
            raise ParameterError("dt", dt, "a finite time step > 0 (s)")
        t0 = perf_counter()
        active, local_t = mesh_particles(mesh_source, p)
        ni = nodal_integration(p1_mesh(p.x[active], local_t))
        stable = stable_time_step(ni, model, p.mass[active], p.material[active])
        n_sub = self._substeps(dt, stable, step)
        h = dt / n_sub
        t1 = perf_counter()
        q, impulse = p, np.zeros_like(p.wall_force)
        GT = ni.G.T.tocsr()  # strains of every substep (G is fixed in the step)
        for _ in range(n_sub):  # explicit substeps: the method's own time loop
            q, dv = self._substep(q, model, h, active, ni, GT)
            impulse += dv
        wall_force = impulse / dt
        q = q.replace(wall_force=wall_force)
        sol = self._solution(p, q, model, active, ni)
        timings = {"mesh": t1 - t0, "update": perf_counter() - t1}
        rec = StepRecord.of_step(
            step,
            dt,
            q,
            model.gravity,
            active,
            ni,
            sol,
            timings,
            substeps=n_sub,
            stable_dt=stable,
            explicit_dt=h,
            cfl=h / stable,
        )
        rec.n_contacts = int(np.count_nonzero(np.any(wall_force > 0, axis=1)))
        end = (StepState() if start is None else start).after(dt, None)
        return q, Step(rec, sol, active, local_t, ni, q, end)

    def _substeps(self, dt: float, stable: float, step: int | None) -> int:
        """Number of substeps of a step of ``dt`` on a mesh of this stable step."""
        h = self.explicit_dt
        if h is None:
            h = SAFETY * stable
        elif h > MID_RUN_MARGIN * stable:
            where = "" if step is None else f" at step {step}"
            raise ParameterError(
                "explicit_dt",
                h,
                f"at most {MID_RUN_MARGIN:g} x the stable explicit step "
                f"{stable:.4g} s of the mesh{where} (cells shrink as the body "
                "compresses): reduce it or omit it (automatic)",
            )
        return max(1, math.ceil(dt / h * (1 - 1e-12)))

    def _substep(self, p: Particles, model: Model, h: float, active, ni, GT):
        """Central difference, kinematic contact, return mapping, rotation."""
        d, g = model.dim, model.gravity_vector
        m = p.mass[active]
        sig_n = p.stress[active]
        f = m[:, None] * g[None, :] - (ni.G @ sig_n.reshape(-1)).reshape(-1, d)
        half = 0.5 * self.damping * h
        v = p.v + h * g[None, :]  # ballistic (inactive) particles
        v[active] = ((1.0 - half) * p.v[active] + h * f / m[:, None]) / (1.0 + half)
        v = np.where(p.fixed, p.v_prescribed, v)
        impulse = np.zeros_like(p.wall_force)
        if model.update_geometry:
            moved = p.x + h * v
            x, v_new = project_to_walls(
                model.walls, moved, v, friction=np.ones(p.n, bool)
            )
            for w_id, wall in enumerate(model.walls):
                dvn = (v_new - v) @ wall.normal
                hit = dvn > 0
                impulse[hit, w_id] = p.mass[hit] * dvn[hit]
            du = x - p.x
        else:
            v_new, du, x = v, h * v, p.x
        mat = p.material[active]
        deps = (GT @ du[active].reshape(-1)).reshape(-1, sig_n.shape[1])
        deps /= ni.volumes[:, None]
        trial = elastic_trial(model.materials, mat, d, sig_n, deps)
        back = return_map(model.materials, mat, d, trial, sig_n)
        sig = back.sigma
        if model.objective_rotation:
            sig = rotate_stress(sig, ni.gradient(du[active]))
        stress = p.stress.copy()
        stress[active] = sig
        eps_p = p.eps_p.copy()
        eps_p[active] += equivalent_strain(back.deps_p)
        new = p.replace(
            x=x,
            v=v_new,
            a=(v_new - p.v) / h,
            u=p.u + du,
            stress=stress,
            eps_p=eps_p,
        )
        return new, impulse

    @staticmethod
    def _solution(p, q, model: Model, active, ni) -> ConeSolution:
        """The step as a :class:`ConeSolution` on the active particles.

        ``reaction`` is the support force ``G s - m g`` on prescribed dofs at the
        end of the step; there are no contact multipliers (kinematic contact).
        """
        d = model.dim
        f_int = (ni.G @ q.stress[active][:, list(ni.components)].reshape(-1)).reshape(
            -1, d
        )
        weight = q.mass[active][:, None] * model.gravity_vector[None, :]
        reaction = np.where(q.fixed[active], f_int - weight, 0.0)
        return ConeSolution(
            du=(q.u - p.u)[active],
            sigma=q.stress[active],
            deps_p=np.zeros_like(q.stress[active]),
            reaction=reaction,
            lambda_n=np.zeros(0),
            lambda_t=np.zeros((0, d - 1)),
            status="Explicit",
            iterations=0,
        )


def _refuse_bodies(model: Model) -> None:
    """SPFEM has no rigid-body contact: refuse a model with bodies."""
    if model.bodies:
        raise ParameterError(
            "bodies",
            [b.name for b in model.bodies],
            "no rigid bodies with SPFEM (its explicit substeps have no contact "
            "rows): use npfem or fem-remap",
        )
