"""Local refinement of a particle lattice where an indicator concentrates.

An adaptive analysis solves on a lattice, measures where its answer is made
(a limit analysis: the plastic power each node's cell dissipates), and adds
particles there: :func:`mark_share` marks the fewest nodes that carry a given
share of the indicator's total (Dörfler's bulk criterion), and
:func:`split_around` adds the midpoint of every edge of the triangles that
touch a marked node, which halves the spacing there.  The points are then
triangulated again (:func:`~skfem_npfem.mesh.regions.mesh_regions`): no state
is carried, so this is for analyses without history (limit analysis, the
factor of safety).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError

__all__ = ["mark_share", "split_around"]


def mark_share(indicator: np.ndarray, share: float) -> np.ndarray:
    """The fewest nodes whose ``indicator`` sums to at least ``share`` of its total.

    Parameters
    ----------
    indicator : ndarray (n,)
        A non-negative amount per node (negative values count as 0).
    share : float
        In (0, 1].

    Returns
    -------
    ndarray (n,) bool
        The marked nodes (at least one).

    Examples
    --------
    >>> mark_share(np.array([1.0, 6.0, 3.0, 0.0]), 0.6).tolist()
    [False, True, False, False]
    >>> mark_share(np.array([1.0, 6.0, 3.0, 0.0]), 0.7).tolist()
    [False, True, True, False]
    """
    if not 0.0 < share <= 1.0:
        raise ParameterError("share", share, "a number in (0, 1]")
    a = np.maximum(np.asarray(indicator, float), 0.0)
    order = np.argsort(-a, kind="stable")
    total = float(a.sum())
    marked = np.zeros(a.size, bool)
    if a.size == 0:
        return marked
    if total <= 0.0:
        marked[order[0]] = True
        return marked
    k = int(np.searchsorted(np.cumsum(a[order]), share * total * (1 - 1e-12)))
    marked[order[: min(k, a.size - 1) + 1]] = True
    return marked


def split_around(pts: np.ndarray, t: np.ndarray, marked: np.ndarray) -> np.ndarray:
    """``pts`` and the midpoints of the edges of the triangles touching ``marked``.

    Parameters
    ----------
    pts : ndarray (n, 2)
        Points of the mesh.
    t : ndarray (3, m) int
        Its triangles (scikit-fem's ``t``).
    marked : ndarray (n,) bool
        Marked nodes.

    Returns
    -------
    ndarray (n + k, 2)
        The points, then one midpoint per distinct edge of the touched
        triangles (an edge on a straight boundary keeps its midpoint on it).

    Examples
    --------
    >>> p = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    >>> t = np.array([[0, 1], [1, 3], [2, 2]])
    >>> split_around(p, t, np.array([True, False, False, False]))[4:].tolist()
    [[0.5, 0.0], [0.0, 0.5], [0.5, 0.5]]
    """
    tri = np.asarray(t).T
    touched = tri[np.asarray(marked, bool)[tri].any(axis=1)]
    if touched.size == 0:
        return np.asarray(pts, float)
    edges = np.concatenate([touched[:, [0, 1]], touched[:, [1, 2]], touched[:, [2, 0]]])
    edges = np.unique(np.sort(edges, axis=1), axis=0)
    mid = 0.5 * (pts[edges[:, 0]] + pts[edges[:, 1]])
    return np.concatenate([np.asarray(pts, float), mid])
