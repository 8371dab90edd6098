"""Pieces of the N-PFEM step that the baselines share with it.

DUPLICATES (to be unified with the restructured step of issue 9):
:func:`node_contacts` is ``simulation._contacts`` over arbitrary displacement
nodes (the FEM baseline's P2 mid-edge nodes are not particles) and
:func:`update_particles` is the particle update of ``simulation.advance``
(θ-scheme velocities, ballistic inactive particles, wall projection,
accumulated displacements).  Both follow the library line by line so that a
FEM-remap run differs from N-PFEM only in integration and mapping.
"""

from __future__ import annotations

import numpy as np

from ..conic import Contacts
from ..errors import ParameterError
from ..particles import Particles
from ..simulation import Model, project_to_walls

__all__ = ["node_contacts", "update_particles"]


def node_contacts(
    model: Model,
    x: np.ndarray,
    v: np.ndarray,
    fixed: np.ndarray,
    v_prescribed: np.ndarray,
    lagged: np.ndarray,
    dt: float,
    h: float,
) -> tuple[Contacts, np.ndarray]:
    """Contact candidates of displacement nodes against every wall.

    Same rule as the library (``simulation._contacts``): a node is a candidate
    when its gap is below ``h + 2|v| dt + g dt^2``; nodes whose dofs along the
    normal are all fixed get no row; the gap includes the prescribed part of
    the increment; the friction bound is ``mu`` times the lagged normal force
    ``lagged[:, wall]`` (values at noise level give no friction).

    Returns
    -------
    Contacts, wall_ids
        Candidates (``node`` indexes the given nodes) and each one's wall.
    """
    d = model.dim
    if lagged.shape[1] < len(model.walls):
        raise ParameterError(
            "wall_force",
            lagged.shape,
            f"one column per wall ({len(model.walls)}): create the particles with "
            "n_walls=len(model.walls)",
        )
    nodes, normals, gaps, bounds, wall_ids = [], [], [], [], []
    du_pres = np.where(fixed, v_prescribed * dt, 0.0)
    reach = h + 2.0 * np.linalg.norm(v, axis=1) * dt + model.gravity * dt**2
    for w_id, wall in enumerate(model.walls):
        g = wall.gap(x)
        cand = np.flatnonzero(g < reach)
        cand = cand[~np.all(fixed[cand][:, np.abs(wall.normal) > 0], axis=1)]
        nodes.append(cand)
        normals.append(np.broadcast_to(wall.normal, (cand.size, d)))
        gaps.append(np.maximum(g[cand], 0.0) + du_pres[cand] @ wall.normal)
        lam = lagged[cand, w_id]
        noise = 1e-8 * np.max(np.abs(lagged[:, w_id]), initial=0.0)
        bounds.append(np.where(lam > noise, wall.mu * lam, 0.0))
        wall_ids.append(np.full(cand.size, w_id))
    if not nodes:
        return Contacts.empty(d), np.zeros(0, int)
    c = Contacts(
        node=np.concatenate(nodes),
        normal=np.concatenate(normals),
        gap=np.concatenate(gaps),
        mu_lambda=np.concatenate(bounds),
    )
    return c, np.concatenate(wall_ids)


def update_particles(
    p: Particles,
    model: Model,
    dt: float,
    active: np.ndarray,
    du_active: np.ndarray,
    **fields: np.ndarray,
) -> Particles:
    """New particles after a step (the update of ``simulation.advance``).

    Parameters
    ----------
    p : Particles
        State at the start of the step.
    model : Model
    dt : float
    active : ndarray (N_a,)
        Particles in the step's mesh.
    du_active : ndarray (N_a, d)
        Their displacement increments.
    **fields
        Other fields of the new particles (stress, eps_p, wall_force, and for
        subclasses their own fields).
    """
    g = model.gravity_vector
    th1, th2 = model.theta1, model.theta2
    du = np.zeros_like(p.x)
    du[active] = du_active
    inactive = np.ones(p.n, bool)
    inactive[active] = False
    if np.any(inactive):
        du[inactive] = dt * p.v[inactive] + th2 * dt**2 * g
    if model.mode == "dynamic":
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
        u = p.u + du + (x - moved)
    else:
        x, u = p.x, p.u + du
    return p.replace(x=x, v=v, a=a, u=u, **fields)
