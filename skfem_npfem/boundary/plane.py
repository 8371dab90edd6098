"""A moving rigid plane in 3D models: :class:`RigidPlane`.

The body is the half-space behind the plane; see :mod:`.solid` for what the
3D bodies share and how they enter the step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .body import _Moving, _vector
from .solid import _unit3

__all__ = ["RigidPlane"]


@dataclass(frozen=True)
class RigidPlane(_Moving):
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
        point = _vector("point", self.point, "m", 3)
        normal = _unit3("normal", self.normal)
        self._store(point.copy(), "punch", point=point, normal=normal)

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
