"""Moving rigid bodies: polygons pushed through the particles.

A :class:`RigidBody` is a closed polygon (plane strain, or the ``(r, z)``
half-section of a body of revolution in an axisymmetric model) that moves with
a prescribed velocity: a footing, a cone with its shaft, a pipe section.  Every
step of a model with bodies

1. drops the elements of the step's mesh that span a body
   (:func:`~skfem_npfem.boundary.spanning.spanning_elements`: an element whose
   centroid or an edge midpoint is inside, or whose edge crosses the outline,
   deeper than a sliver: an edge that joins the soil on the two faces of a
   corner may cut the corner off);
2. finds the contact candidates of the mesh's nodes against each body at its
   position at the start of the step (:func:`body_contacts`): the node's
   distance to the outline and the outward normal at the closest point; the
   non-penetration row is ``gap + n . (du - dU) >= 0`` with ``dU`` the body's
   displacement over the step, so the soil may leave the body (unilateral);
3. puts particles that ended inside a body back on its outline
   (:func:`project_out_of_bodies`) and reports how deep they were -- the
   ``<name>_penetration`` of the step record, zero when the contact rows held;
4. reports the force and moment the soil exerts on each body
   (:func:`body_loads`).

Interface (one of):

* frictionless (the default);
* Tresca adhesion ``|t| <= adhesion`` (Pa; ``alpha s_u`` for undrained clay):
  the bound of a node is ``adhesion`` times its contact area (half the
  mesh-boundary facets that meet at the node; ``2 pi r`` times that in
  axisymmetry), applied while the node was in contact in the previous step;
* Coulomb friction ``|t| <= mu p`` with the *lagged* normal force of the
  previous step (as the walls: an associated bound in the cone program would
  lift the soil off the body by ``mu |slip|``).  The lag makes friction one
  step late where the contact force changes; docs/theory.md measures its error
  on a block carried by a moving rough belt.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ParameterError
from ..mesh.geometry import tangents
from .contacts import Contacts

if TYPE_CHECKING:
    from ..particles import Particles

__all__ = [
    "RigidBody",
    "body_loads",
    "check_clear",
    "project_out_of_bodies",
    "start_clear",
]

#: Relative tolerance (of a body's size) below which a point counts as on the outline.
_ON_OUTLINE = 1e-9

#: Relative depth (of a body's size) to which a particle may start inside a body
#: (:func:`start_clear`).
START_DEPTH = 1e-6

#: Relative distance (of a body's size) within which a node counts as on a corner.
_ON_CORNER = 1e-6

#: Degrees by which a boundary edge's normal must lie inside a corner's
#: normal cone for a corner row (:func:`corner_contacts`).
_CORNER_MARGIN = 30.0


class _Moving:
    """What the rigid bodies share (2D and 3D): interface, motion, inside test.

    Each body defines its ``size`` and its ``signed_distance(x, t)``.
    """

    velocity: np.ndarray
    friction_angle: float
    adhesion: float | np.ndarray
    name: str
    reference: np.ndarray

    @property
    def mu(self) -> float:
        """Coulomb friction coefficient ``tan(friction_angle)``."""
        return math.tan(math.radians(self.friction_angle))

    @property
    def interface(self) -> str:
        """``"smooth"``, ``"adhesion"`` or ``"coulomb"``."""
        if np.max(self.adhesion) > 0:
            return "adhesion"
        return "coulomb" if self.friction_angle > 0 else "smooth"

    @property
    def dim(self) -> int:
        """2 (plane strain or axisymmetric models) or 3: the velocity's size."""
        return self.velocity.size

    def displacement(self, t: float) -> np.ndarray:
        """Displacement (d,) from time 0 to ``t``, m."""
        return self.velocity * float(t)

    def reference_at(self, t: float) -> np.ndarray:
        """The moment's reference point (d,) at time ``t``."""
        return self.reference + self.displacement(t)

    def _store(
        self, reference: np.ndarray, example: str, edges: int = 0, **checked: Any
    ) -> None:
        """Store the ``checked`` fields with the checked velocity and interface.

        The moment's reference point is the given one, else ``reference``;
        ``example`` is a name for the error message, ``edges`` as in
        :func:`_interface`.
        """
        d = reference.size
        vel = _vector("velocity", self.velocity, "m/s", d)
        fa, ad = _interface(
            self.friction_angle, self.adhesion, self.name, example, edges
        )
        if self.reference is not None:
            reference = _vector("reference", self.reference, "m", d)
        checked |= {"velocity": vel, "friction_angle": fa, "adhesion": ad}
        for key, value in {**checked, "reference": reference}.items():
            object.__setattr__(self, key, value)

    def contains(self, x: np.ndarray, t: float) -> np.ndarray:
        """Points (n, d) strictly inside the body at time ``t`` (n,) bool."""
        dist, _, _ = self.signed_distance(x, t)
        return dist < -_ON_OUTLINE * self.size


