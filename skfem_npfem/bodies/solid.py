"""Moving rigid bodies in 3D models: planes and bodies of revolution.

Two shapes, each moving with a constant velocity vector:

* :class:`RigidPlane` -- the half-space behind a plane (a plate wider than the
  soil, a rigid base pushed up);
* :class:`BodyOfRevolution` -- a closed profile polygon in ``(r, z)`` turned
  about an axis (a flat punch, a pile, a sphere, a cone with its shaft).
  For a point ``x`` the distance to the surface is the distance of its
  ``(r, z)`` (``r`` the distance to the axis, ``z`` the coordinate along it)
  to the profile's outline, and the normal is ``n_r e_r + n_z e_z``; the
  profile's edges that lie on the axis (``r = 0``) are not surface.

They enter the step as :class:`~skfem_npfem.RigidBody` does in 2D
(:mod:`skfem_npfem.bodies.body`): the elements that span a body are dropped
(:func:`spanning_tetrahedra`), the mesh's nodes get unilateral contact rows
against the body at its position at the start of the step
(:func:`solid_contacts`; frictionless, Tresca adhesion or Coulomb friction
with the normal force lagged one step), particles that end inside are put
back on its surface (:func:`~skfem_npfem.bodies.project_out_of_bodies`) and
the step records the force and moment vectors of the soil on each body
(:func:`solid_loads`).  There are no corner rows: an edge of a body (the rim
of a flat punch) can press into a boundary face of the soil between its
nodes; the nodes themselves stay out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..boundary import Contacts
from ..errors import ParameterError
from .body import _ON_CORNER, _ON_OUTLINE

__all__ = [
    "BodyOfRevolution",
    "RigidPlane",
    "boundary_faces",
    "face_tributary",
    "solid_contacts",
    "solid_loads",
    "spanning_tetrahedra",
]

#: Depth, as a fraction of an element's longest edge, beyond which a probe of
#: the element inside a body makes it span the body (a flat face between
#: nodes on a curved surface cuts into it by its sagitta, h^2 / (8 R)).
_SPAN_DEPTH = 0.05

#: Points times profile edges in one block of a distance evaluation.
_BLOCK = 1 << 20


def _tangents(normals: np.ndarray) -> np.ndarray:
    """The cone program's tangent basis (n, 2, 3) of unit normals (n, 3).

    :func:`skfem_npfem.step.families.tangents` (imported when called: the step
    package imports this one).
    """
    from ..step.families import tangents

    return tangents(normals)


def _vector3(name: str, value, what: str = "m or m/s") -> np.ndarray:
    """A finite 3-vector."""
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(name, value, "a finite vector of size 3") from None
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ParameterError(name, value, f"a finite vector of size 3 ({what})")
    return v


def _unit3(name: str, value) -> np.ndarray:
    """A finite non-zero 3-vector, normalised."""
    v = _vector3(name, value, "a direction")
    norm = float(np.linalg.norm(v))
    if not norm > 0.0:
        raise ParameterError(name, value, "a non-zero direction (3 components)")
    return v / norm


def _check_interface(friction_angle, adhesion, name) -> tuple[float, float]:
    """The interface parameters shared by the 3D bodies (as RigidBody)."""
    fa = friction_angle
    if isinstance(fa, bool) or not (
        isinstance(fa, int | float) and math.isfinite(fa) and 0.0 <= fa < 90.0
    ):
        raise ParameterError("friction_angle", fa, "degrees in [0, 90)")
    ad = adhesion
    if isinstance(ad, bool) or not (
        isinstance(ad, int | float) and math.isfinite(ad) and ad >= 0.0
    ):
        raise ParameterError("adhesion", ad, "a finite stress >= 0 (Pa)")
    if fa > 0 and ad > 0:
        raise ParameterError(
            "adhesion",
            ad,
            "0 when friction_angle > 0 (choose Coulomb friction or Tresca adhesion)",
        )
    if not (isinstance(name, str) and name.isidentifier()):
        raise ParameterError("name", name, "a word (letters, digits, _), e.g. 'punch'")
    return float(fa), float(ad)


class _Moving3D:
    """What the 3D bodies share: interface, motion, inside test."""

    velocity: np.ndarray
    friction_angle: float
    adhesion: float
    name: str
    reference: np.ndarray

    @property
    def mu(self) -> float:
        """Coulomb friction coefficient ``tan(friction_angle)``."""
        return math.tan(math.radians(self.friction_angle))

    @property
    def interface(self) -> str:
        """``"smooth"``, ``"adhesion"`` or ``"coulomb"``."""
        if self.adhesion > 0:
            return "adhesion"
        return "coulomb" if self.friction_angle > 0 else "smooth"

    @property
    def dim(self) -> int:
        """3: a body of 3D models."""
        return 3

    def displacement(self, t: float) -> np.ndarray:
        """Displacement (3,) from time 0 to ``t``, m."""
        return self.velocity * float(t)

    def reference_at(self, t: float) -> np.ndarray:
        """The moment's reference point (3,) at time ``t``."""
        return self.reference + self.displacement(t)

    def signed_distance(  # pragma: no cover - overridden
        self, x: np.ndarray, t: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        raise NotImplementedError

    def contains(self, x: np.ndarray, t: float) -> np.ndarray:
        """Points (n, 3) strictly inside the body at time ``t`` (n,) bool."""
        dist, _, _ = self.signed_distance(x, t)
        return dist < -_ON_OUTLINE * self.size

    @property
    def size(self) -> float:  # pragma: no cover - overridden
        raise NotImplementedError


@dataclass(frozen=True)
class RigidPlane(_Moving3D):
    """The rigid half-space behind a plane, moving with a prescribed velocity (3D).

    Parameters
    ----------
    point : array_like (3,)
        A point of the plane at time 0, m.
    normal : array_like (3,)
        Normal of the plane pointing out of the body, towards the soil (any
        length > 0; stored as a unit vector).  The body is every point ``x``
        with ``(x - point) . normal < 0``.
    velocity : array_like (3,)
        Constant velocity, m/s (static models: per unit of pseudo-time).
    friction_angle : float
        Coulomb interface friction angle, degrees, in [0, 90).
    adhesion : float
        Tresca interface strength ``alpha s_u``, Pa, >= 0.  At most one of
        ``friction_angle`` and ``adhesion`` may be > 0; both 0: frictionless.
    name : str
        Label: the step record's keys start with it (``<name>_force_z``).
    reference : array_like (3,), optional
        Point about which the moment is reported, at time 0 (default
        ``point``).

    Raises
    ------
    ParameterError
        For a point, velocity or reference that is not a finite 3-vector, a
        zero or non-finite normal, a friction angle outside [0, 90), a
        negative adhesion, both interface laws, or a name that is not a word.

    Examples
    --------
    >>> lid = RigidPlane([0.0, 0.0, 1.0], [0.0, 0.0, -2.0],
    ...                  velocity=[0.0, 0.0, -0.1], name="lid")
    >>> lid.normal.tolist(), lid.interface
    ([0.0, 0.0, -1.0], 'smooth')
    >>> d, n, _ = lid.signed_distance(np.array([[0.3, 0.2, 0.5]]), 1.0)
    >>> d.round(3).tolist(), n[0].tolist()
    ([0.4], [0.0, 0.0, -1.0])
    """

    point: np.ndarray
    normal: np.ndarray
    velocity: np.ndarray = (0.0, 0.0, 0.0)
    friction_angle: float = 0.0
    adhesion: float = 0.0
    name: str = "plane"
    reference: np.ndarray | None = None

    def __post_init__(self) -> None:
        point = _vector3("point", self.point, "m")
        normal = _unit3("normal", self.normal)
        vel = _vector3("velocity", self.velocity, "m/s")
        fa, ad = _check_interface(self.friction_angle, self.adhesion, self.name)
        ref = (
            point.copy()
            if self.reference is None
            else _vector3("reference", self.reference, "m")
        )
        for key, value in (
            ("point", point),
            ("normal", normal),
            ("velocity", vel),
            ("friction_angle", fa),
            ("adhesion", ad),
            ("reference", ref),
        ):
            object.__setattr__(self, key, value)

    @property
    def size(self) -> float:
        """Length scale of the on-surface tolerances, m: 1 (a plane has no size)."""
        return 1.0

    def bounds_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Bounding box (lo, hi) of the body at ``t``: unbounded."""
        return np.full(3, -np.inf), np.full(3, np.inf)

    def signed_distance(
        self, x: np.ndarray, t: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance of points from the plane at time ``t``, negative inside.

        Returns
        -------
        dist : ndarray (n,)
            Signed distance, m (positive on the soil's side).
        normal : ndarray (n, 3)
            The plane's unit normal.
        closest : ndarray (n, 3)
            Closest point of the plane.
        """
        x = np.asarray(x, float).reshape(-1, 3)
        dist = (x - (self.point + self.displacement(t))) @ self.normal
        normal = np.broadcast_to(self.normal, x.shape).copy()
        return dist, normal, x - dist[:, None] * self.normal

    def corner_normals(self, x: np.ndarray, normal: np.ndarray, t: float) -> np.ndarray:
        """A plane has no corners: ``normal`` unchanged."""
        return normal


@dataclass(frozen=True)
class BodyOfRevolution(_Moving3D):
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
        try:
            v = np.asarray(self.profile, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(
                "profile", self.profile, "an array (m, 2) of (r, z) corners"
            ) from None
        if v.ndim != 2 or v.shape[1] != 2 or not np.all(np.isfinite(v)):
            raise ParameterError(
                "profile",
                getattr(v, "shape", v),
                "a finite array (m, 2) of (r, z) corners",
            )
        if v.shape[0] > 3 and np.allclose(v[0], v[-1]):
            v = v[:-1]
        if v.shape[0] and v[:, 0].min() < 0.0:
            raise ParameterError(
                "profile",
                f"a corner at r = {v[:, 0].min():g} m",
                "corners with r >= 0 (the half-plane on one side of the axis)",
            )
        area = 0.5 * float(
            np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1])
        )
        size = float(np.ptp(v, axis=0).max()) if v.shape[0] else 0.0
        if v.shape[0] < 3 or not abs(area) > 1e-12 * size**2:
            raise ParameterError(
                "profile",
                f"{v.shape[0]} corners enclosing an area of {abs(area):g} m^2",
                "at least 3 corners enclosing a non-zero area",
            )
        if area < 0:
            v = v[::-1].copy()
        point = _vector3("axis_point", self.axis_point, "m")
        axis = _unit3("axis", self.axis)
        vel = _vector3("velocity", self.velocity, "m/s")
        fa, ad = _check_interface(self.friction_angle, self.adhesion, self.name)
        ref = (
            point.copy()
            if self.reference is None
            else _vector3("reference", self.reference, "m")
        )
        for key, value in (
            ("profile", v),
            ("axis_point", point),
            ("axis", axis),
            ("velocity", vel),
            ("friction_angle", fa),
            ("adhesion", ad),
            ("reference", ref),
        ):
            object.__setattr__(self, key, value)

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
        fallback = _tangents(self.axis[None])[0, 0]
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


