"""Contact of rigid bodies with the particles' boundary, found every step.

Two passes: the soil's boundary nodes against the body's faces
(:func:`body_contacts`), and the body's convex corners against the soil's
boundary edges (:func:`corner_contacts`), so that a sharp edge cannot slide
between two nodes.  Contacts are unilateral; see docs/theory.md, "Moving rigid
bodies".
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..mesh.geometry import tangents
from .body import _CORNER_MARGIN, _ON_CORNER, RigidBody, _near
from .contact3d import face_tributary
from .contacts import Contacts

__all__ = [
    "body_contacts",
    "boundary_tributary",
    "corner_contacts",
    "oriented_boundary",
]


def oriented_boundary(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Boundary edges (2, nb) of a 2D triangle mesh, the mesh on their left.

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> oriented_boundary(x, np.array([[0], [2], [1]])).T.tolist()
    [[0, 1], [1, 2], [2, 0]]
    """
    d0 = x[t[1]] - x[t[0]]
    d1 = x[t[2]] - x[t[0]]
    ccw = d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0] > 0
    tt = np.where(ccw, t, t[[0, 2, 1]])
    edges = np.concatenate([tt[[0, 1]], tt[[1, 2]], tt[[2, 0]]], axis=1)
    key = np.sort(edges, axis=0)
    _, inv, counts = np.unique(key, axis=1, return_inverse=True, return_counts=True)
    out = edges[:, counts[inv.reshape(-1)] == 1]
    return out[:, np.lexsort(out[::-1])]


def boundary_tributary(
    x: np.ndarray,
    facets: np.ndarray,
    tangent: np.ndarray | None = None,
    axisymmetric: bool = False,
) -> np.ndarray:
    """Contact area of each node of a 2D mesh: half its boundary edges.

    Parameters
    ----------
    x : ndarray (N, 2)
        Node positions.
    facets : ndarray (2, nb)
        Boundary edges (:func:`oriented_boundary`).
    tangent : ndarray (N, 2), optional
        Unit tangent of the surface a node touches: an edge then counts with
        its length along that tangent (a side edge meeting a flat contact
        face adds nothing).  None: full lengths.
    axisymmetric : bool
        Multiply by ``2 pi r`` (ring area of the ``(r, z)`` half-section).

    Returns
    -------
    ndarray (N,)
        m^2 per m of depth (plane strain) or m^2 (ring); 0 for interior nodes.

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> f = oriented_boundary(x, np.array([[0], [1], [2]]))
    >>> boundary_tributary(x, f).round(3).tolist()
    [1.0, 1.207, 1.207]
    >>> flat = np.tile([1.0, 0.0], (3, 1))
    >>> boundary_tributary(x, f, flat).round(3).tolist()
    [0.5, 1.0, 0.5]
    """
    a, b = facets
    e = x[b] - x[a]
    if tangent is None:
        la = lb = np.linalg.norm(e, axis=1)
    else:
        la = np.abs(np.sum(e * tangent[a], axis=1))
        lb = np.abs(np.sum(e * tangent[b], axis=1))
    if axisymmetric:
        ring = 2.0 * math.pi * 0.5 * (x[a, 0] + x[b, 0])
        la, lb = la * ring, lb * ring
    out = np.bincount(a, weights=0.5 * la, minlength=x.shape[0])
    out += np.bincount(b, weights=0.5 * lb, minlength=x.shape[0])
    return out


