"""Stress roughness: how far each particle's stress departs from its neighbours'.

The measure of ``/work/shared/tools/stress_roughness.py`` (the project's
reference tool, which reads result folders), as a pure function of one mesh:

    R = rms_i(s_i - mean_{j ~ i} s_j) / rms_i(s_i)

over the *interior* particles: particles of the mesh (triangles or tetrahedra)
that lie on no boundary facet and have no mesh neighbour on one.  ``j ~ i``
are the particles sharing a cell with ``i``; ``s`` is the vertical normal
stress (the last axis: Voigt component 1 in 2D, 2 in 3D).  A linear field on a
regular lattice gives ``R ~ 0``, an elastic body at rest remeshed every step
about 0.06, a checkerboard ``R`` of order 1.  With fewer than 10 interior
particles the index is undefined (NaN).

Scenes report it per step (``stress_roughness`` in the step records) and in
their summaries; :func:`stress_roughness` gives the same number as the
reference tool on the written VTU of a step (tested).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["MIN_INTERIOR", "roughness_of_step", "stress_roughness", "vertical_stress"]

#: Fewer interior particles than this: the index is NaN.
MIN_INTERIOR = 10


def vertical_stress(stress: np.ndarray, dim: int) -> np.ndarray:
    """The vertical normal stress (last axis) of full-Voigt stresses (N, 4|6).

    Voigt component 1 in 2D (``yy``; ``zz`` of the ``(r, z)`` axisymmetric
    half-section), 2 in 3D (``zz``).
    """
    return np.asarray(stress)[:, dim - 1]


def stress_roughness(
    points: np.ndarray, cells: np.ndarray, s: np.ndarray
) -> tuple[float, int]:
    """Roughness index of a nodal field ``s`` on a simplex mesh.

    Parameters
    ----------
    points : ndarray (N, d)
        Particle positions (particles in no cell are ignored).
    cells : ndarray (ne, d+1) int
        Triangles or tetrahedra, global particle numbers.
    s : ndarray (N,)
        The field, e.g. :func:`vertical_stress`.

    Returns
    -------
    float
        ``R`` (NaN with fewer than :data:`MIN_INTERIOR` interior particles; 0
        for a zero field).
    int
        Number of interior particles.

    Examples
    --------
    >>> from skfem import MeshTri
    >>> m = MeshTri.init_tensor(np.linspace(0, 1, 9), np.linspace(0, 1, 9))
    >>> r, n = stress_roughness(m.p.T, m.t.T, 1.0 + m.p[0] + 2 * m.p[1])
    >>> n, r < 1e-12
    (25, True)
    """
    cells = np.asarray(cells)
    n = len(points)
    k = cells.shape[1]
    rows = np.repeat(cells, k, axis=1).ravel()
    cols = np.tile(cells, (1, k)).ravel()
    adj = sp.coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n)).tocsr()
    adj.data[:] = 1.0
    adj.setdiag(0)
    adj.eliminate_zeros()
    deg = np.asarray(adj.sum(axis=1)).ravel()
    # Boundary facets: facets of exactly one cell.
    facets = np.vstack([np.delete(cells, j, axis=1) for j in range(k)])
    facets.sort(axis=1)
    uniq, count = np.unique(facets, axis=0, return_counts=True)
    on_boundary = np.zeros(n, bool)
    on_boundary[np.unique(uniq[count == 1])] = True
    interior = (deg > 0) & ~on_boundary & ((adj @ on_boundary.astype(float)) == 0)
    n_int = int(interior.sum())
    if n_int < MIN_INTERIOR:
        return float("nan"), n_int
    dev = (s - adj @ s / np.maximum(deg, 1))[interior]
    scale = np.sqrt(np.mean(s[interior] ** 2))
    return (float(np.sqrt(np.mean(dev**2)) / scale) if scale > 0 else 0.0), n_int


def roughness_of_step(x: np.ndarray, cells: np.ndarray, stress: np.ndarray) -> float:
    """``R`` of the vertical stress of one step (positions, global cells, stress)."""
    d = x.shape[1]
    return stress_roughness(x, cells, vertical_stress(stress, d))[0]