def _positive(name: str, value) -> float:
    if isinstance(value, bool) or not (
        isinstance(value, int | float) and math.isfinite(value) and value > 0
    ):
        raise ParameterError(name, value, "a finite length > 0 (m)")
    return float(value)


SolidBody = RigidPlane | BodyOfRevolution


# --- the step's pieces ------------------------------------------------------
def boundary_faces(t: np.ndarray) -> np.ndarray:
    """Boundary faces (3, nf) of a tetrahedral mesh ``t`` (4, ne): faces of one tet.

    Examples
    --------
    >>> boundary_faces(np.array([[0, 1, 2, 3]]).T).T.tolist()
    [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]
    """
    faces = np.concatenate([t[[0, 1, 2]], t[[0, 1, 3]], t[[0, 2, 3]], t[[1, 2, 3]]], 1)
    faces = np.sort(faces, axis=0).astype(np.int64)
    n = int(faces.max(initial=0)) + 1
    if n**3 < 2**62:  # one integer key per face: a 1D unique, 10x faster
        key = (faces[0] * n + faces[1]) * n + faces[2]
        _, first, counts = np.unique(key, return_index=True, return_counts=True)
        out = faces[:, first[counts == 1]]
        return out[:, np.lexsort(out[::-1])]
    uniq, counts = np.unique(faces, axis=1, return_counts=True)
    return uniq[:, counts == 1]