@dataclass(frozen=True)
class RigidBody(_Moving):
    """A rigid polygon moving with a prescribed velocity (2D models).

    Parameters
    ----------
    vertices : array_like (m, 2)
        Corners of the closed outline at time 0, m, in either order (stored
        counter-clockwise); m >= 3, no repeated closing vertex needed.
    velocity : array_like (2,)
        Constant velocity, m/s (static models: per unit of pseudo-time).
    friction_angle : float
        Coulomb interface friction angle, degrees, in [0, 90).
    adhesion : float or array_like (m,)
        Tresca interface strength ``alpha s_u``, Pa, >= 0; or one per edge
        (edge ``j`` from corner ``j`` to ``j + 1`` as given: a cone with a
        smooth shaft).  At most one of ``friction_angle`` and ``adhesion``
        may be > 0; both 0: frictionless.
    name : str
        Label: the step record's keys start with it (``<name>_force_y``).
    reference : array_like (2,), optional
        Point about which the moment is reported, at time 0 (default: the
        centroid of the vertices).

    Raises
    ------
    ParameterError
        For vertices that are not a finite (m >= 3, 2) array enclosing an area,
        a velocity that is not a finite 2-vector, a friction angle outside
        [0, 90), a negative or non-finite adhesion, both interface laws, or a
        name that is not a word.

    Examples
    --------
    >>> foot = RigidBody([[-0.5, 0.0], [0.5, 0.0], [0.5, 1.0], [-0.5, 1.0]],
    ...                  velocity=[0.0, -0.1], name="footing")
    >>> foot.interface, foot.vertices_at(2.0)[0].tolist()
    ('smooth', [-0.5, -0.2])
    >>> d, n, _ = foot.signed_distance(np.array([[0.0, -0.1], [0.0, 0.5]]), 0.0)
    >>> d.round(3).tolist(), n[0].tolist()
    ([0.1, -0.5], [0.0, -1.0])
    """

    vertices: np.ndarray
    velocity: np.ndarray = (0.0, 0.0)
    friction_angle: float = 0.0
    adhesion: float = 0.0
    name: str = "body"
    reference: np.ndarray | None = None

    def __post_init__(self) -> None:
        v, ccw = _polygon("vertices", self.vertices, "corners", " (2D models only)")
        edges = v.shape[0] if ccw else -v.shape[0]
        self._store(v.mean(axis=0), "footing", edges, vertices=v)

    @property
    def size(self) -> float:
        """Largest extent of the outline, m."""
        return float(np.ptp(self.vertices, axis=0).max())

    def vertices_at(self, t: float) -> np.ndarray:
        """The outline's corners (m, 2) at time ``t``."""
        return self.vertices + self.displacement(t)

    def bounds_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Bounding box (lo, hi) of the outline at time ``t``, each (2,)."""
        v = self.vertices_at(t)
        return v.min(axis=0), v.max(axis=0)

    def signed_distance(
        self, x: np.ndarray, t: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance of points from the outline at time ``t``, negative inside.

        Returns
        -------
        dist : ndarray (n,)
            Signed distance, m (positive outside).
        normal : ndarray (n, 2)
            Unit outward normal at the closest point (from the closest point
            towards an outside point; the edge's normal on the outline).
        closest : ndarray (n, 2)
            Closest point of the outline.
        """
        x = np.asarray(x, float).reshape(-1, 2)
        a = self.vertices_at(t)
        b = np.roll(a, -1, axis=0)
        ab = b - a
        ap = x[:, None, :] - a[None]
        s = np.clip(np.einsum("nmk,mk->nm", ap, ab) / np.sum(ab * ab, axis=1), 0, 1)
        c = a[None] + s[..., None] * ab[None]
        d2 = np.sum((x[:, None, :] - c) ** 2, axis=2)
        k = np.argmin(d2, axis=1)
        rows = np.arange(x.shape[0])
        closest = c[rows, k]
        dist = np.sqrt(d2[rows, k])
        # Crossing number: odd -> inside.
        ya, yb = a[:, 1][None], b[:, 1][None]
        straddle = (ya > x[:, 1:2]) != (yb > x[:, 1:2])
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = a[:, 0][None] + (x[:, 1:2] - ya) * (ab[:, 0] / ab[:, 1])[None]
        inside = np.count_nonzero(straddle & (x[:, 0:1] < xc), axis=1) % 2 == 1
        edge_n = np.stack([ab[:, 1], -ab[:, 0]], axis=1) / np.linalg.norm(
            ab, axis=1, keepdims=True
        )
        # On the outline: the mean normal of the edges there (a corner's
        # bisector, the limit of the closest-point direction around it).
        tol = _ON_OUTLINE * self.size
        on = d2 <= tol * tol
        normal = on.astype(float) @ edge_n
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
        far = dist > tol
        sign = np.where(inside, -1.0, 1.0)
        normal[far] = sign[far, None] * (x[far] - closest[far]) / dist[far, None]
        return sign * dist, normal, closest

    def adhesion_at(self, x: np.ndarray, t: float) -> np.ndarray | float:
        """Adhesion (Pa) of the edge closest to each point (n,), or the scalar."""
        if np.ndim(self.adhesion) == 0:
            return self.adhesion
        a = self.vertices_at(t)
        ab = np.roll(a, -1, axis=0) - a
        ap = np.asarray(x, float).reshape(-1, 2)[:, None, :] - a[None]
        s = np.clip(np.einsum("nmk,mk->nm", ap, ab) / np.sum(ab * ab, axis=1), 0, 1)
        d2 = np.sum((ap - s[..., None] * ab[None]) ** 2, axis=2)
        return self.adhesion[np.argmin(d2, axis=1)]


