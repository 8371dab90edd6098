"""Stage 3 of a step: new particles from the solution.

:func:`update_particles` gives the active particles the step's increments,
stresses and plastic strains; :func:`move_particles` moves every particle
(the ballistic ones under gravity) and asks the boundaries to put back those
that crossed them.  FEM-remap moves its particles with the same
:func:`move_particles`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..boundary import Boundary
from ..particles import Particles
from ..strength_laws import SHEAR_FROM_EQUIVALENT
from .boundary_jobs import put_back
from .conic import ConeSolution
from .kinematics import equivalent_strain, rotate_stress
from .model import Model
from .operators import StepOperators

__all__ = ["move_particles", "update_particles"]


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
    (:func:`~skfem_npfem.step.boundary_jobs.put_back`).
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
    increment = equivalent_strain(sol.deps_p)
    eps_p[active] += increment
    wall_force = np.zeros((p.n, ops.columns))
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
    # The rate a rate-dependent strength reads, and that a refinement by the
    # plastic strain rate marks by (it gives the particles a shear_rate).
    if model.strength_law is not None or p.shear_rate is not None:
        rate = np.zeros(p.n)
        rate[active] = SHEAR_FROM_EQUIVALENT * increment / dt
        new = new.replace(shear_rate=rate)
    pore = ops.data.pore
    if pore is not None:
        # Effective stress on the particles; the pore pressure beside it (a
        # grain in free flight carries none).
        excess = np.zeros(p.n)
        excess[active] = sol.pore_pressure
        total = np.zeros(p.n)
        total[active] = pore.static + sol.pore_pressure
        new = new.replace(pore_pressure=total, excess_pore_pressure=excess)
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
    move ballistically under gravity in a dynamic step and stay where they are
    in a static one (docs/theory.md, "Nodal integration", inactive
    particles); particles that crossed one of ``boundaries`` (behind a wall,
    inside a body at ``t_end``) are put back on it
    (:func:`~skfem_npfem.step.boundary_jobs.put_back`).  Shared by every method
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
    g = model.body_acceleration(t_end)
    du = np.zeros_like(p.x)
    du[active] = du_active
    th1, th2 = model.theta1, model.theta2
    inactive = np.ones(p.n, bool)
    inactive[active] = False
    if dynamic:
        if np.any(inactive):
            du[inactive] = dt * p.v[inactive] + th2 * dt**2 * g
        v = p.v + (du - dt * p.v) / (th2 * dt)
        a = ((v - p.v) / dt - (1 - th1) * p.a) / th1
        if np.any(inactive):
            v[inactive] = p.v[inactive] + dt * g
            a[inactive] = g
    else:
        # A static step has no inertia: a particle outside every element has
        # nothing to move it and stays where it is (its "velocity" is the last
        # increment over a load step, not a speed it could fly on with).
        v = du / dt
        a = np.zeros_like(p.a)
    if not model.update_geometry:
        return {"x": p.x, "v": v, "a": a, "u": p.u + du}, [None] * len(boundaries)
    # Accumulate du itself (x - p.x would lose increments below ~1e-16 |x|);
    # only the projections go through the positions.
    x, v, u, marks = put_back(boundaries, p.x + du, v, p.u + du, inactive, t_end)
    return {"x": x, "v": v, "a": a, "u": u}, marks