def face_tributary(
    x: np.ndarray, faces: np.ndarray, normal: np.ndarray | None = None
) -> np.ndarray:
    """Contact area of each node of a 3D mesh: a third of its boundary faces.

    Parameters
    ----------
    x : ndarray (N, 3)
        Node positions.
    faces : ndarray (3, nf)
        Boundary faces (:func:`boundary_faces`).
    normal : ndarray (N, 3), optional
        Unit normal of the surface a node touches: a face then counts with
        its area projected on that surface (a side face meeting a flat
        contact face adds nothing).  None: full areas.

    Returns
    -------
    ndarray (N,)
        m^2; 0 for interior nodes.

    Examples
    --------
    One tetrahedron: projected on a horizontal surface, its base and its
    slanted face count 1/2 m^2 each, its two vertical faces nothing.

    >>> x = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> f = boundary_faces(np.array([[0, 1, 2, 3]]).T)
    >>> face_tributary(x, f, np.tile([0.0, 0, 1], (4, 1))).round(3).tolist()
    [0.167, 0.333, 0.333, 0.167]
    """
    cross = np.cross(x[faces[1]] - x[faces[0]], x[faces[2]] - x[faces[0]])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    out = np.zeros(x.shape[0])
    for k in range(3):
        node = faces[k]
        w = area / 3.0
        if normal is not None:
            w = 0.5 * np.abs(np.sum(cross * normal[node], axis=1)) / 3.0
        out += np.bincount(node, weights=w, minlength=x.shape[0])
    return out


