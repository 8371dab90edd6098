"""Geometry of simplices: volumes, circumradii, quality, faces and boundaries.

The measures the alpha shape (:mod:`.delaunay`) decides with, vectorised over
all simplices of a triangulation (triangles in 2D, tetrahedra in 3D).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import connected_components

# Volume of the regular simplex inscribed in a sphere of unit radius:
# 3*sqrt(3)/4 for the equilateral triangle, 8*sqrt(3)/27 for the regular tet.
_REGULAR_VOLUME = {2: 3.0 * math.sqrt(3.0) / 4.0, 3: 8.0 * math.sqrt(3.0) / 27.0}


def orientation(o: np.ndarray, u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Twice the signed area of the triangles ``o u w`` (broadcast, ``(..., 2)``).

    Positive when ``w`` lies to the left of the directed line ``o -> u``.

    Examples
    --------
    >>> float(orientation(np.zeros(2), np.array([1.0, 0.0]), np.array([0.0, 1.0])))
    1.0
    """
    left = (u[..., 0] - o[..., 0]) * (w[..., 1] - o[..., 1])
    return left - (u[..., 1] - o[..., 1]) * (w[..., 0] - o[..., 0])


def segment_distance(x: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Distance of points ``x`` from the segments ``p q`` (broadcast, ``(..., d)``).

    Examples
    --------
    >>> float(segment_distance(np.array([2.0, 1.0]), np.zeros(2), np.array([1.0, 0.0])))
    1.4142135623730951
    """
    d = q - p
    s = np.sum((x - p) * d, axis=-1) / np.maximum(np.sum(d * d, axis=-1), 1e-300)
    s = np.clip(s, 0.0, 1.0)
    return np.linalg.norm(x - (p + s[..., None] * d), axis=-1)


def _face_table(d: int) -> NDArray[np.intp]:
    """Local vertex indices of the ``d + 1`` faces of a simplex, outward ordered.

    Row ``j`` is the face opposite vertex ``j``.  For a positively oriented simplex
    the remaining vertices in increasing order give an outward face when ``j`` is
    even and an inward one when ``j`` is odd, so the first two are swapped then.
    """
    rows = []
    for j in range(d + 1):
        face = [k for k in range(d + 1) if k != j]
        if j % 2 == 1:
            face[0], face[1] = face[1], face[0]
        rows.append(face)
    return np.array(rows, dtype=np.intp)


_FACES = {2: _face_table(2), 3: _face_table(3)}


def _simplex_geometry(
    x: NDArray[np.float64], s: NDArray[np.intp], vol_tol: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Signed volumes and circumradii of simplices ``s``.

    The circumradius is ``inf`` where ``|volume| <= vol_tol``.
    """
    d = x.shape[1]
    e = x[s[:, 1:]] - x[s[:, :1]]  # (ne, d, d) edge vectors from vertex 0
    if d == 2:
        det = e[:, 0, 0] * e[:, 1, 1] - e[:, 0, 1] * e[:, 1, 0]
        # R = abc / (4 A) with 2 A = |det|
        third = e[:, 1] - e[:, 0]
        num = (
            np.linalg.norm(e[:, 0], axis=1)
            * np.linalg.norm(e[:, 1], axis=1)
            * np.linalg.norm(third, axis=1)
        )
        den = 2.0 * np.abs(det)
        signed = det / 2.0
    else:
        a, b, c = e[:, 0], e[:, 1], e[:, 2]
        bxc, cxa, axb = np.cross(b, c), np.cross(c, a), np.cross(a, b)
        det = np.einsum("ij,ij->i", a, bxc)
        # Circumcentre relative to vertex 0 (closed form of E c = |E|^2 / 2):
        # c = (|a|^2 b x c + |b|^2 c x a + |c|^2 a x b) / (2 a . (b x c))
        sq = np.einsum("ijk,ijk->ij", e, e)
        centre = sq[:, 0, None] * bxc + sq[:, 1, None] * cxa + sq[:, 2, None] * axb
        num = np.linalg.norm(centre, axis=1)
        den = 2.0 * np.abs(det)
        signed = det / 6.0
    ok = np.abs(signed) > vol_tol
    radius = np.full(s.shape[0], np.inf)
    np.divide(num, den, out=radius, where=ok)
    return signed, radius


def _quality(
    vol: NDArray[np.float64], radius: NDArray[np.float64], d: int
) -> NDArray[np.float64]:
    """Volume over that of the regular simplex with the same circumradius."""
    q = np.zeros_like(vol)
    ok = np.isfinite(radius) & (radius > 0.0)
    q[ok] = vol[ok] / (_REGULAR_VOLUME[d] * radius[ok] ** d)
    return q


def _group_rows(
    faces: NDArray[np.intp],
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Group facets with the same vertex set.

    Returns, per row, the group id, and the number of rows in every group.
    """
    m = faces.shape[0]
    if m == 0:
        return np.empty(0, dtype=np.intp), np.empty(0, dtype=np.intp)
    key = np.sort(faces, axis=1)
    order = np.lexsort(key.T[::-1])
    ks = key[order]
    new = np.ones(m, dtype=bool)
    new[1:] = np.any(ks[1:] != ks[:-1], axis=1)
    gid = np.cumsum(new) - 1
    inverse = np.empty(m, dtype=np.intp)
    inverse[order] = gid
    return inverse, np.bincount(gid)


def _shared_face_pairs(
    inverse: NDArray[np.intp], owner: NDArray[np.intp]
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Owners ``(a, b)`` of the facet groups that have two members."""
    order = np.argsort(inverse, kind="stable")
    g = inverse[order]
    pair = np.flatnonzero(g[1:] == g[:-1])
    return owner[order[pair]], owner[order[pair + 1]]


def _facet_groups(
    simplices: NDArray[np.intp],
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
    """Facets of ``simplices`` with their owners, group ids and group sizes."""
    ne, d1 = simplices.shape
    faces = simplices[:, _FACES[d1 - 1]].reshape(-1, d1 - 1)
    owner = np.repeat(np.arange(ne), d1)
    inverse, count = _group_rows(faces)
    return faces, owner, inverse, count


def _open_slivers(
    simplices: NDArray[np.intp], kept: NDArray[np.bool_], groups: tuple | None = None
) -> NDArray[np.bool_]:
    """Slivers (simplices not ``kept``) open to the outside of the complex.

    Slivers connected through shared facets form one (zero-volume) region; it
    is open if any of its slivers has a facet that no other simplex of the
    complex has.  The other slivers are buried in the body.  ``groups``:
    :func:`_facet_groups` of ``simplices``, if already computed.
    """
    if simplices.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    _, owner, inverse, count = groups or _facet_groups(simplices)
    return _open_region(inverse, owner, count[inverse] == 1, ~kept)


def _open_region(
    inverse: NDArray[np.intp],
    owner: NDArray[np.intp],
    exposed_face: NDArray[np.bool_],
    sliver: NDArray[np.bool_],
) -> NDArray[np.bool_]:
    """The slivers whose region (slivers sharing facets) has an exposed facet."""
    ne = sliver.size
    exposed_sliver = np.zeros(ne, dtype=bool)
    exposed_sliver[owner[exposed_face]] = True
    exposed_sliver &= sliver
    if sliver.any():
        a, b = _shared_face_pairs(inverse, owner)
        both = sliver[a] & sliver[b]
        graph = sp.coo_matrix(
            (np.ones(int(both.sum())), (a[both], b[both])), shape=(ne, ne)
        )
        _, label = connected_components(graph, directed=False)
        open_region = np.bincount(label, weights=exposed_sliver) > 0
        exposed_sliver = sliver & open_region[label]
    return exposed_sliver


def _boundary_facets(
    simplices: NDArray[np.intp], kept: NDArray[np.bool_], groups: tuple | None = None
) -> NDArray[np.intp]:
    """Outward-ordered boundary facets of the kept simplices.

    ``simplices`` is the (positively oriented) alpha complex and ``kept`` marks
    the simplices that are meshed; the others are slivers.  A facet of exactly
    one kept simplex is on the boundary if no other simplex of the complex has
    it, or if the other one is a sliver connected (through slivers sharing
    facets) to the boundary of the complex.  Slivers buried in the body therefore
    do not create an internal boundary, and the boundary stays closed.
    ``groups``: :func:`_facet_groups` of ``simplices``, if already computed.
    """
    ne, d1 = simplices.shape
    if ne == 0:
        return np.empty((0, d1 - 1), dtype=np.intp)
    faces, owner, inverse, count = groups or _facet_groups(simplices)
    ng = count.size
    owner_kept = kept[owner]
    n_kept = np.bincount(inverse, weights=owner_kept, minlength=ng)
    exposed_face = count[inverse] == 1
    exposed_sliver = _open_region(inverse, owner, exposed_face, ~kept)
    next_to_exposed_sliver = (
        np.bincount(inverse, weights=exposed_sliver[owner], minlength=ng) > 0
    )
    on_boundary = (
        owner_kept
        & (n_kept[inverse] == 1)
        & (exposed_face | next_to_exposed_sliver[inverse])
    )
    return np.ascontiguousarray(faces[on_boundary])
