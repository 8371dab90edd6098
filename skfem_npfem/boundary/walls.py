"""Rigid plane walls with frictionless or lagged-Coulomb contact.

Fixed and roller supports and prescribed displacements are particle flags
(:attr:`Particles.fixed`, :attr:`Particles.v_prescribed`); this module holds the
rigid walls that particles may touch and leave: the contact candidates of one
step (:func:`node_contacts` on any displacement nodes, handed to the cone
program as :class:`~skfem_npfem.boundary.contacts.Contacts`), the projection of
particles that ended behind a wall (:func:`project_to_walls`) and
:class:`Walls`, the walls of a model as one
:class:`~skfem_npfem.boundary.protocol.Boundary` of a step.  A pressure on a
flat surface enters as dead nodal loads instead
(:func:`skfem_npfem.loads.surface_load`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..particles import Particles
from .contacts import Contacts
from .protocol import ContactNodes

__all__ = [
    "RigidWall",
    "Walls",
    "floor",
    "node_contacts",
    "project_to_walls",
    "wall_x",
]


@dataclass(frozen=True)
class RigidWall:
    """A fixed rigid plane ``(x - point) . normal >= 0`` (the body side).

    Contact is unilateral (gap closes, never penetrates, the wall only pushes).
    Friction is Coulomb with the *lagged* normal force of the previous step
    (associated friction would lift nodes off by ``mu |slip|``: docs/theory.md,
    "Wall friction: lagged normal forces").

    Parameters
    ----------
    point : array_like (d,)
        A point on the wall, m.
    normal : array_like (d,)
        Normal pointing into the body (normalised here).
    friction_angle : float
        Wall friction angle, degrees, in [0, 90); 0 (the default) is
        frictionless (a symmetry plane).
    name : str
        Label used in messages and pictures (default ``"wall"``).

    Raises
    ------
    ParameterError
        If ``point`` and ``normal`` are not vectors of the same size 2 or 3,
        the normal is zero or not finite, or the friction angle is outside
        [0, 90).

    Examples
    --------
    >>> w = RigidWall(point=[0.0, 0.0], normal=[0.0, 2.0], friction_angle=30.0)
    >>> round(w.mu, 4), w.normal.tolist()
    (0.5774, [0.0, 1.0])
    """

    point: np.ndarray
    normal: np.ndarray
    friction_angle: float = 0.0
    name: str = "wall"

    def __post_init__(self) -> None:
        p = np.asarray(self.point, float)
        n = np.asarray(self.normal, float)
        if p.ndim != 1 or p.shape != n.shape or p.size not in (2, 3):
            raise ParameterError("wall", (p.shape, n.shape), "point/normal of size d")
        norm = float(np.linalg.norm(n))
        if not (np.all(np.isfinite(p)) and math.isfinite(norm) and norm > 0):
            raise ParameterError("normal", self.normal, "a finite non-zero vector")
        fa = float(self.friction_angle)
        if not (math.isfinite(fa) and 0.0 <= fa < 90.0):
            raise ParameterError(
                "friction_angle", self.friction_angle, "degrees in [0, 90)"
            )
        object.__setattr__(self, "point", p)
        object.__setattr__(self, "normal", n / norm)
        object.__setattr__(self, "friction_angle", fa)

    @property
    def mu(self) -> float:
        """Friction coefficient ``tan(friction_angle)``."""
        return math.tan(math.radians(self.friction_angle))

    def gap(self, x: np.ndarray) -> np.ndarray:
        """Signed distance of points (n, d) from the wall (positive: body side)."""
        return (np.asarray(x) - self.point) @ self.normal

    def project(self, x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Put points behind the wall back on it and remove their inward velocity.

        Used for particles that are not in the cone program (ballistic ones).
        """
        g = self.gap(x)
        behind = g < 0.0
        if not np.any(behind):
            return x, v
        x = x.copy()
        v = v.copy()
        x[behind] -= g[behind, None] * self.normal
        vn = v[behind] @ self.normal
        v[behind] -= np.minimum(vn, 0.0)[:, None] * self.normal
        return x, v


def floor(dim: int, friction_angle: float = 0.0, level: float = 0.0) -> RigidWall:
    """Horizontal floor ``x_d = level`` (gravity acts along ``-e_d``)."""
    n = np.zeros(dim)
    n[-1] = 1.0
    return RigidWall(
        point=level * n, normal=n, friction_angle=friction_angle, name="floor"
    )


def wall_x(
    dim: int, x0: float, facing: int = 1, friction_angle: float = 0.0
) -> RigidWall:
    """Vertical wall ``x = x0``; ``facing=+1`` keeps the body at ``x >= x0``."""
    n = np.zeros(dim)
    n[0] = float(np.sign(facing))
    p = np.zeros(dim)
    p[0] = x0
    return RigidWall(point=p, normal=n, friction_angle=friction_angle, name="wall")


