"""The boundary of a particle triangulation: outward normals and free surface.

Works on the :class:`~skfem_npfem.mesh.delaunay.Triangulation` of one step: its
boundary facets (which :func:`~skfem_npfem.mesh.delaunay.alpha_shape` finds, slivers
counted as material) give each boundary particle an outward normal
(:func:`boundary_normals`), and the boundary particles that do not rest on a
wall form the free surface (:func:`free_surface`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ParameterError
from .delaunay import Triangulation, check_triangulation

__all__ = ["boundary_normals", "free_surface"]


def boundary_normals(tri: Triangulation) -> NDArray[np.float64]:
    """Outward unit normal at every boundary particle.

    The normal of a particle is the average of the outward normals of its
    boundary facets, weighted by facet length (2D) or area (3D), then normalised.
    At a 90-degree corner of a lattice it is therefore the bisector.

    Parameters
    ----------
    tri : Triangulation
        Result of :func:`alpha_shape`.

    Returns
    -------
    ndarray of float, shape (N, d)
        Unit normals; zero rows for interior and inactive particles, and for a
        boundary particle whose facet normals cancel (a one-particle-thick
        filament).

    Examples
    --------
    >>> import numpy as np
    >>> from skfem_npfem.mesh.delaunay import alpha_shape
    >>> g = np.linspace(0.0, 1.0, 3)
    >>> pts = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
    >>> boundary_normals(alpha_shape(pts, h=0.5))[[3, 4]]  # bottom middle, centre
    array([[ 0., -1.],
           [ 0.,  0.]])
    """
    check_triangulation(tri)
    x, f = tri.points, tri.boundary_facets
    n, d = x.shape
    out = np.zeros((n, d))
    if f.shape[0] == 0:
        return out
    if d == 2:
        t = x[f[:, 1]] - x[f[:, 0]]
        normals = np.column_stack([t[:, 1], -t[:, 0]])
    else:
        normals = np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]])
    nodes = f.ravel()
    for k in range(d):
        out[:, k] = np.bincount(nodes, weights=np.repeat(normals[:, k], d), minlength=n)
    norm = np.linalg.norm(out, axis=1)
    scale = np.linalg.norm(normals, axis=1).max()
    ok = norm > 1e-12 * scale
    out[ok] /= norm[ok, None]
    out[~ok] = 0.0
    return out


def free_surface(
    tri: Triangulation, on_wall: ArrayLike | None = None
) -> NDArray[np.bool_]:
    """Boundary particles that are not in contact with a wall.

    Parameters
    ----------
    tri : Triangulation
        Result of :func:`alpha_shape`.
    on_wall : array_like of bool, shape (N,), optional
        True for particles lying on a wall (supports, rigid bodies).

    Returns
    -------
    ndarray of bool, shape (N,)
        ``tri.boundary & ~on_wall``.

    Raises
    ------
    ParameterError
        If ``on_wall`` is not a boolean array of shape (N,).
    """
    check_triangulation(tri)
    if on_wall is None:
        return tri.boundary.copy()
    wall = np.asarray(on_wall)
    n = tri.points.shape[0]
    if wall.dtype != np.bool_ or wall.shape != (n,):
        raise ParameterError(
            "on_wall",
            f"array of shape {wall.shape}, dtype {wall.dtype}",
            f"a boolean array of shape ({n},)",
        )
    return tri.boundary & ~wall
