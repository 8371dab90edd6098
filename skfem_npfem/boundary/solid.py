"""What the 3D rigid bodies share: checked input, interface laws, motion.

The 3D models have two shapes, each moving with a constant velocity vector:

* :class:`~skfem_npfem.RigidPlane` (:mod:`.plane`) -- the half-space behind a
  plane (a plate wider than the soil, a rigid base pushed up);
* :class:`~skfem_npfem.BodyOfRevolution` (:mod:`.revolution`) -- a closed
  profile polygon in ``(r, z)`` turned about an axis (a flat punch, a pile, a
  sphere, a cone with its shaft).
  For a point ``x`` the distance to the surface is the distance of its
  ``(r, z)`` (``r`` the distance to the axis, ``z`` the coordinate along it)
  to the profile's outline, and the normal is ``n_r e_r + n_z e_z``; the
  profile's edges that lie on the axis (``r = 0``) are not surface.

They enter the step as :class:`~skfem_npfem.RigidBody` does in 2D
(:mod:`skfem_npfem.boundary.body`), through :mod:`.contact3d`: the elements that
span a body are dropped (:func:`~skfem_npfem.boundary.spanning_tetrahedra`), the
mesh's nodes get unilateral contact rows against the body at its position at
the start of the step (:func:`~skfem_npfem.boundary.solid_contacts`;
frictionless, Tresca adhesion or Coulomb friction with the normal force lagged
one step), particles that end inside are put back on its surface
(:func:`~skfem_npfem.boundary.project_out_of_bodies`) and the step records the
force and moment vectors of the soil on each body
(:func:`~skfem_npfem.boundary.solid_loads`).  There are no corner rows: an edge
of a body (the rim of a flat punch) can press into a boundary face of the soil
between its nodes; the nodes themselves stay out.

This module holds their common base class and the checks of their parameters.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from .body import _ON_OUTLINE

__all__: list[str] = []


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


def _positive(name: str, value) -> float:
    if isinstance(value, bool) or not (
        isinstance(value, int | float) and math.isfinite(value) and value > 0
    ):
        raise ParameterError(name, value, "a finite length > 0 (m)")
    return float(value)


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
