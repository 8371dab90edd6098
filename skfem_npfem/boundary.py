"""Boundaries: rigid plane walls with frictionless or lagged-Coulomb contact.

Fixed and roller supports and prescribed displacements are particle flags
(:attr:`Particles.fixed`, :attr:`Particles.v_prescribed`); this module holds the
rigid walls that particles may touch and leave: the contact candidates of one
step (:func:`wall_contacts` for particles, :func:`node_contacts` for any
displacement nodes, handed to the cone program as :class:`Contacts`)
and the projection of particles that ended behind a wall
(:func:`project_to_walls`).  A pressure on a flat surface enters as dead
nodal loads instead (:func:`skfem_npfem.loads.surface_load`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .particles import Particles

__all__ = [
    "Contacts",
    "RigidWall",
    "floor",
    "node_contacts",
    "project_to_walls",
    "wall_contacts",
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


@dataclass
class Contacts:
    """Contact candidates of one step (node against a rigid plane or body).

    Attributes
    ----------
    node : ndarray (nc,) int
        Local node index.
    normal : ndarray (nc, d)
        Unit wall normal pointing into the body.
    gap : ndarray (nc,)
        Current gap (>= 0), m, plus ``normal . du_prescribed`` for a node with
        prescribed dofs (the program only sees the free dofs; non-penetration is
        ``gap + normal . du_free >= 0``).
    mu_lambda : ndarray (nc,)
        Friction bound ``mu * lambda_bar_n`` (N) from the previous step, or an
        adhesion bound that does not depend on the normal force (a
        :class:`RigidBody` with ``adhesion``); values <= 0 mean frictionless
        (no tangential variable).
    slip_offset : ndarray (nc, d-1) or None
        Tangential motion of the contact surface that the node's slip is
        measured against: ``t_k . (du_prescribed - du_surface)`` for a moving
        :class:`RigidBody` (the tangential counterpart of what ``gap`` holds
        along the normal).  None (fixed walls): zero.
    partner : ndarray (nc,) int or None
        Second node of a candidate that is a point of a boundary edge rather
        than a node (a :class:`RigidBody` corner against the soil's outline),
        -1 for node candidates.  None: all are node candidates.
    share : ndarray (nc,) or None
        Weight of ``partner`` in the candidate's point: its displacement is
        ``(1 - share) du_node + share du_partner`` and its force goes to the
        two nodes in the same proportions (0 for node candidates).

    Raises
    ------
    ParameterError
        If the array sizes disagree or ``gap``/``mu_lambda`` are not finite.

    Notes
    -----
    Sign conventions (docs/theory.md, "The mixed step"): the wall pushes on the body, so
    the equilibrium rows read ``G s + r - N lambda_n - T lambda_t = f~`` with
    ``lambda_n >= 0``; the normal dual gives ``gap + n . du >= 0`` and is zero
    where ``lambda_n > 0``.  Tangential forces ``lambda_t`` act along
    :func:`~skfem_npfem.step.families.tangents` of the normal and oppose the
    slip ``t . du``.
    """

    node: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    mu_lambda: np.ndarray
    slip_offset: np.ndarray | None = None
    partner: np.ndarray | None = None
    share: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.node = np.asarray(self.node, dtype=np.int64).reshape(-1)
        nc = self.node.size
        self.normal = np.asarray(self.normal, dtype=float)
        self.gap = np.asarray(self.gap, dtype=float).reshape(-1)
        self.mu_lambda = np.asarray(self.mu_lambda, dtype=float).reshape(-1)
        if (
            self.normal.ndim != 2
            or self.normal.shape[0] != nc
            or self.gap.size != nc
            or self.mu_lambda.size != nc
        ):
            raise ParameterError(
                "contacts",
                (nc, self.normal.shape, self.gap.size, self.mu_lambda.size),
                "node (nc,), normal (nc, d), gap (nc,) and mu_lambda (nc,)",
            )
        if not (np.all(np.isfinite(self.gap)) and np.all(np.isfinite(self.mu_lambda))):
            raise ParameterError(
                "contacts", "non-finite values", "finite gap, mu_lambda"
            )
        if self.slip_offset is not None:
            d = self.normal.shape[1]
            self.slip_offset = np.asarray(self.slip_offset, float).reshape(nc, d - 1)
        if (self.partner is None) != (self.share is None):
            raise ParameterError(
                "contacts",
                "partner without share",
                "both partner and share, or neither",
            )
        if self.partner is not None:
            self.partner = np.asarray(self.partner, dtype=np.int64).reshape(nc)
            self.share = np.asarray(self.share, dtype=float).reshape(nc)
            self.share = np.where(self.partner >= 0, self.share, 0.0)

    @classmethod
    def empty(cls, dim: int) -> Contacts:
        """No contacts."""
        return cls(np.zeros(0, int), np.zeros((0, dim)), np.zeros(0), np.zeros(0))

    @property
    def size(self) -> int:
        """Number of candidates."""
        return int(self.node.shape[0])

    def weights(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each candidate's nodes and their weights, as pairs.

        Returns
        -------
        nodes : ndarray (nc, 2) int
            ``node`` and ``partner`` (``node`` again for node candidates).
        weights : ndarray (nc, 2)
            ``1 - share`` and ``share`` (1 and 0 for node candidates).
        used : ndarray (nc, 2) bool
            Which of the two weights are non-zero.
        """
        if self.partner is None:
            nodes = np.stack([self.node, self.node], axis=1)
            w = np.zeros((self.size, 2))
            w[:, 0] = 1.0
        else:
            nodes = np.stack(
                [self.node, np.where(self.partner >= 0, self.partner, self.node)],
                axis=1,
            )
            w = np.stack([1.0 - self.share, self.share], axis=1)
        return nodes, w, w != 0.0

    def points(self, x: np.ndarray) -> np.ndarray:
        """Positions (nc, d) of the candidates' points, from node positions ``x``."""
        nodes, w, _ = self.weights()
        return np.einsum("ck,ckd->cd", w, x[nodes])

    def subset(self, sel: np.ndarray) -> Contacts:
        """The candidates ``sel`` (boolean or index array)."""
        return Contacts(
            node=self.node[sel],
            normal=self.normal[sel],
            gap=self.gap[sel],
            mu_lambda=self.mu_lambda[sel],
            slip_offset=None if self.slip_offset is None else self.slip_offset[sel],
            partner=None if self.partner is None else self.partner[sel],
            share=None if self.share is None else self.share[sel],
        )

    @classmethod
    def concat(cls, parts: Sequence[Contacts]) -> Contacts:
        """The candidates of several sources, in order (``slip_offset`` zero-filled)."""
        d = parts[0].normal.shape[1]
        partner = share = None
        if any(c.partner is not None for c in parts):
            partner = np.concatenate(
                [np.full(c.size, -1) if c.partner is None else c.partner for c in parts]
            )
            share = np.concatenate(
                [np.zeros(c.size) if c.share is None else c.share for c in parts]
            )
        offset = None
        if any(c.slip_offset is not None for c in parts):
            offset = np.concatenate(
                [
                    np.zeros((c.size, d - 1))
                    if c.slip_offset is None
                    else c.slip_offset
                    for c in parts
                ]
            )
        return cls(
            node=np.concatenate([c.node for c in parts]),
            normal=np.concatenate([c.normal for c in parts]),
            gap=np.concatenate([c.gap for c in parts]),
            mu_lambda=np.concatenate([c.mu_lambda for c in parts]),
            slip_offset=offset,
            partner=partner,
            share=share,
        )


def wall_contacts(
    walls: Sequence[RigidWall],
    p: Particles,
    active: np.ndarray,
    dt: float,
    h: float,
    gravity: float,
) -> tuple[Contacts, np.ndarray]:
    """Contact candidates of the active particles against every wall.

    :func:`node_contacts` on the particles of the step's mesh, with the lagged
    normal forces :attr:`Particles.wall_force`.

    Returns
    -------
    Contacts
        Candidates, with node indices local to ``active``.
    ndarray (nc,) int
        The wall of each candidate.
    """
    if p.wall_force.shape[1] < len(walls):
        raise ParameterError(
            "wall_force",
            p.wall_force.shape,
            f"one column per wall ({len(walls)}): create the particles with "
            "Particles.create(..., n_walls=len(walls))",
        )
    return node_contacts(
        walls,
        p.x[active],
        p.v[active],
        p.fixed[active],
        p.v_prescribed[active],
        p.wall_force[active],
        dt,
        h,
        gravity,
        noise_ref=p.wall_force,
    )


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
