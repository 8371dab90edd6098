"""Stress roughness: how far each particle's stress departs from its neighbours'.

The project's reference measure of stress oscillation (public as
:func:`skfem_npfem.stress_roughness`; the scenes' ``stress_roughness`` metric is
this function on each step's mesh):

    R = rms_i(s_i - mean_{j ~ i} s_j) / rms_i(s_i)

over the *interior* particles ``i`` -- nodes of the mesh that lie on no
boundary facet (a facet of exactly one cell) and have no mesh neighbour on
one; ``j ~ i`` are the nodes sharing a cell with ``i``.  ``s`` is the vertical
normal stress (Voigt component ``d - 1``: ``yy`` in 2D, ``zz`` in 3D).  A
linear field on a regular lattice gives ``R ~ 0``, a checkerboard ``R`` of
order one.  Fewer than 10 interior particles give NaN.

The scenes report the index of the last step as ``stress_roughness`` and the
largest over the run as ``stress_roughness_max``; the same function on a run's
VTU files (their cells and ``stress``) gives the same numbers (tested, also
against an independent implementation of the definition).

The index is not zero for a smooth field on an irregular mesh: a linear field
gives ``s_i - mean_j s_j = grad s . (x_i - mean_j x_j)``, which vanishes only
where the neighbours are centred on the node, and curvature adds
``O(h^2 |hess s|)``.  :func:`roughness_floor` measures that part on a given
mesh: the index of the least-squares polynomial fit of the values (a smooth
field of the same shape), so that ``R`` can be read against what a smooth
stress would score on the same particles.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["MIN_INTERIOR", "roughness_floor", "roughness_index", "stress_roughness"]

#: Fewer interior particles than this give NaN.
MIN_INTERIOR = 10


def roughness_index(cells: np.ndarray, values: np.ndarray) -> tuple[float, int]:
    """Roughness ``R`` of nodal ``values`` on a simplex mesh; and the interior count.

    Parameters
    ----------
    cells : ndarray (ne, k) int
        Triangles (k = 3) or tetrahedra (k = 4), indices into ``values``.
    values : ndarray (n,)
        One value per node (nodes in no cell are ignored).

    Returns
    -------
    float
        ``R`` (NaN with fewer than :data:`MIN_INTERIOR` interior nodes; 0 if the
        values vanish there).
    int
        Number of interior nodes.

    Examples
    --------
    >>> from skfem import MeshTri
    >>> m = MeshTri.init_tensor(*[np.linspace(0, 1, 9)] * 2)
    >>> r, n = roughness_index(m.t.T, 1.0 + m.p[1])  # a linear field
    >>> round(r, 12), n
    (0.0, 25)
    """
    cells = np.asarray(cells)
    values = np.asarray(values, float)
    n, (ne, k) = values.shape[0], cells.shape
    incidence = sp.csr_matrix(
        (np.ones(ne * k), (cells.ravel(), np.repeat(np.arange(ne), k))),
        shape=(n, ne),
    )
    adj = (incidence @ incidence.T).tocsr()
    adj.setdiag(0)
    adj.eliminate_zeros()
    adj.data[:] = 1.0
    degree = np.asarray(adj.sum(axis=1)).ravel()
    # A facet of exactly one cell is on the boundary.
    facets = np.sort(
        np.concatenate([np.delete(cells, j, axis=1) for j in range(k)]), axis=1
    )
    unique, count = np.unique(facets, axis=0, return_counts=True)
    boundary = np.zeros(n, bool)
    boundary[unique[count == 1].ravel()] = True
    near_boundary = adj @ boundary.astype(float) > 0
    interior = (degree > 0) & ~boundary & ~near_boundary
    n_int = int(np.count_nonzero(interior))
    if n_int < MIN_INTERIOR:
        return float("nan"), n_int
    mean_nb = (adj @ values)[interior] / degree[interior]
    scale = float(np.sqrt(np.mean(values[interior] ** 2)))
    if scale == 0.0:
        return 0.0, n_int
    dev = values[interior] - mean_nb
    return float(np.sqrt(np.mean(dev**2)) / scale), n_int


def roughness_floor(
    points: np.ndarray, cells: np.ndarray, values: np.ndarray, degree: int = 3
) -> float:
    """``R`` of a smooth field of the same shape: the floor of the index on a mesh.

    The nodal ``values`` of the nodes in ``cells`` are fitted by least squares
    with a polynomial of total ``degree`` in the coordinates, and the index of
    the fit is returned.  A smooth stress field scores about this on the same
    particles and cells, so ``R`` well above it is oscillation, and ``R`` near
    it is what the measure gives a smooth field at this spacing and mesh
    quality.  ``sqrt(R^2 - floor^2)`` is a rough estimate of the oscillating
    part (the two are not exactly orthogonal).

    Parameters
    ----------
    points : ndarray (n, d)
        Node coordinates.
    cells : ndarray (ne, d+1) int
        Triangles or tetrahedra.
    values : ndarray (n,)
        One value per node.
    degree : int
        Total degree of the fitted polynomial (default 3).

    Returns
    -------
    float
        :func:`roughness_index` of the fit (NaN with too few interior nodes).

    Examples
    --------
    >>> from skfem import MeshTri
    >>> m = MeshTri.init_tensor(*[np.linspace(0, 1, 9)] * 2)
    >>> x, y = m.p
    >>> rough = 1.0 + y + 0.1 * (-1.0) ** np.arange(x.size)  # a checkerboard
    >>> r = roughness_index(m.t.T, rough)[0]
    >>> print(f"R {r:.2f}, floor {roughness_floor(m.p.T, m.t.T, rough):.4f}")
    R 0.09, floor 0.0004
    """
    points = np.asarray(points, float)
    cells = np.asarray(cells)
    values = np.asarray(values, float)
    used = np.unique(cells)
    x = points[used]
    # Centred and scaled coordinates keep the monomial basis well conditioned.
    x = (x - x.mean(axis=0)) / max(float(np.ptp(x, axis=0).max()), 1e-300)
    d = x.shape[1]
    exps = [e for e in np.ndindex(*(degree + 1,) * d) if sum(e) <= degree]
    basis = np.stack([np.prod(x ** np.array(e), axis=1) for e in exps], axis=1)
    coef = np.linalg.lstsq(basis, values[used], rcond=None)[0]
    fit = np.zeros_like(values)
    fit[used] = basis @ coef
    return roughness_index(cells, fit)[0]


def stress_roughness(cells: np.ndarray, stress: np.ndarray) -> float:
    """The stress roughness ``R`` of the vertical normal stress of particles.

    The reference measure of stress oscillation (see the module notes):
    ``rms(s_i - mean of its mesh neighbours) / rms(s_i)`` over the interior
    particles, with ``s`` the vertical normal stress.  The scenes'
    ``stress_roughness`` metric is this function on each step's mesh.

    Parameters
    ----------
    cells : ndarray (ne, d+1) int
        Triangles (2D) or tetrahedra (3D) indexing the particles, as the step's
        mesh or the cells of a result file.
    stress : ndarray (n, m)
        Voigt stress per particle as stored by the package (``xx, yy, zz, xy``
        in 2D, ``xx, yy, zz, xy, yz, zx`` in 3D); the vertical component
        ``d - 1`` (``yy`` in 2D, ``zz`` in 3D) is measured.

    Returns
    -------
    float
        ``R`` (about 0 for a smooth field, of order 1 for a checkerboard; NaN
        with fewer than :data:`MIN_INTERIOR` interior particles).

    Examples
    --------
    >>> from skfem import MeshTri
    >>> m = MeshTri.init_tensor(*[np.linspace(0, 1, 13)] * 2)
    >>> i = np.rint(12 * m.p).astype(int)
    >>> stress = np.zeros((m.p.shape[1], 4))
    >>> stress[:, 1] = (-1.0) ** (i[0] + i[1])  # a checkerboard: R = 4/3
    >>> round(stress_roughness(m.t.T, stress), 12)
    1.333333333333
    """
    cells = np.asarray(cells)
    dim = cells.shape[1] - 1
    return roughness_index(cells, np.asarray(stress)[:, dim - 1])[0]
