"""Moving Gauss-point variables from an old mesh to a new one (remapping).

This is the step N-PFEM does not need: a classical PFEM keeps its state at
the Gauss points of a mesh that is rebuilt every step, so every history
variable (stress, equivalent plastic strain) has to be carried over from the
old Gauss points to the new ones.  Two operators:

``"nearest"``
    Each new point takes the value of the closest old Gauss point (k-d tree).
    Cheap and local; it is not exact even for a linear field.
``"recovery"``
    Superconvergent patch recovery (Zienkiewicz-Zhu): at every old vertex a
    linear polynomial is fitted by least squares to the Gauss-point values of
    the elements around it (the patch is widened to the second ring where the
    first ring cannot fit a plane well, e.g. at corners or where a thin
    element makes the points nearly collinear: :data:`WELL_POSED`), evaluated
    at the vertex,
    and the recovered nodal field is interpolated linearly at the new points
    inside the old element that contains them.  Exact for linear fields; new
    points outside the old mesh take the nearest old Gauss-point value.

Point location is vectorised and works on the old mesh itself (an alpha shape
is not the Delaunay triangulation of its vertices: lattice ties are broken
differently and simplices have been removed, so ``scipy.spatial.Delaunay`` of
the old vertices would interpolate across removed simplices).  Candidate
elements come from a k-d tree of element centroids, their barycentric
coordinates are computed for all candidates at once, and a point belongs to the
candidate whose smallest barycentric coordinate is largest (inside when it is
``>= -1e-10``).  Memory is ``O(n_points * k)``, unlike scikit-fem's ``probes``,
which builds a dense point-element array.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..errors import ParameterError

__all__ = [
    "TRANSFERS",
    "interpolate_nodal",
    "locate",
    "nearest_values",
    "recover_nodal",
    "transfer_values",
]

#: Transfer operators of the FEM baseline.
TRANSFERS = ("nearest", "recovery")

#: A point is inside an element when every barycentric coordinate is >= -BARY_TOL.
BARY_TOL = 1e-10
#: A patch fit is used when the smallest eigenvalue of its normal matrix (in
#: coordinates scaled by the patch size) is at least this fraction of the
#: largest; otherwise the patch grows to the second ring of elements.  With
#: 1e-8 a boundary vertex whose patch held a sliver extrapolated its nearly
#: collinear Gauss points, the transfer amplified that value step after step
#: and FEM-remap P1 blew up in the a = 2 column collapse (stresses 1e6 rho g H
#: at t = 0.6 s, ``tests/baseline/test_fem.py``); a well-posed fit of a linear
#: field is still exact.
WELL_POSED = 1e-3


def _inverse_maps(x: np.ndarray, t: np.ndarray):
    """Per-element origin and inverse Jacobian of the affine maps."""
    x0 = x[t[:, 0]]
    J = np.stack([x[t[:, a]] - x0 for a in range(1, t.shape[1])], axis=2)  # (ne,d,d)
    det = np.linalg.det(J)
    ok = np.abs(det) > 1e-14 * np.max(np.abs(J), axis=(1, 2)) ** J.shape[1]
    Jinv = np.zeros_like(J)
    Jinv[ok] = np.linalg.inv(J[ok])
    return x0, Jinv, ok


def locate(
    points: np.ndarray, x: np.ndarray, t: np.ndarray, k: int = 12
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Find the element of a simplex mesh that contains each point.

    A fast pass tries the ``k`` elements with the nearest centroids; the points
    not found there are searched exhaustively among all elements whose
    centroid lies within the largest centroid-vertex distance of the mesh (a
    containing element always does), so a point is reported outside only if no
    element contains it.

    Parameters
    ----------
    points : ndarray (n, d)
    x : ndarray (N, d)
        Mesh vertices.
    t : ndarray (ne, d+1)
        Elements (vertex indices into ``x``).
    k : int
        Candidates of the fast pass.

    Returns
    -------
    elem : ndarray (n,) int
        Containing element (or the best candidate when not found).
    bary : ndarray (n, d+1)
        Barycentric coordinates in ``elem``.
    found : ndarray (n,) bool
        Whether the point lies inside the mesh (to ``BARY_TOL``).

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    >>> t = np.array([[0, 1, 2], [1, 3, 2]])
    >>> e, b, f = locate(np.array([[0.75, 0.75], [2.0, 2.0]]), x, t)
    >>> e.tolist(), f.tolist()
    ([1, 1], [True, False])
    """
    points = np.asarray(points, float)
    n, nv = points.shape[0], t.shape[1]
    x0, Jinv, ok = _inverse_maps(x, t)
    cent = x[t].mean(axis=1)
    tree = cKDTree(cent)
    _, cand = tree.query(points, k=min(k, t.shape[0]))
    cand = cand.reshape(n, -1)
    rows = np.repeat(np.arange(n), cand.shape[1])
    elem, bary, score = _best(points, rows, cand.ravel(), x0, Jinv, ok, n, nv)
    todo = np.flatnonzero(score < -BARY_TOL)
    if todo.size:
        reach = float(np.max(np.linalg.norm(x[t] - cent[:, None, :], axis=2)))
        lists = tree.query_ball_point(points[todo], reach * (1 + 1e-9))
        counts = np.array([len(c) for c in lists])
        if counts.sum():
            rows2 = np.repeat(np.arange(todo.size), counts)
            cand2 = np.concatenate([np.asarray(c, int) for c in lists if len(c)])
            e2, b2, s2 = _best(points[todo], rows2, cand2, x0, Jinv, ok, todo.size, nv)
            better = s2 > score[todo]
            upd = todo[better]
            elem[upd], bary[upd], score[upd] = e2[better], b2[better], s2[better]
    return elem, bary, score >= -BARY_TOL