def _polygon(name: str, value, corners: str, note: str = "") -> tuple[np.ndarray, bool]:
    """A closed polygon (m >= 3, 2) enclosing an area, stored counter-clockwise.

    Returns the corners (a repeated closing corner dropped) and whether they
    were given counter-clockwise.
    """
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(name, value, f"an array (m, 2) of {corners}") from None
    if v.ndim != 2 or v.shape[1] != 2 or not np.all(np.isfinite(v)):
        raise ParameterError(
            name, getattr(v, "shape", v), f"a finite array (m, 2) of {corners}{note}"
        )
    if v.shape[0] > 3 and np.allclose(v[0], v[-1]):
        v = v[:-1]
    area = 0.5 * float(
        np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1])
    )
    size = float(np.ptp(v, axis=0).max()) if v.shape[0] else 0.0
    if v.shape[0] < 3 or not abs(area) > 1e-12 * size**2:
        raise ParameterError(
            name,
            f"{v.shape[0]} corners enclosing an area of {abs(area):g} m^2",
            "at least 3 corners enclosing a non-zero area",
        )
    return (v[::-1] if area < 0 else v), area > 0


def _interface(
    friction_angle, adhesion, name, example: str, edges: int = 0
) -> tuple[float, float | np.ndarray]:
    """The checked interface law of a body and its name.

    ``edges``: the adhesion may be one stress per edge (as :func:`_adhesion`);
    0: one stress (the 3D bodies).
    """
    fa = friction_angle
    if isinstance(fa, bool) or not (
        isinstance(fa, int | float) and math.isfinite(fa) and 0.0 <= fa < 90.0
    ):
        raise ParameterError("friction_angle", fa, "degrees in [0, 90)")
    ad = _adhesion(adhesion, edges)
    if fa > 0 and np.max(ad) > 0:
        raise ParameterError(
            "adhesion",
            ad,
            "0 when friction_angle > 0 (choose Coulomb friction or Tresca adhesion)",
        )
    if not (isinstance(name, str) and name.isidentifier()):
        raise ParameterError(
            "name", name, f"a word (letters, digits, _), e.g. {example!r}"
        )
    return float(fa), ad