def _near3(body: SolidBody, x: np.ndarray, t: float, reach) -> np.ndarray:
    lo, hi = body.bounds_at(t)
    r = np.asarray(reach)[..., None] if np.ndim(reach) else reach
    return np.flatnonzero(np.all((x > lo - r) & (x < hi + r), axis=1))


def spanning_tetrahedra(
    bodies: Sequence[SolidBody], x: np.ndarray, t: np.ndarray, time: float
) -> np.ndarray:
    """Tetrahedra (4, ne) of nodes ``x`` that span a body at ``time`` (ne,) bool.

    An element spans a body when one of its probes -- the centroid, the six
    edge midpoints and the four face centroids -- is inside the body deeper
    than ``_SPAN_DEPTH`` (5 %) of the element's longest edge: a face between
    nodes on a curved surface cuts into it by its sagitta and is kept.
    Bodies thinner than about half an element may be missed (the 2D
    :func:`~skfem_npfem.bodies.spanning_elements` also tests crossing edges).
    """
    ne = t.shape[1]
    drop = np.zeros(ne, bool)
    if not ne:
        return drop
    xe = x[t]  # (4, ne, 3)
    lo, hi = xe.min(axis=0), xe.max(axis=0)
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    for body in bodies:
        blo, bhi = body.bounds_at(time)
        near = np.flatnonzero(np.all((lo < bhi) & (hi > blo), axis=1))
        if not near.size:
            continue
        p = xe[:, near]  # (4, k, 3)
        edge = np.stack([np.linalg.norm(p[i] - p[j], axis=1) for i, j in pairs])
        longest = edge.max(axis=0)
        # Every probe is within the longest edge of the centroid: elements
        # whose centroid is farther from the body than that are clear.
        centroid = p.mean(axis=0)
        close = body.signed_distance(centroid, time)[0] < longest
        near, p, longest = near[close], p[:, close], longest[close]
        if not near.size:
            continue
        mids = np.stack([0.5 * (p[i] + p[j]) for i, j in pairs])
        face_c = (p.sum(axis=0)[None] - p) / 3.0
        probes = np.concatenate([p.mean(axis=0)[None], mids, face_c])  # (11, k, 3)
        depth = _SPAN_DEPTH * longest
        dist = body.signed_distance(probes.reshape(-1, 3), time)[0]
        inside = dist.reshape(probes.shape[:2]) < -np.maximum(
            depth, _ON_OUTLINE * body.size
        )
        drop[near[np.any(inside, axis=0)]] = True
    return drop


