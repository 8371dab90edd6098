"""Which elements of a step's mesh span a moving rigid body (plane strain, axisymmetry).

Every step of a model with :class:`~skfem_npfem.boundary.RigidBody` bodies drops
the elements that span a body before it assembles anything, so that no element
bridges a body; :func:`spanning_elements` decides which, allowing a sliver at
a corner of the body (docs/theory.md, "Moving rigid bodies").
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..mesh.simplices import orientation, segment_distance
from .body import _ON_OUTLINE, RigidBody

__all__ = ["CLIP_DEPTH", "spanning_elements"]

#: Fraction of an element's mean edge by which a body may cut into a kept
#: element (:func:`spanning_elements`).
CLIP_DEPTH = 0.3


def spanning_elements(
    bodies: Sequence[RigidBody],
    x: np.ndarray,
    t: np.ndarray,
    time: float,
    sliver: float = CLIP_DEPTH,
) -> np.ndarray:
    """Triangles (3, ne) of nodes ``x`` that span a body at ``time`` (ne,) bool.

    An element spans a body when its centroid or an edge midpoint is inside
    the outline, a corner of the outline is inside it, or one of its edges
    crosses an edge of the outline (a triangle may have all three nodes
    outside a thin body and still cover it).  Each test allows a depth of
    ``sliver`` (default :data:`CLIP_DEPTH`) times the element's mean edge:
    soil that flows round a body's corner (the shoulder of a cone, the edge
    of a footing, a vertex of a polygon standing in for a curved body) has a
    node on each face, and the straight edge that joins them cuts the corner
    off.  Dropping that element would open a notch at the corner at every
    step; the soil round it then falls into the notch, several times as far
    as the body moved, and the load on the body collapses for a step
    (measured on the cone: single-step drops of the tip resistance to the
    initial stress, more of them the smaller the step).
    The allowance is for a corner only (an end of the crossed outline edge,
    or a corner inside the element, within that depth of an element edge
    that touches the body): the kept element covers a sliver of the body no
    deeper than that fraction of its size, and a body inside an element, or
    an element reaching across a thin body, is still dropped.  FEM-remap
    with P2 elements passes ``sliver=0``: the mid-edge node of the edge that
    cuts the corner would start inside the body.
    """
    ne = t.shape[1]
    drop = np.zeros(ne, bool)
    xe = x[t]  # (3, ne, 2)
    lo, hi = xe.min(axis=0), xe.max(axis=0)
    for body in bodies:
        a = body.vertices_at(time)
        blo, bhi = a.min(axis=0), a.max(axis=0)
        near = np.flatnonzero(np.all((lo < bhi) & (hi > blo), axis=1))
        if not near.size:
            continue
        p = xe[:, near]  # (3, k, 2)
        q = np.roll(p, -1, axis=0)
        depth = sliver * np.linalg.norm(q - p, axis=-1).mean(axis=0)  # (k,)
        probes = np.concatenate([p.mean(axis=0)[None], 0.5 * (p + q)])
        dist, _, _ = body.signed_distance(
            np.concatenate([probes, p]).reshape(-1, 2), time
        )
        dist = dist.reshape(7, -1)
        hit = np.any(dist[:4] < -depth, axis=0)
        # Proper crossings of element edges (p, q) with outline edges (a, b),
        # except where an end of the outline edge is within the depth of the
        # element edge (a clipped corner; an element edge across a thin body
        # crosses edges whose ends are far).  An end within the outline
        # tolerance of the other line counts as on it (no crossing): nodes on
        # a sloping face are collinear with it only up to rounding.
        P, Q = p[:, :, None, :], q[:, :, None, :]  # (3, k, 1, 2)
        b = np.roll(a, -1, axis=0)
        near_line = _ON_OUTLINE * body.size
        A, B = a[None, None], b[None, None]  # (1, 1, m, 2)
        o1, o2 = orientation(P, Q, A), orientation(P, Q, B)
        o3, o4 = orientation(A, B, P), orientation(A, B, Q)
        t12 = near_line * np.linalg.norm(Q - P, axis=-1)  # (3, k, 1)
        t34 = near_line * np.linalg.norm(B - A, axis=-1)  # (1, 1, m)
        cross = _opposite(o1, o2, t12) & _opposite(o3, o4, t34)
        corner = segment_distance(A, P, Q)  # (3, k, m): outline vertex a_j
        end = np.minimum(corner, np.roll(corner, -1, axis=2))  # a_j or b_j
        hit |= np.any(cross & (end > depth[None, :, None]), axis=(0, 2))
        # A corner of the outline inside an element, unless it is within the
        # depth of an edge that touches the body: one that crosses the outline,
        # or a chord with both ends within the depth of it.  (A body inside an
        # element touches none of its edges.)
        on = np.abs(dist[4:]) <= depth  # (3, k)
        touch = (on & np.roll(on, -1, axis=0)) | np.any(cross, axis=2)  # (3, k)
        d0 = p[1] - p[0]
        d1 = p[2] - p[0]
        det = d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0]  # (k,)
        r = a[None, :, :] - p[0][:, None, :]  # (k, m, 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            l1 = (r[..., 0] * d1[:, None, 1] - r[..., 1] * d1[:, None, 0]) / det[
                :, None
            ]
            l2 = (d0[:, None, 0] * r[..., 1] - d0[:, None, 1] * r[..., 0]) / det[
                :, None
            ]
        tiny = 1e-9
        within = (l1 > tiny) & (l2 > tiny) & (l1 + l2 < 1 - tiny)  # (k, m)
        near_edge = corner <= depth[None, :, None]  # (3, k, m)
        clipped = np.any(touch[:, :, None] & near_edge, axis=0)  # (k, m)
        hit |= np.any(within & ~clipped, axis=1)
        drop[near[hit]] = True
    return drop


def _opposite(u: np.ndarray, w: np.ndarray, tol: np.ndarray) -> np.ndarray:
    """``u`` and ``w`` of opposite signs, each farther than ``tol`` from zero."""
    return ((u > tol) & (w < -tol)) | ((u < -tol) & (w > tol))
