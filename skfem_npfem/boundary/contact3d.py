"""Contact of 3D rigid bodies with the particles, found every step.

What the 3D bodies need beside :mod:`.contact` (whose
:func:`~skfem_npfem.boundary.contact.body_contacts` gives their node rows; no
corner rows): the mesh's boundary faces and the nodes' contact areas, the
tetrahedra that span a body and the loads the bodies take.  See :mod:`.solid`
for how these enter the step.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .body import _ON_OUTLINE
from .plane import RigidPlane
from .revolution import BodyOfRevolution

__all__ = [
    "boundary_faces",
    "face_tributary",
    "spanning_tetrahedra",
]

#: Depth, as a fraction of an element's longest edge, beyond which a probe of
#: the element inside a body makes it span the body (a flat face between
#: nodes on a curved surface cuts into it by its sagitta, h^2 / (8 R)).
_SPAN_DEPTH = 0.05

SolidBody = RigidPlane | BodyOfRevolution


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


def spanning_tetrahedra(
    bodies: Sequence[SolidBody], x: np.ndarray, t: np.ndarray, time: float
) -> np.ndarray:
    """Tetrahedra (4, ne) of nodes ``x`` that span a body at ``time`` (ne,) bool.

    An element spans a body when one of its probes -- the centroid, the six
    edge midpoints and the four face centroids -- is inside the body deeper
    than ``_SPAN_DEPTH`` (5 %) of the element's longest edge: a face between
    nodes on a curved surface cuts into it by its sagitta and is kept.
    Bodies thinner than about half an element may be missed (the 2D
    :func:`~skfem_npfem.boundary.spanning_elements` also tests crossing edges).
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
