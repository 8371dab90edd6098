"""Boundaries: rigid plane walls with frictionless or lagged-Coulomb contact.

Fixed and roller supports and prescribed displacements are particle flags
(:attr:`Particles.fixed`, :attr:`Particles.v_prescribed`); this module holds the
rigid walls that particles may touch and leave.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError

__all__ = ["RigidWall", "floor", "wall_x"]


@dataclass(frozen=True)
class RigidWall:
    """A fixed rigid plane ``(x - point) . normal >= 0`` (the body side).

    Contact is unilateral (gap closes, never penetrates, the wall only pushes).
    Friction is Coulomb with the *lagged* normal force of the previous step
    (pitfall 8: associated friction would lift nodes off by ``mu |slip|``).

    Parameters
    ----------
    point : array_like (d,)
        A point on the wall, m.
    normal : array_like (d,)
        Normal pointing into the body (normalised here).
    friction_angle : float
        Wall friction angle, degrees, in [0, 90); 0 is frictionless (a symmetry
        plane).

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