@dataclass(frozen=True)
class Walls:
    """A model's rigid walls as one boundary of a step.

    The :class:`~skfem_npfem.boundary.protocol.Boundary` of the walls: they
    span no element, give the contact rows of :func:`node_contacts` (columns
    ``0 .. len(walls)-1`` of the lagged forces), put particles behind them
    back (:func:`project_to_walls`) and write nothing into the record.

    Parameters
    ----------
    walls : sequence of RigidWall
    gravity : float
        Gravitational acceleration, m/s^2 (the contact reach of a step).
    """

    walls: Sequence[RigidWall]
    gravity: float

    def with_columns(self, p: Particles) -> Particles:
        """``p``: the particles are made with their wall columns."""
        return p

    def without_spanned(
        self,
        x: np.ndarray,
        active: np.ndarray,
        local_t: np.ndarray,
        time: float,
        sliver: float | None,
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """The mesh unchanged: a wall spans no element."""
        return active, local_t, 0

    def contacts(
        self, nodes: ContactNodes, dt: float, h: float, time: float
    ) -> tuple[Contacts, np.ndarray]:
        """:func:`node_contacts` of the nodes against every wall.

        Raises
        ------
        ParameterError
            If the nodes have fewer lagged-force columns than walls.
        """
        if nodes.lagged.shape[1] < len(self.walls):
            raise ParameterError(
                "wall_force",
                nodes.lagged.shape,
                f"one column per wall ({len(self.walls)}): create the particles "
                "with Particles.create(..., n_walls=len(walls))",
            )
        return node_contacts(
            self.walls,
            nodes.x,
            nodes.v,
            nodes.fixed,
            nodes.v_prescribed,
            nodes.lagged,
            dt,
            h,
            self.gravity,
            noise_ref=nodes.noise_ref,
        )

    def put_back(
        self,
        x: np.ndarray,
        v: np.ndarray,
        u: np.ndarray,
        friction: np.ndarray,
        t_end: float,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, None]:
        """:func:`project_to_walls`; ``u`` takes the projection's shift."""
        moved = x
        x, v = project_to_walls(self.walls, moved, v, friction=friction)
        return x, v, u + (x - moved), None

    def record(
        self,
        extra: dict[str, Any],
        contacts: Contacts,
        ids: np.ndarray,
        lambdas: tuple[np.ndarray, np.ndarray],
        x: np.ndarray,
        t_end: float,
        mark: None,
        dropped: int,
    ) -> None:
        """Nothing: the walls' forces are the particles' lagged columns."""


def node_contacts(
    walls: Sequence[RigidWall],
    x: np.ndarray,
    v: np.ndarray,
    fixed: np.ndarray,
    v_prescribed: np.ndarray,
    lagged: np.ndarray,
    dt: float,
    h: float,
    gravity: float,
    noise_ref: np.ndarray | None = None,
) -> tuple[Contacts, np.ndarray]:
    """Contact candidates of displacement nodes (particles or not) against walls.

    A node is a candidate when its gap is below ``h + 2|v| dt + g dt^2`` so
    that fast nodes cannot tunnel through a wall within one step.  The gap
    handed to the cone program includes the normal part of any prescribed
    displacement increment of the node (the program only sees the free dofs).
    The friction bound is ``mu`` times the node's lagged normal force
    ``lagged[:, wall]``.

    Parameters
    ----------
    walls : sequence of RigidWall
    x, v : ndarray (n, d)
        Node positions and velocities at the start of the step.
    fixed : ndarray (n, d) bool
        Prescribed dofs; ``v_prescribed`` (n, d) their velocities.
    lagged : ndarray (n, n_walls)
        Normal force of each wall on the node in the previous step, N.
    dt, h, gravity : float
        Time step (s), mesh size (m), gravitational acceleration (m/s^2).
    noise_ref : ndarray (m, n_walls), optional
        Forces that set the noise level of ``lagged`` per wall (default
        ``lagged``; the particles pass all of theirs, not only the active ones).

    Returns
    -------
    Contacts
        Candidates (``node`` indexes the given nodes).
    ndarray (nc,) int
        The wall of each candidate.
    """
    d = x.shape[1]
    noise_ref = lagged if noise_ref is None else noise_ref
    nodes, normals, gaps, bounds, wall_ids = [], [], [], [], []
    du_pres = np.where(fixed, v_prescribed * dt, 0.0)
    reach = h + 2.0 * np.linalg.norm(v, axis=1) * dt + gravity * dt**2
    for w_id, wall in enumerate(walls):
        g = wall.gap(x)
        cand = np.flatnonzero(g < reach)
        # A node whose dofs along the normal are all fixed needs no contact row.
        cand = cand[~np.all(fixed[cand][:, np.abs(wall.normal) > 0], axis=1)]
        nodes.append(cand)
        normals.append(np.broadcast_to(wall.normal, (cand.size, d)))
        gaps.append(np.maximum(g[cand], 0.0) + du_pres[cand] @ wall.normal)
        # Lagged normal force; values at the solver's noise level (a node that
        # was only a candidate, lambda_n ~ +-1e-8 of the load) give no friction
        # rather than a near-degenerate |lambda_t| <= tiny constraint.
        lam = lagged[cand, w_id]
        noise = 1e-8 * np.max(np.abs(noise_ref[:, w_id]), initial=0.0)
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


def project_to_walls(
    walls: Sequence[RigidWall],
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