def _corner_normals(
    body: RigidBody,
    x: np.ndarray,
    normal: np.ndarray,
    time: float,
    shares: np.ndarray | None = None,
) -> np.ndarray:
    """Normals of nodes on a corner: the faces the soil lies against.

    ``shares`` (m, 2), optional: the soil's boundary next to each node along
    the corner's two faces (:func:`_face_shares`).  A node with soil against
    both faces (the shoulder of a cone with soil on its face and along its
    shaft) takes their normals weighted by those shares: the direction of the
    load of a uniform pressure on it, so the corner node carries each face's
    share along that face's normal (with either normal alone the shaft's
    horizontal pressure leaks into the cone's vertical force: 14 % of it at
    four spacings per cone radius under an isotropic initial stress).
    Otherwise the node has no closest-point direction to go by.  The bisector would
    let the node under a footing's edge slide off diagonally with a fraction
    of its load (measured: the first step of the footing-penetration scene
    at h = B/10 lost 15 % of the load, and the soil under the edge sagged
    away from it for the steps after).  Such a node takes the normal of the
    adjacent face that moves fastest along its own normal (largest ``V .
    n``: the base of a footing pushed down); when both faces move alike (a
    body at rest, a symmetric tip pushed along its axis) it keeps the
    bisector.  A node beyond the corner keeps the corner-to-node direction:
    it is in contact with a face only while it is in front of it.
    """
    V = body.vertices_at(time)
    # A node pushed onto a corner in the previous step sits there to the
    # solver's tolerance, not to round-off.
    tol = _ON_CORNER * body.size
    d2 = np.sum((x[:, None, :] - V[None]) ** 2, axis=2)
    k = np.argmin(d2, axis=1)
    on = np.flatnonzero(d2[np.arange(x.shape[0]), k] <= tol * tol)
    if not on.size:
        return normal
    ab = np.roll(V, -1, axis=0) - V  # edge j: V[j] -> V[j+1]
    edge_n = np.stack([ab[:, 1], -ab[:, 0]], axis=1)
    edge_n /= np.linalg.norm(edge_n, axis=1, keepdims=True)
    k = k[on]
    faces = np.stack([edge_n[k - 1], edge_n[k]], axis=1)  # (m, 2, 2)
    approach = faces @ body.velocity  # (m, 2)
    best = np.argmax(approach, axis=1)
    speed = float(np.linalg.norm(body.velocity))
    use = (approach.max(axis=1) > 0.0) & (
        np.abs(approach[:, 0] - approach[:, 1]) > 1e-9 * speed
    )
    normal = normal.copy()
    normal[on[use]] = faces[use, best[use]]
    if shares is not None:
        w = shares[on]
        both = np.all(w > 0.0, axis=1)
        mixed = np.einsum("mk,mkd->md", w[both], faces[both])
        normal[on[both]] = mixed / np.linalg.norm(mixed, axis=1, keepdims=True)
    return normal


def _face_shares(
    body: RigidBody,
    x: np.ndarray,
    facets: np.ndarray,
    time: float,
    axisymmetric: bool,
) -> np.ndarray:
    """Each node's boundary share along the two faces of its nearest corner.

    For every node (n, 2): the tributary length (ring area / 2 pi in
    axisymmetry, the P1 weight of the node) of the soil's boundary edges at
    the node that run along the face before (column 0) and after (column 1)
    the body's corner nearest to it, within 10 degrees; 0 where none does.
    """
    V = body.vertices_at(time)
    out = np.zeros((x.shape[0], 2))
    if not facets.size:
        return out
    d2 = np.sum((x[:, None, :] - V[None]) ** 2, axis=2)
    k = np.argmin(d2, axis=1)
    ab = np.roll(V, -1, axis=0) - V
    ab /= np.linalg.norm(ab, axis=1, keepdims=True)
    # Directions along each face away from the corner: back along the edge
    # before it, forward along the edge after it.
    away = np.stack([-ab[k - 1], ab[k]], axis=1)  # (n, 2, 2)
    a, b = facets
    for node, other in ((a, b), (b, a)):
        e = x[other] - x[node]
        length = np.linalg.norm(e, axis=1)
        cos = (
            np.einsum("ed,ekd->ek", e, away[node]) / np.maximum(length, 1e-300)[:, None]
        )
        along = cos > math.cos(math.radians(10.0))
        if axisymmetric:
            weight = length * (2.0 * x[node, 0] + x[other, 0]) / 6.0
        else:
            weight = 0.5 * length
        for j in (0, 1):
            out[:, j] += np.bincount(
                node, weights=np.where(along[:, j], weight, 0.0), minlength=x.shape[0]
            )
    return out


