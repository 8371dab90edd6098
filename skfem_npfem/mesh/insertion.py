"""Particle insertion on the long edges of a triangulation: mass and momentum kept.

Where the soil stretches (round the shoulder of a pushed body, at a thinning
front) an edge of the particles' triangulation grows beyond the spacing the
particles started with.  :func:`long_edges` picks such edges, at most one per
particle in a pass, and :func:`insert_midpoints` adds a particle at the middle
of each.  A new particle's state comes from the two ends of its edge only:

* **mass**: the midpoint takes the volume the two ends give up when the edge's
  simplices are split in two (each end keeps half of its share of those
  simplices: ``E_ab = sum |T| / (2 (d + 1))`` over the simplices holding the
  edge), at each end's own density ``m / V``.  What the new particle gets,
  its ends lose: the total mass is conserved to round-off.
* **momentum**: the new particle's velocity is the mass-weighted mean of the
  donated momenta; the donors keep their velocities, so the total momentum is
  conserved to round-off (the kinetic energy drops by the donors' velocity
  difference squared times a reduced mass: nothing where the two move alike).
* **intensive state** (stress, plastic strain, pore pressure, strength and
  stiffness factors, displacement since the start): the mean of the two ends,
  which is exact for a field linear along the edge, the fields P1 nodal
  integration represents.  Extensive wall forces are split as the mass is.

Edges across two materials and edges with a prescribed end are left alone.
Nothing else is mapped: every other particle keeps its state bit for bit,
which is the difference from a remeshing FEM that transfers every field at
every remesh (docs/theory.md, "Particle insertion").
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from itertools import combinations

import numpy as np

from ..particles import Particles

__all__ = [
    "Insertion",
    "conservation_errors",
    "disjoint_edges",
    "edge_shares",
    "insert_midpoints",
    "long_edges",
]


@dataclass(frozen=True)
class Insertion:
    """What one insertion (or merging) pass did.

    Attributes
    ----------
    count : int
        Particles added (merging: pairs merged).
    mass_error : float
        ``|sum m_after - sum m_before| / sum m_before``.
    momentum_error : float
        ``|sum m v after - sum m v before| / sum |m v| before`` (0 at rest).
    """

    count: int = 0
    mass_error: float = 0.0
    momentum_error: float = 0.0


def edge_shares(
    x: np.ndarray, simplices: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The edges of ``simplices`` with the volume their split frees, and nodal volumes.

    Parameters
    ----------
    x : ndarray (N, d)
        Positions.
    simplices : ndarray (ne, d + 1)
        Global particle indices of the simplices.

    Returns
    -------
    edges : ndarray (n_edges, 2)
        Unique edges, lower index first.
    share : ndarray (n_edges,)
        ``sum |T| / (2 (d + 1))`` over the simplices holding the edge: what each
        end gives up when the edge is split at its midpoint.
    volume : ndarray (N,)
        Lumped nodal volumes ``sum |T| / (d + 1)`` (0 off the mesh).

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> e, s, v = edge_shares(x, np.array([[0, 1, 2]]))
    >>> e.tolist(), s.round(4).tolist(), v.round(4).tolist()
    ([[0, 1], [0, 2], [1, 2]], [0.0833, 0.0833, 0.0833], [0.1667, 0.1667, 0.1667])
    """
    n, d = x.shape
    t = np.asarray(simplices, dtype=np.intp)
    span = x[t[:, 1:]] - x[t[:, :1]]
    size = np.abs(np.linalg.det(span)) / (2.0 if d == 2 else 6.0)
    volume = np.bincount(t.ravel(), np.repeat(size / (d + 1), d + 1), minlength=n)
    pairs = np.array(list(combinations(range(d + 1), 2)))
    ends = np.sort(t[:, pairs].reshape(-1, 2), axis=1)
    keys = ends[:, 0].astype(np.int64) * n + ends[:, 1]
    unique, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    share = np.bincount(
        inverse, np.repeat(size / (2 * (d + 1)), len(pairs)), minlength=unique.size
    )
    return ends[first], share, volume


def long_edges(
    x: np.ndarray,
    edges: np.ndarray,
    target: np.ndarray,
    ratio: float,
    allowed: np.ndarray | None = None,
    *,
    shorter: bool = False,
) -> np.ndarray:
    """Indices of edges longer than ``ratio`` times their ends' target spacing.

    At most one edge per particle is returned: an edge is taken when it is the
    most stretched (length over target) of the candidates at both its ends,
    ties to the lower index, so a pass never splits two edges of one particle.

    Parameters
    ----------
    x : ndarray (N, d)
    edges : ndarray (n_edges, 2)
    target : ndarray (N,)
        Target spacing of each particle, m; an edge's is the smaller of its
        ends' (with ``shorter``: the larger).
    ratio : float
        Insertion threshold (> 1).
    allowed : ndarray (n_edges,) of bool, optional
        Edges that may be taken (default: all).
    shorter : bool
        The converse, for merging: edges *shorter* than ``ratio`` times the
        larger target of their ends, the shortest first.

    Returns
    -------
    ndarray of int
        Indices into ``edges``, increasing.

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [0.1, 0.0], [2.0, 0.0]])
    >>> e = np.array([[0, 1], [1, 2]])
    >>> long_edges(x, e, np.ones(3), 1.6).tolist()
    [1]
    >>> long_edges(x, e, np.ones(3), 0.4, shorter=True).tolist()
    [0]
    """
    a, b = edges[:, 0], edges[:, 1]
    pick = np.maximum if shorter else np.minimum
    rel = np.linalg.norm(x[b] - x[a], axis=1) / pick(target[a], target[b])
    candidate = rel < ratio if shorter else rel > ratio
    if allowed is not None:
        candidate &= allowed
    return disjoint_edges(edges, -rel if shorter else rel, candidate, x.shape[0])


