"""SPFEM: the smoothed PFEM with explicit time stepping.

Same particles, meshes and nodal (smoothing-cell) integration as N-PFEM
(:func:`skfem_npfem.smoothing.nodal_integration` gives ``G`` and ``V_i``), but
the step is the classical explicit one instead of a cone program:

1. accelerations from the lumped (particle) masses,
   ``a = (m g - G s_n) / m``;
2. central difference, velocities at half steps with optional
   mass-proportional damping ``alpha`` (1/s) treated centred:
   ``v_{n+1/2} = ((1 - alpha dt/2) v_{n-1/2} + dt a) / (1 + alpha dt/2)``
   (this keeps the undamped stability limit ``omega dt <= 2``); prescribed
   dofs take their prescribed velocity;
3. rigid walls by *kinematic* contact: a particle that would end behind a wall
   is put back on it, its inward normal velocity removed and its tangential
   velocity reduced by ``mu`` times the normal velocity removed (never past
   zero) - the Coulomb rule the library applies to its ballistic particles
   (:func:`skfem_npfem.simulation.project_to_walls`), here with the normal
   impulse of the same step rather than a lagged force;
4. strain increment from the smoothed strain of the (corrected) displacement
   increment on the mesh at the start of the step, elastic trial stress and
   the closed-form return to the library's cones
   (:func:`~skfem_npfem.baseline.returnmap.return_map`, frozen friction and
   tension cut-off included), Hughes-Winget rotation with the smoothed spin.

No stress regularisation.  The stored particle velocity is the half-step
velocity ``v_{n+1/2}``.  ``theta1``/``theta2`` of the model are not used.

Stable step: ``dt_stable = min_i V_i^(1/d) / c_p,i`` with the smallest
smoothing-cell size ``V_i^(1/d)`` and the P-wave speed
``c_p = sqrt(M / rho_i)`` (``M`` the constrained modulus, ``rho_i = m_i /
V_i``).  Checked against the exact limit ``2 / omega_max`` of the nodally
integrated stiffness (``tests/test_baseline_spfem.py``): the exact limit was
1.3-2.6 times larger on lattice, jittered, random-Delaunay and alpha-shape
meshes in 2D and 3D.  A time step above it is refused with a
:class:`~skfem_npfem.errors.ParameterError` before any step is taken
(:meth:`SPFEM.check_dt`, called by :meth:`SPFEM.run`).  Cells shrink as a body
compresses, so during a run each step only stops with the same error once
``dt`` exceeds the current mesh's estimate by more than
:data:`MID_RUN_MARGIN` (25 %, inside the estimate's measured margin of at
least 29 %); every record reports the current ``stable_dt`` and ``cfl``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..particles import Particles
from ..simulation import (
    MeshSource,
    Model,
    StepRecord,
    energies,
    equivalent_strain,
    project_to_walls,
    rotate_stress,
)
from ..smoothing import NodalIntegration, nodal_integration
from .operators import make_mesh
from .returnmap import elastic_trial, return_map

__all__ = ["MID_RUN_MARGIN", "SPFEM", "stable_time_step"]

#: During a run, ``dt`` may exceed the current mesh's stable-step estimate by
#: this factor before :meth:`SPFEM.advance` stops (see the module docstring).
MID_RUN_MARGIN = 1.25


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


@dataclass(frozen=True)
class SPFEM:
    """Explicit smoothed PFEM (see the module docstring).

    Parameters
    ----------
    damping : float
        Mass-proportional damping coefficient ``alpha``, 1/s (0: none).  The
        damping ratio of a mode of circular frequency ``omega`` is
        ``alpha / (2 omega)``.

    Examples
    --------
    >>> SPFEM(damping=10.0).damping
    10.0
    """

    damping: float = 0.0

    def __post_init__(self) -> None:
        a = self.damping
        if isinstance(a, bool) or not (
            isinstance(a, int | float) and math.isfinite(a) and a >= 0
        ):
            raise ParameterError("damping", a, "a finite number >= 0 (1/s)")

    def initial_state(self, p: Particles, mesh_source: MeshSource) -> Particles:
        """The particles themselves (SPFEM keeps its state on them).

        Present so that every method offers ``initial_state`` and ``advance``.
        """
        return p

    def _mesh(self, p: Particles, model: Model, mesh_source: MeshSource):
        active, local_t = mesh_source(p.x)
        ni = nodal_integration(make_mesh(p.x[active], local_t))
        return active, local_t, ni

    def stable_dt(self, p: Particles, model: Model, mesh_source: MeshSource) -> float:
        """Stable time step on the mesh ``mesh_source`` gives for ``p``, s."""
        active, _, ni = self._mesh(p, model, mesh_source)
        return stable_time_step(ni, model, p.mass[active], p.material[active])

    def check_dt(
        self, dt: float, p: Particles, model: Model, mesh_source: MeshSource
    ) -> float:
        """Raise :class:`ParameterError` unless ``0 < dt <= stable step``.

        Returns the stable step.
        """
        if model.mode != "dynamic":
            raise ParameterError(
                "mode", model.mode, "SPFEM is explicit and dynamic: use mode='dynamic'"
            )
        if isinstance(dt, bool) or not (
            isinstance(dt, int | float) and math.isfinite(dt) and dt > 0
        ):
            raise ParameterError("dt", dt, "a finite time step > 0 (s)")
        stable = self.stable_dt(p, model, mesh_source)
        if dt > stable:
            raise ParameterError(
                "dt",
                dt,
                f"at most the stable explicit step {stable:.4g} s "
                "(smallest smoothing-cell size / P-wave speed)",
            )
        return stable

    def advance(
        self,
        p: Particles,
        model: Model,
        dt: float,
        mesh_source: MeshSource,
        step: int | None = None,
    ) -> tuple[Particles, StepRecord]:
        """One explicit step (same signature as :func:`skfem_npfem.simulation.advance`).

        Raises
        ------
        ParameterError
            If ``dt`` exceeds :data:`MID_RUN_MARGIN` times the stable step of
            this step's mesh, or the model is static.
        """
        if model.mode != "dynamic":
            raise ParameterError(
                "mode", model.mode, "SPFEM is explicit and dynamic: use mode='dynamic'"
            )
        if not (math.isfinite(dt) and dt > 0):
            raise ParameterError("dt", dt, "a finite time step > 0 (s)")
        t0 = time.perf_counter()
        active, local_t, ni = self._mesh(p, model, mesh_source)
        stable = stable_time_step(ni, model, p.mass[active], p.material[active])
        if dt > MID_RUN_MARGIN * stable:
            where = "" if step is None else f" at step {step}"
            raise ParameterError(
                "dt",
                dt,
                f"at most {MID_RUN_MARGIN:g} x the stable explicit step "
                f"{stable:.4g} s of the mesh{where} (smallest smoothing-cell size / "
                "P-wave speed; cells shrink as the body compresses): reduce dt",
            )
        t1 = time.perf_counter()
        new, n_contacts = self._explicit_update(p, model, dt, active, ni)
        timings = {"mesh": t1 - t0, "update": time.perf_counter() - t1}
        rec = StepRecord(
            step=-1 if step is None else step,
            time=float("nan"),
            dt=dt,
            status="Explicit",
            iterations=0,
            timings=timings,
            n_active=int(active.size),
            n_inactive=int(p.n - active.size),
            mesh_volume=float(ni.volumes.sum()),
            n_contacts=n_contacts,
            extra={"stable_dt": stable, "cfl": dt / stable},
            **energies(new, model),
            active=active,
            local_t=local_t,
        )
        return new, rec

    def _explicit_update(self, p, model, dt, active, ni):
        """Central difference, kinematic contact, return mapping, rotation."""
        d, g = model.dim, model.gravity_vector
        m = p.mass[active]
        sig_n = p.stress[active]
        f = m[:, None] * g[None, :] - (ni.G @ sig_n.reshape(-1)).reshape(-1, d)
        half = 0.5 * self.damping * dt
        v = p.v + dt * g[None, :]  # ballistic (inactive) particles
        v[active] = ((1.0 - half) * p.v[active] + dt * f / m[:, None]) / (1.0 + half)
        v = np.where(p.fixed, p.v_prescribed, v)
        wall_force = np.zeros_like(p.wall_force)
        if model.update_geometry:
            moved = p.x + dt * v
            x, v_new = project_to_walls(
                model.walls, moved, v, friction=np.ones(p.n, bool)
            )
            for w_id, wall in enumerate(model.walls):
                dvn = (v_new - v) @ wall.normal
                hit = dvn > 0
                wall_force[hit, w_id] = p.mass[hit] * dvn[hit] / dt
            du = x - p.x
        else:
            v_new, du = v, dt * v
            x = p.x
        deps = ni.strain(du[active])
        mat = p.material[active]
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
            a=(v_new - p.v) / dt,
            u=p.u + du,
            stress=stress,
            eps_p=eps_p,
            wall_force=wall_force,
        )
        return new, int(np.count_nonzero(wall_force))

    def run(
        self,
        p: Particles,
        model: Model,
        dt: float,
        mesh_source: MeshSource,
        *,
        steps: int | None = None,
        t_end: float | None = None,
        callback=None,
    ) -> tuple[Particles, dict]:
        """Many explicit steps; ``dt`` is checked before any step is taken.

        Parameters
        ----------
        p, model, dt, mesh_source
            As :meth:`advance`.
        steps : int, optional
            Number of steps.
        t_end : float, optional
            End time (``ceil(t_end / dt)`` steps of ``dt``); one of the two.
        callback : callable, optional
            ``callback(step, time, particles, record)`` after every step.

        Returns
        -------
        Particles, dict
            Final state and a summary: ``steps``, ``time``, ``stable_dt``
            (initial mesh), ``min_stable_dt`` (over the run), ``wall_time``.
        """
        stable0 = self.check_dt(dt, p, model, mesh_source)
        if (steps is None) == (t_end is None):
            raise ParameterError("steps", steps, "give exactly one of steps and t_end")
        n = int(steps) if steps is not None else math.ceil(t_end / dt - 1e-9)
        start = time.perf_counter()
        min_stable = stable0
        for k in range(n):
            p, rec = self.advance(p, model, dt, mesh_source, step=k + 1)
            min_stable = min(min_stable, rec.extra["stable_dt"])
            if callback is not None:
                callback(k + 1, (k + 1) * dt, p, rec)
        return p, {
            "steps": n,
            "time": n * dt,
            "stable_dt": stable0,
            "min_stable_dt": min_stable,
            "wall_time": time.perf_counter() - start,
        }