def _best(points, rows, cand, x0, Jinv, ok, n, nv):
    """Per point, the candidate with the largest smallest barycentric coordinate."""
    rel = points[rows] - x0[cand]
    lam = np.einsum("kij,kj->ki", Jinv[cand], rel)
    b = np.concatenate([1.0 - lam.sum(axis=1, keepdims=True), lam], axis=1)
    s = np.where(ok[cand], b.min(axis=1), -np.inf)
    order = np.lexsort((-s, rows))  # per point, best score first
    first = order[np.r_[True, rows[order][1:] != rows[order][:-1]]]
    elem = np.zeros(n, int)
    bary = np.zeros((n, nv))
    score = np.full(n, -np.inf)
    pts = rows[first]
    elem[pts], bary[pts], score[pts] = cand[first], b[first], s[first]
    return elem, bary, score


def nearest_values(
    points: np.ndarray, old_points: np.ndarray, values: np.ndarray
) -> np.ndarray:
    """Values of the closest old point, shape (n, ...)."""
    _, idx = cKDTree(old_points).query(np.asarray(points, float))
    return values[idx]


def _patch_pairs(t: np.ndarray, nq: int, n_vert: int, ring2: np.ndarray | None):
    """(vertex, Gauss point) pairs of the patches (first or second ring)."""
    ne, nv = t.shape
    inc = sp.csr_matrix(
        (np.ones(ne * nv), (t.ravel(), np.repeat(np.arange(ne), nv))),
        shape=(n_vert, ne),
    )
    if ring2 is not None:
        sub = inc[ring2]
        inc = ((sub @ inc.T) @ inc).tocsr()
        inc.data[:] = 1.0
        vert_ids = ring2
    else:
        vert_ids = np.arange(n_vert)
    coo = inc.tocoo()
    v = vert_ids[coo.row]
    e = coo.col
    vv = np.repeat(v, nq)
    gg = (e[:, None] * nq + np.arange(nq)[None, :]).ravel()
    return vv, gg


def _fit(x, gp_x, values, vv, gg, n_vert):
    """Least-squares linear fit per vertex; returns (value, well_posed)."""
    d = x.shape[1]
    rel = gp_x[gg] - x[vv]
    scale = np.zeros(n_vert)
    np.maximum.at(scale, vv, np.linalg.norm(rel, axis=1))
    scale[scale == 0] = 1.0
    basis = np.concatenate([np.ones((vv.size, 1)), rel / scale[vv, None]], axis=1)
    nb = d + 1
    AtA = np.zeros((n_vert, nb, nb))
    np.add.at(AtA, vv, basis[:, :, None] * basis[:, None, :])
    m = values.shape[1]
    Atb = np.zeros((n_vert, nb, m))
    np.add.at(Atb, vv, basis[:, :, None] * values[gg][:, None, :])
    eig = np.linalg.eigvalsh(AtA)
    good = eig[:, 0] > WELL_POSED * np.maximum(eig[:, -1], 1e-300)
    coef = np.zeros((n_vert, nb, m))
    coef[good] = np.linalg.solve(AtA[good], Atb[good])
    return coef[:, 0, :], good, AtA, Atb