def body_contacts(
    bodies: Sequence[Any],
    x: np.ndarray,
    v: np.ndarray,
    fixed: np.ndarray,
    v_prescribed: np.ndarray,
    lagged: np.ndarray,
    facets: np.ndarray,
    dt: float,
    h: float,
    gravity: float,
    time: float,
    noise_ref: np.ndarray | None = None,
    axisymmetric: bool = False,
    corners: bool = False,
) -> tuple[Contacts, np.ndarray]:
    """Contact candidates of nodes against the bodies over one step (2D or 3D).

    A node is a candidate when it is closer to a body than ``h + 2 (|v| +
    |V|) dt + g dt^2`` (it cannot tunnel through within the step).  Its row
    is ``gap + n . (du - dU) >= 0`` with the distance ``gap`` (0 for a node
    already inside), the outward normal ``n`` at the closest point and the
    body's displacement ``dU = V dt``; the slip is measured against the body
    (:attr:`Contacts.slip_offset`; in 3D along
    :func:`~skfem_npfem.mesh.geometry.tangents` of ``n``).  Tresca adhesion
    bounds it by ``adhesion`` times the node's contact area, Coulomb by ``mu``
    times the lagged normal force, both only where the node was in contact in
    the previous step.

    Parameters
    ----------
    bodies : sequence of RigidBody (2D), or of RigidPlane and BodyOfRevolution (3D)
    x, v : ndarray (n, d)
        Node positions and velocities at the start of the step.
    fixed, v_prescribed : ndarray (n, d)
        Prescribed dofs and their velocities.
    lagged : ndarray (n, n_bodies)
        Normal force of each body on the node in the previous step, N.
    facets : ndarray (2, nb) or (3, nf)
        The boundary of the step's mesh, for the contact areas of adhesion:
        its edges in 2D (:func:`oriented_boundary`; :func:`boundary_tributary`
        along the body), its faces in 3D
        (:func:`~skfem_npfem.boundary.contact3d.boundary_faces`;
        :func:`~skfem_npfem.boundary.contact3d.face_tributary` projected on the
        body's surface).
    dt, h, gravity, time : float
        Step (s), spacing (m), gravity (m/s^2), time at the start (s).
    axisymmetric : bool
        Contact areas of rings (2D).
    corners : bool
        Add the candidates of the bodies' corners against the boundary edges
        (2D: :func:`corner_contacts`; ``facets`` must then have the mesh on
        their left, :func:`oriented_boundary`).
    noise_ref : ndarray (m, n_bodies), optional
        Forces that set the noise level of ``lagged`` (default ``lagged``).

    Returns
    -------
    Contacts
        Candidates (``node`` indexes the given nodes).
    ndarray (nc,) int
        The body of each candidate.
    """
    dim = x.shape[1]
    noise_ref = lagged if noise_ref is None else noise_ref
    du_pres = np.where(fixed, v_prescribed * dt, 0.0)
    speed = np.linalg.norm(v, axis=1)
    parts, ids = [], []
    for b_id, body in enumerate(bodies):
        dU = body.velocity * dt
        reach = h + 2.0 * (speed + float(np.linalg.norm(body.velocity))) * dt
        reach = reach + gravity * dt**2
        near = _near(body, x, time, reach)
        dist, normal, _ = body.signed_distance(x[near], time)
        keep = dist < reach[near]
        cand, dist, normal = near[keep], dist[keep], normal[keep]
        if dim == 2:
            shares = _face_shares(body, x, facets, time, axisymmetric)[cand]
            normal = _corner_normals(body, x[cand], normal, time, shares)
        else:
            normal = body.corner_normals(x[cand], normal, time)
        free = ~np.all(fixed[cand] | (np.abs(normal) == 0.0), axis=1)
        cand, dist, normal = cand[free], dist[free], normal[free]
        rel = du_pres[cand] - dU
        if dim == 2:
            tang = np.stack([-normal[:, 1], normal[:, 0]], axis=1)
            slip = np.sum(rel * tang, axis=1)[:, None]
        else:
            tang = tangents(normal) if cand.size else np.zeros((0, 2, 3))
            slip = np.einsum("ckd,cd->ck", tang, rel)
        lam = lagged[cand, b_id]
        touching = lam > 1e-8 * np.max(np.abs(noise_ref[:, b_id]), initial=0.0)
        if np.max(body.adhesion) > 0:
            surface = np.zeros_like(x)
            if dim == 2:
                surface[cand] = tang
                area = boundary_tributary(x, facets, surface, axisymmetric)[cand]
                strength = body.adhesion_at(x[cand], time)
            else:
                surface[cand] = normal
                area = face_tributary(x, facets, surface)[cand]
                strength = body.adhesion
            bound = np.where(touching, strength * area, 0.0)
        else:
            bound = np.where(touching, body.mu * lam, 0.0)
        parts.append(
            Contacts(
                node=cand,
                normal=normal,
                gap=np.maximum(dist, 0.0) + np.sum(rel * normal, axis=1),
                mu_lambda=bound,
                slip_offset=slip,
            )
        )
        ids.append(np.full(cand.size, b_id))
        if corners:
            cc = corner_contacts(body, x, facets, fixed, du_pres, reach, dt, time)
            parts.append(cc)
            ids.append(np.full(cc.size, b_id))
    if not parts:
        return Contacts.empty(dim), np.zeros(0, int)
    return Contacts.concat(parts), np.concatenate(ids)


