"""A moving rigid body of revolution in 3D models: :class:`BodyOfRevolution`.

A closed profile polygon in ``(r, z)`` turned about an axis (a flat punch, a
pile, a sphere, a cone with its shaft); see :mod:`.solid` for what the 3D
bodies share and how they enter the step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..mesh.geometry import tangents
from .body import _ON_CORNER, _ON_OUTLINE, _Moving, _polygon, _vector
from .solid import _positive, _unit3

__all__ = ["BodyOfRevolution"]

#: Points times profile edges in one block of a distance evaluation.
_BLOCK = 1 << 20


@dataclass(frozen=True)
class BodyOfRevolution(_Moving):
    """A rigid body of revolution moving with a prescribed velocity (3D).

    The body is a closed profile polygon in the half-plane ``(r, z)``, ``r >=
    0``, turned about an axis: a point ``x`` has ``z = (x - axis_point) .
    axis`` and ``r`` its distance to the axis.  Profile edges on the axis
    (``r = 0``) close the polygon but are not surface; a profile away from
    the axis makes a ring (a pipe section).

    Parameters
    ----------
    profile : array_like (m, 2)
        Corners ``(r, z)`` of the profile at time 0, m, in either order
        (stored counter-clockwise); m >= 3, every ``r >= 0``, enclosing an area.
    axis_point : array_like (3,)
        The point of the axis where ``z = 0`` at time 0, m.
    axis : array_like (3,)
        Direction of the axis (any length > 0; stored as a unit vector).
    velocity : array_like (3,)
        Constant velocity, m/s (static models: per unit of pseudo-time).
    friction_angle : float
        Coulomb interface friction angle, degrees, in [0, 90).
    adhesion : float
        Tresca interface strength ``alpha s_u``, Pa, >= 0 (not both).
    name : str
        Label: the step record's keys start with it (``<name>_force_z``).
    reference : array_like (3,), optional
        Point about which the moment is reported, at time 0 (default
        ``axis_point``).

    Raises
    ------
    ParameterError
        For a profile that is not a finite (m >= 3, 2) array with ``r >= 0``
        enclosing an area, an axis point, velocity or reference that is not a
        finite 3-vector, a zero-length axis, or bad interface parameters (as
        :class:`~skfem_npfem.RigidBody`).

    See Also
    --------
    BodyOfRevolution.cylinder, BodyOfRevolution.sphere : the usual shapes.

    Examples
    --------
    A flat punch of radius 0.2 m and height 0.5 m, its base at z = 1 m:

    >>> punch = BodyOfRevolution([[0, 0], [0.2, 0], [0.2, 0.5], [0, 0.5]],
    ...                          axis_point=[0, 0, 1.0], axis=[0, 0, 1],
    ...                          velocity=[0, 0, -0.1], name="punch")
    >>> x = np.array([[0.1, 0.0, 0.9], [0.0, 0.3, 1.2], [0.0, 0.0, 1.1]])
    >>> d, n, _ = punch.signed_distance(x, 0.0)
    >>> d.round(3).tolist()
    [0.1, 0.1, -0.1]
    >>> (n.round(3) + 0.0).tolist()
    [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]
    """

    profile: np.ndarray
    axis_point: np.ndarray = (0.0, 0.0, 0.0)
    axis: np.ndarray = (0.0, 0.0, 1.0)
    velocity: np.ndarray = (0.0, 0.0, 0.0)
    friction_angle: float = 0.0
    adhesion: float = 0.0
    name: str = "body"
    reference: np.ndarray | None = None

    def __post_init__(self) -> None:
        v, _ = _polygon("profile", self.profile, "(r, z) corners")
        if v[:, 0].min() < 0.0:
            raise ParameterError(
                "profile",
                f"a corner at r = {v[:, 0].min():g} m",
                "corners with r >= 0 (the half-plane on one side of the axis)",
            )
        v = np.ascontiguousarray(v)
        point = _vector("axis_point", self.axis_point, "m", 3)
        axis = _unit3("axis", self.axis)
        self._store(point.copy(), "punch", profile=v, axis_point=point, axis=axis)

    # -- usual shapes ---------------------------------------------------------
    @classmethod
    def cylinder(
        cls,
        base: Sequence[float],
        radius: float,
        height: float,
        axis: Sequence[float] = (0.0, 0.0, 1.0),
        **kwargs,
    ) -> BodyOfRevolution:
        """A solid circular cylinder (a flat punch, a pile) on ``base``.

        Parameters
        ----------
        base : array_like (3,)
            Centre of the base at time 0, m (the axis point, ``z = 0``).
        radius, height : float
            Radius and height (along ``axis`` from the base), m, > 0.
        axis : array_like (3,)
            Direction from the base to the top.
        **kwargs
            ``velocity``, ``friction_angle``, ``adhesion``, ``name``,
            ``reference`` (see the class).

        Examples
        --------
        >>> BodyOfRevolution.cylinder([0, 0, 1], 0.2, 0.5).profile.tolist()
        [[0.0, 0.0], [0.2, 0.0], [0.2, 0.5], [0.0, 0.5]]
        """
        _positive("radius", radius)
        _positive("height", height)
        prof = [[0.0, 0.0], [radius, 0.0], [radius, height], [0.0, height]]
        return cls(prof, axis_point=base, axis=axis, **kwargs)

    @classmethod
    def sphere(
        cls,
        centre: Sequence[float],
        radius: float,
        segments: int = 32,
        **kwargs,
    ) -> BodyOfRevolution:
        """A sphere: a half-circle profile of ``segments`` chords.

        The chords' corners are on the circle, so the polygon lies inside it
        by at most ``radius (1 - cos(pi / (2 segments)))``.

        Parameters
        ----------
        centre : array_like (3,)
            Centre at time 0, m.
        radius : float
            Radius, m, > 0.
        segments : int
            Chords of the half-circle, >= 4.
        **kwargs
            ``velocity``, ``friction_angle``, ``adhesion``, ``name``,
            ``reference`` (see the class; the axis is z).

        Examples
        --------
        >>> ball = BodyOfRevolution.sphere([0, 0, 0], 1.0, segments=64)
        >>> float(ball.signed_distance(np.array([[0.0, 2.0, 0.0]]), 0.0)[0][0])
        1.0
        """
        _positive("radius", radius)
        if isinstance(segments, bool) or not (
            isinstance(segments, int | np.integer) and segments >= 4
        ):
            raise ParameterError("segments", segments, "an integer >= 4")
        a = np.linspace(-0.5 * math.pi, 0.5 * math.pi, int(segments) + 1)
        prof = np.column_stack([radius * np.cos(a), radius * np.sin(a)])
        prof[[0, -1], 0] = 0.0
        return cls(prof, axis_point=centre, axis=(0.0, 0.0, 1.0), **kwargs)

    # -- geometry -------------------------------------------------------------
    @property
    def size(self) -> float:
        """Largest extent of the body (diameter or length), m."""
        ext = np.ptp(self.profile, axis=0)
        return float(max(2.0 * self.profile[:, 0].max(), ext[1]))

    def axis_point_at(self, t: float) -> np.ndarray:
        """The axis point (3,) at time ``t``."""
        return self.axis_point + self.displacement(t)

    def bounds_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Bounding box (lo, hi) of the body at ``t``, each (3,)."""
        c = self.axis_point_at(t)
        z = self.profile[:, 1]
        ends = c[None] + np.array([z.min(), z.max()])[:, None] * self.axis[None]
        spread = self.profile[:, 0].max() * np.sqrt(np.maximum(1.0 - self.axis**2, 0.0))
        return ends.min(axis=0) - spread, ends.max(axis=0) + spread

    def _axis_frame(self, x: np.ndarray, t: float):
        """``(r, z)`` of points (n, 3) and their radial unit vectors (n, 3)."""
        d = x - self.axis_point_at(t)
        z = d @ self.axis
        rho = d - z[:, None] * self.axis
        r = np.linalg.norm(rho, axis=1)
        fallback = tangents(self.axis[None])[0, 0]
        on_axis = r <= _ON_OUTLINE * self.size
        e_r = np.where(
            on_axis[:, None], fallback, rho / np.where(on_axis, 1.0, r)[:, None]
        )
        return np.column_stack([r, z]), e_r

    def _edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Profile edges: start corners, vectors, outward unit normals, surface."""
        a = self.profile
        ab = np.roll(a, -1, axis=0) - a
        n = np.stack([ab[:, 1], -ab[:, 0]], axis=1)
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        tol = _ON_OUTLINE * self.size
        surface = ~((np.abs(a[:, 0]) <= tol) & (np.abs(a[:, 0] + ab[:, 0]) <= tol))
        return a, ab, n, surface

    def profile_distance(
        self, q: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Signed distance of ``(r, z)`` points (n, 2) from the profile's surface.

        The 2D counterpart of :meth:`signed_distance` (the profile at time
        0): distance to the nearest surface edge (edges on the axis do not
        count), negative inside; outward normal and closest point in ``(r,
        z)``.
        """
        q = np.asarray(q, float).reshape(-1, 2)
        a, ab, edge_n, surface = self._edges()
        b = a + ab
        ap = q[:, None, :] - a[None]
        s = np.clip(np.einsum("nmk,mk->nm", ap, ab) / np.sum(ab * ab, axis=1), 0, 1)
        c = a[None] + s[..., None] * ab[None]
        d2 = np.sum((q[:, None, :] - c) ** 2, axis=2)
        d2[:, ~surface] = np.inf
        k = np.argmin(d2, axis=1)
        rows = np.arange(q.shape[0])
        closest = c[rows, k]
        dist = np.sqrt(d2[rows, k])
        # Crossing number over all edges (the axis edges close the polygon).
        ya, yb = a[:, 1][None], b[:, 1][None]
        straddle = (ya > q[:, 1:2]) != (yb > q[:, 1:2])
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = a[:, 0][None] + (q[:, 1:2] - ya) * (ab[:, 0] / ab[:, 1])[None]
        inside = np.count_nonzero(straddle & (q[:, 0:1] < xc), axis=1) % 2 == 1
        tol = _ON_OUTLINE * self.size
        on = d2 <= tol * tol
        normal = on.astype(float) @ edge_n
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
        far = dist > tol
        sign = np.where(inside, -1.0, 1.0)
        normal[far] = sign[far, None] * (q[far] - closest[far]) / dist[far, None]
        return sign * dist, normal, closest

    def signed_distance(
        self, x: np.ndarray, t: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance of points from the surface at time ``t``, negative inside.

        Returns
        -------
        dist : ndarray (n,)
            Signed distance, m (positive outside).
        normal : ndarray (n, 3)
            Unit outward normal at the closest point, ``n_r e_r + n_z e_z``.
        closest : ndarray (n, 3)
            Closest point of the surface.
        """
        x = np.asarray(x, float).reshape(-1, 3)
        q, e_r = self._axis_frame(x, t)
        # In blocks: the distance works on (points, edges, 2) arrays.
        block = max(1, _BLOCK // self.profile.shape[0])
        parts = [
            self.profile_distance(q[i : i + block])
            for i in range(0, max(q.shape[0], 1), block)
        ]
        dist, n2, c2 = (np.concatenate(a) for a in zip(*parts, strict=True))
        normal = n2[:, :1] * e_r + n2[:, 1:] * self.axis
        closest = self.axis_point_at(t) + c2[:, :1] * e_r + c2[:, 1:] * self.axis
        return dist, normal, closest

    def corner_normals(self, x: np.ndarray, normal: np.ndarray, t: float) -> np.ndarray:
        """Normals of nodes on a profile corner (a rim): the face that moves onto them.

        As :class:`~skfem_npfem.RigidBody` in 2D: a node on the rim of a flat
        punch takes the normal of the adjacent face that moves fastest along
        its own normal (the base of a punch pushed down), not the bisector,
        which would let it slide off the rim with part of its load; when both
        faces move alike it keeps the bisector.
        """
        if not x.shape[0]:
            return normal
        q, e_r = self._axis_frame(x, t)
        a, _, edge_n, surface = self._edges()
        tol = _ON_CORNER * self.size
        d2 = np.sum((q[:, None, :] - a[None]) ** 2, axis=2)
        k = np.argmin(d2, axis=1)
        on = np.flatnonzero(d2[np.arange(q.shape[0]), k] <= tol * tol)
        k = k[on]
        both = surface[k - 1] & surface[k]
        on, k = on[both], k[both]
        if not on.size:
            return normal
        faces = np.stack(
            [
                edge_n[k - 1, :1] * e_r[on] + edge_n[k - 1, 1:] * self.axis,
                edge_n[k, :1] * e_r[on] + edge_n[k, 1:] * self.axis,
            ],
            axis=1,
        )  # (m, 2, 3)
        approach = faces @ self.velocity
        best = np.argmax(approach, axis=1)
        speed = float(np.linalg.norm(self.velocity))
        use = (approach.max(axis=1) > 0.0) & (
            np.abs(approach[:, 0] - approach[:, 1]) > 1e-9 * speed
        )
        normal = normal.copy()
        normal[on[use]] = faces[use, best[use]]
        return normal