def _adhesion(value, m: int) -> float | np.ndarray:
    """A finite stress >= 0, or one per edge (``m`` edges; ``-m``: reversed).

    ``m = 0``: one stress only.
    """
    if np.ndim(value) == 0 or not m:
        if isinstance(value, bool) or not (
            isinstance(value, int | float | np.floating)
            and math.isfinite(value)
            and value >= 0.0
        ):
            raise ParameterError("adhesion", value, "a finite stress >= 0 (Pa)")
        return float(value)
    try:
        ad = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        ad = np.full(0, np.nan)
    n = abs(m)
    if ad.shape != (n,) or not np.all(np.isfinite(ad)) or np.any(ad < 0):
        raise ParameterError(
            "adhesion",
            getattr(ad, "shape", value),
            f"a finite stress >= 0 (Pa), or one per edge ({n} values, edge j "
            "from corner j to corner j + 1)",
        )
    if m < 0:  # corners reversed to counter-clockwise: edge j is edge n-2-j
        ad = ad[(n - 2 - np.arange(n)) % n]
    return ad


def _vector(name: str, value, what: str, size: int) -> np.ndarray:
    """A finite vector of ``size`` components."""
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(name, value, f"a finite vector of size {size}") from None
    if v.shape != (size,) or not np.all(np.isfinite(v)):
        raise ParameterError(name, value, f"a finite vector of size {size} ({what})")
    return v


def _near(body, x: np.ndarray, t: float, reach: float | np.ndarray):
    """Indices of points within ``reach`` of the body's bounding box (2D or 3D)."""
    lo, hi = body.bounds_at(t)
    r = np.asarray(reach)[..., None] if np.ndim(reach) else reach
    return np.flatnonzero(np.all((x > lo - r) & (x < hi + r), axis=1))