def corner_contacts(
    body: RigidBody,
    x: np.ndarray,
    edges: np.ndarray,
    fixed: np.ndarray,
    du_prescribed: np.ndarray,
    reach: np.ndarray,
    dt: float,
    time: float,
) -> Contacts:
    """Candidates of the body's convex corners against the soil's boundary edges.

    Node candidates (:func:`body_contacts`) keep the nodes out of the body;
    these keep the body's corners out of the soil: when the soil flows round
    a corner (the edge of a footing) the corner sits between two boundary
    nodes and would otherwise press into the edge that joins them without
    any force (the strip between the last node under the footing and its
    edge carries no load).  The row of a corner ``X`` against the edge ``(a,
    b)`` at its closest point ``x_s = (1 - s) x_a + s x_b`` (``0 < s < 1``)
    is ``gap + n . ((1 - s) du_a + s du_b - dU) >= 0`` with the edge's
    normal ``n`` into the soil, ``gap = n . (x_s - X) >= 0``; its force goes
    to ``a`` and ``b`` in the proportions ``1 - s`` and ``s``.  An edge
    counts when it is within the reach of its nodes and its inward normal
    lies inside the corner's normal cone by at least ``_CORNER_MARGIN``
    degrees from either face normal: the corner, not a face, presses on it.
    An edge nearly parallel to a face is left to the node rows: a straight
    edge cannot fold round the corner, so a row there would pin the node
    beyond the corner to the face's plane and keep the soil beside a footing
    from heaving (measured: the footing's bearing factor then climbs 10-15 %
    above Prandtl within w/B = 0.1).  Frictionless (the corner is a line of
    zero width).

    Parameters
    ----------
    body : RigidBody
    x : ndarray (n, 2)
        Node positions at the start of the step.
    edges : ndarray (2, nb)
        Boundary edges with the mesh on their left (:func:`oriented_boundary`).
    fixed, du_prescribed : ndarray (n, 2)
        Prescribed dofs and their increments over the step.
    reach : ndarray (n,)
        Search distance of each node, m.
    dt, time : float
        Step and time at its start, s.

    Returns
    -------
    Contacts
        With ``partner`` and ``share`` (empty when no corner is near an edge).
    """
    V = body.vertices_at(time)
    t1 = V - np.roll(V, 1, axis=0)
    t2 = np.roll(V, -1, axis=0) - V
    convex = t1[:, 0] * t2[:, 1] - t1[:, 1] * t2[:, 0] > 0
    V, t1, t2 = V[convex], t1[convex], t2[convex]
    empty = Contacts(
        np.zeros(0, int),
        np.zeros((0, 2)),
        np.zeros(0),
        np.zeros(0),
        slip_offset=np.zeros((0, 1)),
        partner=np.zeros(0, int),
        share=np.zeros(0),
    )
    if not V.shape[0] or not edges.size:
        return empty
    a, b = edges
    r = np.maximum(reach[a], reach[b])
    lo, hi = V.min(axis=0), V.max(axis=0)
    emin = np.minimum(x[a], x[b])
    emax = np.maximum(x[a], x[b])
    near = np.flatnonzero(
        np.all((emax > lo - r[:, None]) & (emin < hi + r[:, None]), axis=1)
    )
    if not near.size:
        return empty
    a, b, r = a[near], b[near], r[near]
    e = x[b] - x[a]  # (k, 2)
    length = np.linalg.norm(e, axis=1)
    n_in = np.stack([-e[:, 1], e[:, 0]], axis=1) / length[:, None]
    rel = V[None, :, :] - x[a][:, None, :]  # (k, m, 2)
    s = np.einsum("kmd,kd->km", rel, e) / (length**2)[:, None]
    xs = x[a][:, None, :] + s[..., None] * e[:, None, :]
    dist = np.linalg.norm(xs - V[None], axis=2)
    gap = np.einsum("kmd,kd->km", xs - V[None], n_in)
    tol = 1e-9
    ok = (s > tol) & (s < 1 - tol) & (dist < r[:, None]) & (gap > -tol * body.size)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 /= np.linalg.norm(t2, axis=1, keepdims=True)
    margin = math.sin(math.radians(_CORNER_MARGIN))
    ok &= (n_in @ t1.T > margin) & (n_in @ t2.T < -margin)
    ok &= ~(np.all(fixed[a], axis=1) & np.all(fixed[b], axis=1))[:, None]
    ke, km = np.nonzero(ok)
    if not ke.size:
        return empty
    sk = s[ke, km]
    nk = n_in[ke]
    du = (1 - sk)[:, None] * du_prescribed[a[ke]] + sk[:, None] * du_prescribed[b[ke]]
    g = np.maximum(gap[ke, km], 0.0) + np.sum((du - body.velocity * dt) * nk, axis=1)
    return Contacts(
        node=a[ke],
        normal=nk,
        gap=g,
        mu_lambda=np.zeros(ke.size),
        slip_offset=np.zeros((ke.size, 1)),
        partner=b[ke],
        share=sk,
    )
