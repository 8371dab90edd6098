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
(:mod:`skfem_npfem.boundary.body`): the elements that span a body are dropped
(:func:`~skfem_npfem.boundary.spanning_tetrahedra`), the mesh's nodes get
unilateral contact rows against the body at its position at the start of the
step (:func:`~skfem_npfem.boundary.body_contacts`;
frictionless, Tresca adhesion or Coulomb friction with the normal force lagged
one step), particles that end inside are put back on its surface
(:func:`~skfem_npfem.boundary.project_out_of_bodies`) and the step records the
force and moment vectors of the soil on each body
(:func:`~skfem_npfem.boundary.body_loads`).  There are no corner rows: an edge
of a body (the rim of a flat punch) can press into a boundary face of the soil
between its nodes; the nodes themselves stay out.

Their common base class is :class:`~skfem_npfem.boundary.body.RigidBody`'s;
this module holds the checks of their parameters that 2D bodies do not need.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from .body import _vector

__all__: list[str] = []


def _unit3(name: str, value) -> np.ndarray:
    """A finite non-zero 3-vector, normalised."""
    v = _vector(name, value, "a direction", 3)
    norm = float(np.linalg.norm(v))
    if not norm > 0.0:
        raise ParameterError(name, value, "a non-zero direction (3 components)")
    return v / norm


def _positive(name: str, value) -> float:
    if isinstance(value, bool) or not (
        isinstance(value, int | float) and math.isfinite(value) and value > 0
    ):
        raise ParameterError(name, value, "a finite length > 0 (m)")
    return float(value)