def recover_nodal(
    x: np.ndarray, t: np.ndarray, gp_x: np.ndarray, values: np.ndarray
) -> np.ndarray:
    """Superconvergent patch recovery of Gauss-point values at the vertices.

    Parameters
    ----------
    x : ndarray (N, d)
        Vertex positions (vertices not in ``t`` get NaN).
    t : ndarray (ne, d+1)
        Elements.
    gp_x : ndarray (ne * nq, d)
        Gauss points, element-major (point ``e * nq + q``).
    values : ndarray (ne * nq, m)
        Values at the Gauss points.

    Returns
    -------
    ndarray (N, m)
        Recovered nodal values; exact when ``values`` samples a linear field.
    """
    values = np.asarray(values, float)
    flat = values.reshape(values.shape[0], -1)
    n_vert, ne = x.shape[0], t.shape[0]
    nq = gp_x.shape[0] // ne
    vv, gg = _patch_pairs(t, nq, n_vert, None)
    out, good, _, _ = _fit(x, gp_x, flat, vv, gg, n_vert)
    used = np.zeros(n_vert, bool)
    used[t.ravel()] = True
    weak = np.flatnonzero(used & ~good)
    if weak.size:  # corners and thin spots: second ring of elements
        vv2, gg2 = _patch_pairs(t, nq, n_vert, weak)
        out2, good2, AtA2, Atb2 = _fit(x, gp_x, flat, vv2, gg2, n_vert)
        out[weak] = out2[weak]
        still = weak[~good2[weak]]
        # Constant fit (patch mean) where even two rings are degenerate.
        out[still] = Atb2[still, 0, :] / np.maximum(AtA2[still, 0, 0], 1)[:, None]
    out[~used] = np.nan
    return out.reshape((n_vert, *values.shape[1:]))


def interpolate_nodal(
    points: np.ndarray, x: np.ndarray, t: np.ndarray, nodal: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Linear interpolation of vertex values at points; (values, found)."""
    elem, bary, found = locate(points, x, t)
    flat = nodal.reshape(nodal.shape[0], -1)
    vals = np.einsum("na,nam->nm", bary, flat[t[elem]])
    return vals.reshape((points.shape[0], *nodal.shape[1:])), found


def transfer_values(
    method: str,
    x: np.ndarray,
    t_old: np.ndarray,
    gp_old: np.ndarray,
    values: np.ndarray,
    gp_new: np.ndarray,
) -> tuple[np.ndarray, int]:
    """Move Gauss-point values from an old mesh to new points.

    Parameters
    ----------
    method : {"nearest", "recovery"}
    x : ndarray (N, d)
        Current vertex positions (the old mesh moved with the particles).
    t_old : ndarray (ne, d+1)
        Old elements (indices into ``x``).
    gp_old : ndarray (ne * nq, d)
        Old Gauss points in the current configuration.
    values : ndarray (ne * nq, ...)
    gp_new : ndarray (n, d)
        New Gauss points.

    Returns
    -------
    new_values : ndarray (n, ...)
    n_outside : int
        New points outside the old mesh (given the nearest value; 0 for
        ``"nearest"``).
    """
    if method not in TRANSFERS:
        raise ParameterError("transfer", method, f"one of {TRANSFERS}")
    if method == "nearest":
        return nearest_values(gp_new, gp_old, values), 0
    nodal = recover_nodal(x, t_old, gp_old, values)
    out, found = interpolate_nodal(gp_new, x, t_old, nodal)
    if not np.all(found):
        out[~found] = nearest_values(gp_new[~found], gp_old, values)
    return out, int(np.count_nonzero(~found))