def disjoint_edges(
    edges: np.ndarray, score: np.ndarray, candidate: np.ndarray, n: int
) -> np.ndarray:
    """Candidate edges that score highest at both their ends (a disjoint set).

    Ties go to the lower index.  Returns indices into ``edges``, increasing.

    Examples
    --------
    >>> e = np.array([[0, 1], [1, 2], [2, 3]])
    >>> disjoint_edges(e, np.array([1.0, 3.0, 2.0]), np.ones(3, bool), 4).tolist()
    [1]
    """
    a, b = edges[:, 0], edges[:, 1]
    idx = np.flatnonzero(candidate)
    if idx.size == 0:
        return idx
    order = idx[np.argsort(-score[idx], kind="stable")]
    rank = np.empty(edges.shape[0], np.intp)
    rank[order] = np.arange(order.size)
    first = np.full(n, order.size, np.intp)
    np.minimum.at(first, a[order], rank[order])
    np.minimum.at(first, b[order], rank[order])
    keep = (first[a[order]] == rank[order]) & (first[b[order]] == rank[order])
    return np.sort(order[keep])


def insert_midpoints(
    p: Particles,
    edges: np.ndarray,
    share: np.ndarray,
    volume: np.ndarray,
    ids: np.ndarray,
    spacing: np.ndarray,
) -> tuple[Particles, Insertion]:
    """Add a particle at the middle of each edge (no particle on two edges).

    Parameters
    ----------
    p : Particles
    edges : ndarray (k, 2)
        The edges to split (:func:`long_edges`), disjoint.
    share : ndarray (k,)
        Each end's volume given up (:func:`edge_shares`), m^d.
    volume : ndarray (N,)
        Nodal volumes of the particles, m^d (> 0 at every edge's ends).
    ids, spacing : ndarray (N,)
        Stable ids and target spacings; the new particles get ids after the
        largest and the smaller spacing of their ends.

    Returns
    -------
    Particles
        The ``N + k`` particles, the new ones last, with ``ids`` and
        ``spacing`` set.
    Insertion
        The count and the conservation errors.
    """
    k = edges.shape[0]
    if k == 0:
        return p.replace(ids=ids, spacing=spacing), Insertion()
    a, b = edges[:, 0], edges[:, 1]
    given_a = p.mass[a] * (share / volume[a])
    given_b = p.mass[b] * (share / volume[b])
    mass = p.mass.copy()
    mass[a] -= given_a
    mass[b] -= given_b
    m_new = given_a + given_b
    wa, wb = given_a / m_new, given_b / m_new
    changes: dict[str, np.ndarray] = {}
    for f in fields(p):
        arr = getattr(p, f.name)
        if arr is None or f.name in ("mass", "ids", "spacing"):
            continue
        if f.name in ("v", "a"):  # momentum (and its rate) by the donated mass
            new = wa[:, None] * arr[a] + wb[:, None] * arr[b]
        elif f.name == "wall_force":  # extensive: split as the mass is
            fa, fb = given_a / p.mass[a], given_b / p.mass[b]
            new = fa[:, None] * arr[a] + fb[:, None] * arr[b]
            arr = arr.copy()
            arr[a] *= (1.0 - fa)[:, None]
            arr[b] *= (1.0 - fb)[:, None]
        elif f.name in ("material", "fixed", "v_prescribed"):
            new = arr[a]  # same material, free (the edges were chosen so)
        else:  # intensive: the midpoint's linear interpolant
            new = 0.5 * (arr[a] + arr[b])
        changes[f.name] = np.concatenate([arr, new.astype(arr.dtype, copy=False)])
    changes["mass"] = np.concatenate([mass, m_new])
    start = int(ids.max(initial=-1)) + 1
    changes["ids"] = np.concatenate([ids, np.arange(start, start + k, dtype=ids.dtype)])
    changes["spacing"] = np.concatenate([spacing, np.minimum(spacing[a], spacing[b])])
    out = p.replace(**changes)
    return out, Insertion(k, *conservation_errors(p, out))


def conservation_errors(before: Particles, after: Particles) -> tuple[float, float]:
    """Relative changes of the total mass and momentum (0 at rest).

    ``|sum m - sum m0| / sum m0`` and ``max |sum m v - sum m0 v0| / sum |m0 v0|``.
    """
    m0 = float(before.mass.sum())
    mom0 = (before.mass[:, None] * before.v).sum(axis=0)
    mom1 = (after.mass[:, None] * after.v).sum(axis=0)
    scale = float(np.abs(before.mass[:, None] * before.v).sum())
    return (
        abs(float(after.mass.sum()) - m0) / m0,
        float(np.abs(mom1 - mom0).max()) / scale if scale > 0 else 0.0,
    )