def solid_contacts(
    bodies: Sequence[SolidBody],
    x: np.ndarray,
    v: np.ndarray,
    fixed: np.ndarray,
    v_prescribed: np.ndarray,
    lagged: np.ndarray,
    faces: np.ndarray,
    dt: float,
    h: float,
    gravity: float,
    time: float,
    noise_ref: np.ndarray | None = None,
) -> tuple[Contacts, np.ndarray]:
    """Contact candidates of nodes against 3D bodies over one step.

    The 3D counterpart of :func:`~skfem_npfem.bodies.body_contacts` (node
    rows only): a node closer to a body than ``h + 2 (|v| + |V|) dt + g
    dt^2`` gets the row ``gap + n . (du - dU) >= 0``, its slip measured
    against the body along :func:`~skfem_npfem.step.families.tangents` of
    ``n``; Tresca adhesion bounds it by ``adhesion`` times the node's contact
    area (:func:`face_tributary` projected on the body's surface), Coulomb by
    ``mu`` times the lagged normal force, both only where the node was in
    contact in the previous step.

    Parameters
    ----------
    bodies : sequence of RigidPlane or BodyOfRevolution
    x, v : ndarray (n, 3)
        Node positions and velocities at the start of the step.
    fixed, v_prescribed : ndarray (n, 3)
        Prescribed dofs and their velocities.
    lagged : ndarray (n, n_bodies)
        Normal force of each body on the node in the previous step, N.
    faces : ndarray (3, nf)
        Boundary faces of the step's mesh (:func:`boundary_faces`).
    dt, h, gravity, time : float
        Step (s), spacing (m), gravity (m/s^2), time at the start (s).
    noise_ref : ndarray (m, n_bodies), optional
        Forces that set the noise level of ``lagged`` (default ``lagged``).

    Returns
    -------
    Contacts
        Candidates (``node`` indexes the given nodes), with ``slip_offset``.
    ndarray (nc,) int
        The body of each candidate.
    """
    noise_ref = lagged if noise_ref is None else noise_ref
    du_pres = np.where(fixed, v_prescribed * dt, 0.0)
    speed = np.linalg.norm(v, axis=1)
    parts, ids = [], []
    for b_id, body in enumerate(bodies):
        dU = body.velocity * dt
        reach = h + 2.0 * (speed + float(np.linalg.norm(body.velocity))) * dt
        reach = reach + gravity * dt**2
        near = _near3(body, x, time, reach)
        dist, normal, _ = body.signed_distance(x[near], time)
        keep = dist < reach[near]
        cand, dist, normal = near[keep], dist[keep], normal[keep]
        normal = body.corner_normals(x[cand], normal, time)
        free = ~np.all(fixed[cand] | (np.abs(normal) == 0.0), axis=1)
        cand, dist, normal = cand[free], dist[free], normal[free]
        rel = du_pres[cand] - dU
        tang = _tangents(normal) if cand.size else np.zeros((0, 2, 3))
        lam = lagged[cand, b_id]
        touching = lam > 1e-8 * np.max(np.abs(noise_ref[:, b_id]), initial=0.0)
        if body.adhesion > 0:
            across = np.zeros_like(x)
            across[cand] = normal
            area = face_tributary(x, faces, across)[cand]
            bound = np.where(touching, body.adhesion * area, 0.0)
        else:
            bound = np.where(touching, body.mu * lam, 0.0)
        parts.append(
            Contacts(
                node=cand,
                normal=normal,
                gap=np.maximum(dist, 0.0) + np.sum(rel * normal, axis=1),
                mu_lambda=bound,
                slip_offset=np.einsum("ckd,cd->ck", tang, rel),
            )
        )
        ids.append(np.full(cand.size, b_id))
    if not parts:
        return Contacts.empty(3), np.zeros(0, int)
    return Contacts.concat(parts), np.concatenate(ids)


def solid_loads(
    bodies: Sequence[SolidBody],
    contacts: Contacts,
    body_ids: np.ndarray,
    lambda_n: np.ndarray,
    lambda_t: np.ndarray,
    x: np.ndarray,
    time: float,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Force (3,) and moment (3,) that the soil exerts on each 3D body, N and N m.

    The contact force on a node is ``n lambda_n + sum_k t_k lambda_t,k``
    (:func:`~skfem_npfem.step.families.tangents` of ``n``); the body gets the
    opposite.  The moment is about the body's reference point at ``time``,
    from the node positions ``x``.
    """
    n = contacts.normal
    f = -n * lambda_n[:, None]
    if lambda_t.size and contacts.size:
        f -= np.einsum("ckd,ck->cd", _tangents(n), lambda_t)
    out = []
    for b_id, body in enumerate(bodies):
        sel = body_ids == b_id
        force = f[sel].sum(axis=0) if np.any(sel) else np.zeros(3)
        r = contacts.subset(sel).points(x) - body.reference_at(time)
        moment = np.cross(r, f[sel]).sum(axis=0) if np.any(sel) else np.zeros(3)
        out.append((force, moment))
    return out