def project_out_of_bodies(
    bodies: Sequence[RigidBody],
    x: np.ndarray,
    v: np.ndarray,
    time: float,
    beyond: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Put points that are inside a body at ``time`` back on its outline.

    Only points deeper than ``beyond`` (m; 0: all inside) move.

    The velocity loses its component into the body (relative to the body's
    velocity).  2D and 3D: the bodies are :class:`RigidBody` objects, or
    :class:`~skfem_npfem.RigidPlane` and :class:`~skfem_npfem.BodyOfRevolution`
    ones (points (n, 3)).

    Returns
    -------
    x, v : ndarray (n, d)
        Projected positions and velocities (copies if anything moved).
    depth : ndarray (n_bodies,)
        Deepest point inside each body before the projection, m (0: none).
    """
    depth = np.zeros(len(bodies))
    for b_id, body in enumerate(bodies):
        near = _near(body, x, time, 0.0)
        if not near.size:
            continue
        dist, normal, closest = body.signed_distance(x[near], time)
        inside = dist < -beyond
        if not np.any(inside):
            continue
        idx = near[inside]
        depth[b_id] = float(-dist[inside].min())
        x, v = x.copy(), v.copy()
        x[idx] = closest[inside]
        n = normal[inside]
        vn = np.sum((v[idx] - body.velocity) * n, axis=1)
        v[idx] -= np.minimum(vn, 0.0)[:, None] * n
    return x, v, depth


def body_loads(
    bodies: Sequence[Any],
    contacts: Contacts,
    body_ids: np.ndarray,
    lambda_n: np.ndarray,
    lambda_t: np.ndarray,
    x: np.ndarray,
    time: float,
) -> list[tuple[np.ndarray, float | np.ndarray]]:
    """Force (d,) and moment that the soil exerts on each body, N (per m) and N m.

    The contact force on a node is ``n lambda_n + t lambda_t`` (in 3D ``n
    lambda_n + sum_k t_k lambda_t,k``, :func:`~skfem_npfem.mesh.geometry.tangents`
    of ``n``); the body gets the opposite.  The moment is about
    :meth:`RigidBody.reference_at` ``time``, from the node positions ``x``
    (nodes of ``contacts``): counter-clockwise positive in 2D, a vector (3,)
    in 3D.
    """
    n = contacts.normal
    d = x.shape[1]
    if d == 2:
        tang = np.stack([-n[:, 1], n[:, 0]], axis=1)
        lt = lambda_t[:, 0] if lambda_t.size else np.zeros(n.shape[0])
        f = -(n * lambda_n[:, None] + tang * lt[:, None])
    else:
        f = -n * lambda_n[:, None]
        if lambda_t.size and contacts.size:
            f -= np.einsum("ckd,ck->cd", tangents(n), lambda_t)
    out = []
    for b_id, body in enumerate(bodies):
        sel = body_ids == b_id
        force = f[sel].sum(axis=0) if np.any(sel) else np.zeros(d)
        r = contacts.subset(sel).points(x) - body.reference_at(time)
        if d == 2:
            moment = float(np.sum(r[:, 0] * f[sel, 1] - r[:, 1] * f[sel, 0]))
        else:
            moment = np.cross(r, f[sel]).sum(axis=0) if np.any(sel) else np.zeros(3)
        out.append((force, moment))
    return out


def check_clear(
    bodies: Sequence[RigidBody], x: np.ndarray, time: float, tolerance: float
) -> None:
    """Refuse particles deeper than ``tolerance`` inside a body at ``time``.

    2D and 3D bodies alike (as :func:`project_out_of_bodies`).

    Raises
    ------
    ParameterError
        Naming the body, the number of particles inside and the deepest.
    """
    for body in bodies:
        near = _near(body, x, time, 0.0)
        if not near.size:
            continue
        dist = body.signed_distance(x[near], time)[0]
        inside = dist < -tolerance
        if np.any(inside):
            raise ParameterError(
                f"body {body.name!r}",
                f"{int(inside.sum())} particle(s) inside it at t = {time:g} s "
                f"(deepest {float(-dist.min()):.3g} m)",
                "a body that starts clear of the soil (touching is fine): move "
                "its vertices or remove the particles it covers",
            )


def start_clear(bodies: Sequence[Any], particles: Particles) -> Particles:
    """The particles a run starts from, clear of the bodies at time 0.

    A particle deeper than :data:`START_DEPTH` times a body's size inside it
    is refused (:func:`check_clear`); one inside by less, but by more than the
    outline's tolerance (``1e-9`` of the size), is put on the outline
    (:func:`project_out_of_bodies`): left there, the elements that join it to
    the soil would span the body and the first step drop them (on the cone, a
    particle ``1e-7`` of its size inside the shaft took a third of its force).
    """
    x, v = particles.x, particles.v
    for body in bodies:
        check_clear([body], x, 0.0, START_DEPTH * body.size)
        x, v, _ = project_out_of_bodies([body], x, v, 0.0, _ON_OUTLINE * body.size)
    if x is particles.x and v is particles.v:
        return particles
    return particles.replace(x=x, v=v)
