"""Particle re-triangulation: Delaunay plus the alpha-shape test of PFEM.

Every time step the particles (the mesh nodes) are triangulated afresh, simplices
that are too large for the particle spacing are removed (the *alpha shape*), and
the remaining simplices form a disposable scikit-fem mesh for that step only.

The rule, as in the PFEM literature, is

    keep simplex e  if  R_e < alpha * h,

where ``R_e`` is the circumradius of ``e``, ``h`` the characteristic particle
spacing and ``alpha`` a user factor (typically 1.2-1.6).  In addition, degenerate
*slivers* are removed from the mesh because their P1 gradients are unbounded.

Three details matter in practice and are handled here.

* **Ties on regular lattices.**  Lattice particles are co-circular (2D) and
  co-spherical (3D), so the Delaunay triangulation is not unique.  Moving the
  particles by a random jitter breaks the tie but, in 3D, leaves about a third of
  the tetrahedra of a cubic lattice as flat slivers of zero volume.  Instead the
  jitter is applied to the *lifted* coordinate ``|x|^2`` of the paraboloid
  construction of the Delaunay triangulation (qhull's convex hull in ``d + 1``
  dimensions).  The result is a regular (weighted Delaunay) triangulation of the
  original, unmoved particles: it never contains interior simplices of zero
  volume and it coincides with the Delaunay triangulation whenever that one is
  unique up to a margin of ``jitter * h**2`` in the empty-sphere test.
* **Slivers.**  A sliver that passes the alpha test belongs to the body; it is
  left out of the mesh but still counts as material when the boundary is
  detected, so dropping it does not open a spurious internal free surface.
* **Near-coincident particles.**  See :func:`alpha_shape`.

Simplices are returned positively oriented (counter-clockwise in 2D, positive
signed volume in 3D), with global particle indices and with a compacted
numbering on the active particles that scikit-fem needs (its number of vertices
is ``max(t) + 1``).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError
from skfem import MeshTet, MeshTri

from ..errors import NpfemError, ParameterError
from .cavities import seal
from .simplices import (
    _FACES,
    _boundary_facets,
    _facet_groups,
    _group_rows,
    _open_slivers,
    _quality,
    _shared_face_pairs,
    _simplex_geometry,
)

__all__ = ["Triangulation", "alpha_shape", "check_triangulation", "p1_mesh"]

#: Simplices with volume below ``VOLUME_TOL * h**d`` are treated as degenerate.
VOLUME_TOL = 1e-12
#: Default ``min_quality`` of :func:`alpha_shape`: simplices below it are slivers.
SLIVER_QUALITY = 1e-3


def p1_mesh(points: np.ndarray, t: np.ndarray) -> MeshTri | MeshTet:
    """The scikit-fem P1 mesh of one step: nodes ``points`` (N, d), cells ``t``.

    ``t`` is (d+1, ne) with node numbers ``0 .. N-1``, every node in a cell
    (scikit-fem takes ``nvertices = max(t) + 1``).  Cells keep their vertex
    order (``sort_t=False``: scikit-fem would otherwise reorder, and flip,
    them).

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> mesh = p1_mesh(x, np.array([[0], [1], [2]]))
    >>> type(mesh).__name__, int(mesh.nvertices), mesh.t[:, 0].tolist()
    ('MeshTri1', 3, [0, 1, 2])
    """
    cls = MeshTri if points.shape[1] == 2 else MeshTet
    return cls(np.ascontiguousarray(points.T), np.ascontiguousarray(t), sort_t=False)


@dataclass(frozen=True, eq=False)
class Triangulation:
    """Alpha-shape triangulation of a particle cloud, valid for one time step.

    All index arrays refer to rows of :attr:`points` unless stated otherwise.
    The arrays are read-only.

    Attributes
    ----------
    points : ndarray of float, shape (N, d)
        Particle positions the triangulation was built on (not jittered).
    simplices : ndarray of int, shape (ne, d + 1)
        Global particle indices of the kept simplices, every one positively
        oriented (counter-clockwise in 2D, positive signed volume in 3D).
    active : ndarray of bool, shape (N,)
        True for particles that belong to at least one kept simplex.
    active_index : ndarray of int, shape (N_a,)
        Global indices of the active particles, increasing.
    local_simplices : ndarray of int, shape (ne, d + 1)
        :attr:`simplices` renumbered to ``0 .. N_a - 1`` (positions in
        :attr:`active_index`).
    boundary_facets : ndarray of int, shape (nf, d)
        Global indices of the facets on the boundary of the kept body.  Each is a
        facet of exactly one kept simplex and is ordered so that its normal points
        outwards: for an edge ``(a, b)`` in 2D the body lies on the left of
        ``a -> b``; for a triangle ``(a, b, c)`` in 3D the outward normal is
        ``(x_b - x_a) x (x_c - x_a)``.
    boundary : ndarray of bool, shape (N,)
        True for particles on at least one boundary facet.
    volume : float
        Total area (2D, m^2) or volume (3D, m^3) of the kept simplices.

    Examples
    --------
    >>> import numpy as np
    >>> from skfem_npfem.mesh.delaunay import alpha_shape
    >>> g = np.linspace(0.0, 1.0, 5)
    >>> pts = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    >>> tri = alpha_shape(pts, h=0.25)
    >>> round(tri.volume, 12), tri.n_components(), int(tri.boundary.sum())
    (1.0, 1, 16)
    >>> tri.mesh().t.shape
    (3, 32)
    """

    points: NDArray[np.float64]
    simplices: NDArray[np.intp]
    active: NDArray[np.bool_]
    active_index: NDArray[np.intp]
    local_simplices: NDArray[np.intp]
    boundary_facets: NDArray[np.intp]
    boundary: NDArray[np.bool_]
    volume: float

    @property
    def dim(self) -> int:
        """Spatial dimension ``d`` (2 or 3)."""
        return int(self.points.shape[1])

    def mesh(self) -> MeshTri | MeshTet:
        """Build the scikit-fem mesh on the active particles.

        Node ``k`` of the mesh is particle ``active_index[k]``, so nodal results
        map back with ``values_on_particles[active_index] = mesh_values``.  Cells
        keep the positive orientation of :attr:`local_simplices`
        (``sort_t=False``).

        Returns
        -------
        MeshTri or MeshTet
            ``MeshTri`` in 2D, ``MeshTet`` in 3D.

        Raises
        ------
        NpfemError
            If no simplex survived the alpha-shape test.
        """
        if self.simplices.shape[0] == 0:
            raise NpfemError(
                "the triangulation has no simplices (every candidate failed the "
                "alpha-shape or quality test); increase alpha or h"
            )
        return p1_mesh(self.points[self.active_index], self.local_simplices.T)

    def n_components(self) -> int:
        """Count the connected bodies.

        Two kept simplices are connected when they share a facet; bodies that
        touch only at a vertex or an edge count separately.

        Returns
        -------
        int
            Number of connected components (0 for an empty triangulation).
        """
        ne = self.simplices.shape[0]
        if ne == 0:
            return 0
        faces = self.simplices[:, _FACES[self.dim]].reshape(-1, self.dim)
        owner = np.repeat(np.arange(ne), self.dim + 1)
        inverse, _ = _group_rows(faces)
        a, b = _shared_face_pairs(inverse, owner)
        graph = sp.coo_matrix((np.ones(a.size), (a, b)), shape=(ne, ne))
        ncomp, _ = connected_components(graph, directed=False)
        return int(ncomp)


def alpha_shape(
    points: ArrayLike,
    h: float,
    alpha: float = 1.3,
    *,
    min_quality: float = SLIVER_QUALITY,
    jitter: float = 1e-6,
    seed: int = 0,
    h_local: ArrayLike | None = None,
    keep_buried_slivers: bool = False,
    closed: ArrayLike | None = None,
) -> Triangulation:
    """Triangulate particles and keep the simplices that pass the alpha test.

    Parameters
    ----------
    points : array_like of float, shape (N, d)
        Particle positions (m), ``d`` in {2, 3}, ``N >= d + 1``, all finite.
    h : float
        Characteristic particle spacing (m), > 0.
    alpha : float, default 1.3
        Alpha-shape factor, > 0: a simplex is kept if its circumradius is below
        ``alpha * h``.  A square lattice needs ``alpha > 1/sqrt(2)`` and a cubic
        lattice ``alpha > sqrt(3)/2``.
    min_quality : float, default 1e-3
        Simplices of quality below this value are dropped from the mesh, in
        ``[0, 1]``.  The quality is ``|e| / |e_reg(R_e)|``: the volume of the
        simplex over that of the regular simplex with the same circumradius,
        i.e. ``|e| / (3 sqrt(3)/4 R^2)`` in 2D and ``|e| / (8 sqrt(3)/27 R^3)``
        in 3D.  It is 1 for an equilateral triangle or a regular tetrahedron and
        tends to 0 for needles, caps and slivers (four nearly co-circular points).
        Simplices with volume below ``1e-12 * h**d`` are always dropped.
    jitter : float, default 1e-6
        Size of the deterministic perturbation that breaks co-circular and
        co-spherical ties, >= 0, dimensionless.  A uniform random value in
        ``[-jitter, jitter] * h**2`` is added to the lifted coordinate ``|x|^2``
        of each particle (not to its position; see the module notes).  0 disables
        it, which is not recommended for lattices.
    seed : int, default 0
        Seed of the jitter, >= 0.  Equal inputs give equal triangulations.
    h_local : array_like of float, shape (N,), optional
        Spacing of each particle, m, for a graded particle cloud: a simplex is
        then kept if its circumradius is below ``alpha`` times the largest
        spacing of its vertices (``h`` still scales the tolerances and the
        jitter: pass the finest spacing).  None: ``h`` everywhere.
    keep_buried_slivers : bool, default False
        Mesh the slivers buried in the body instead of dropping them, and
        count flat simplices (volume below the tolerance) whose facets pass
        the alpha test as part of the body.  A nearly cubic 3D lattice (the
        first steps of a body released from rest) triangulates into cubes
        split along different face diagonals with flat slivers between them:
        dropped, they leave the kept tetrahedra non-conforming across those
        faces (and flat ones open internal surfaces); kept, the mesh is
        closed.  A sliver contributes only its facet area vectors
        ``|e| grad N`` to the smoothed strain, which stay bounded as its volume
        vanishes.  Simplices below the volume tolerance are never meshed.
    closed : array_like of bool, shape (N,), optional
        Supports: a region of simplices failing the alpha test that reaches the
        hull only through facets of closed particles, or not at all, is kept
        (:func:`~skfem_npfem.mesh.cavities.seal`).  None: no region is kept.

    Returns
    -------
    Triangulation
        The kept simplices, active and boundary particles, boundary facets and the
        kept volume.

    Raises
    ------
    ParameterError
        If an argument is outside the ranges above.

    Notes
    -----
    Near-coincident particles (closer than about ``jitter * h``) never cause a
    crash, an infinite or a NaN.  Usually one of them is hidden by the
    triangulation (exact duplicates always are) and becomes inactive, so the
    caller moves it ballistically.  Otherwise the thin simplices it forms with its
    twin fail the quality test and are dropped, and it stays active through its
    remaining well-shaped simplices.  Dropped slivers still count as material for
    the boundary: a kept facet shared with a sliver is a boundary facet only if
    that sliver is connected, through slivers sharing facets, to the boundary of
    the alpha shape.  Slivers buried in the body thus open no internal surface.

    If all particles are collinear (2D) or coplanar (3D), qhull cannot build a
    triangulation; the result then has no simplices and every particle is
    inactive.

    Examples
    --------
    >>> import numpy as np
    >>> from skfem_npfem.mesh.delaunay import alpha_shape
    >>> pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [9.0, 9.0]])
    >>> tri = alpha_shape(pts, h=1.0)
    >>> tri.volume, tri.active.tolist()
    (1.0, [True, True, True, True, False])
    """
    x = _validate_points(points)
    h = _positive_float("h", h)
    alpha = _positive_float("alpha", alpha)
    min_quality = _float_in("min_quality", min_quality, 0.0, 1.0)
    jitter = _float_in("jitter", jitter, 0.0, math.inf)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError("seed", seed, "a non-negative integer")

    n, d = x.shape
    vol_tol = VOLUME_TOL * h**d
    candidates = _regular_triangulation(x, h, jitter, int(seed))
    signed, radius = _simplex_geometry(x, candidates, vol_tol)

    # Orient every candidate positively by swapping its first two vertices.
    flip = signed < 0.0
    candidates[flip, 0], candidates[flip, 1] = (
        candidates[flip, 1],
        candidates[flip, 0],
    )
    vol = np.abs(signed)
    quality = _quality(vol, radius, d)

    # The alpha complex: candidates that pass the alpha test.  Degenerate ones
    # have radius = inf and never do.  Among them, slivers are not meshed.
    if h_local is None:
        in_alpha = radius < alpha * h
    else:
        hl = np.asarray(h_local, dtype=float).reshape(-1)
        if hl.shape != (n,) or not np.all(np.isfinite(hl) & (hl > 0)):
            raise ParameterError(
                "h_local", hl.shape, f"{n} finite spacings > 0 (one per particle)"
            )
        in_alpha = radius < alpha * hl[candidates].max(axis=1)
    if closed is not None:
        in_alpha = seal(candidates, in_alpha, radius, closed)
    good = quality >= min_quality
    if keep_buried_slivers:
        # Flat simplices whose facets pass the alpha test belong to the body
        # (unmeshed): they close it where a sliver collapsed to a plane.
        flat = ~np.isfinite(radius) & _small_facets(x, candidates, alpha, h, h_local)
        good = good & ~flat
        in_alpha = in_alpha | flat
    simplices_k = candidates[in_alpha]
    kept_k = good[in_alpha]
    groups = _facet_groups(simplices_k) if simplices_k.shape[0] else None
    if keep_buried_slivers and groups is not None:
        buried = ~kept_k & ~_open_slivers(simplices_k, kept_k, groups)
        kept_k = kept_k | (buried & np.isfinite(radius[in_alpha]))
    boundary_facets = _boundary_facets(simplices_k, kept_k, groups)

    simplices = simplices_k[kept_k]
    active = np.zeros(n, dtype=bool)
    active[simplices.ravel()] = True
    active_index = np.flatnonzero(active)
    local = np.full(n, -1, dtype=np.intp)
    local[active_index] = np.arange(active_index.size)
    local_simplices = local[simplices]
    boundary = np.zeros(n, dtype=bool)
    boundary[boundary_facets.ravel()] = True
    volume = float(vol[in_alpha][kept_k].sum())

    arrays = (
        x,
        simplices,
        active,
        active_index,
        local_simplices,
        boundary_facets,
        boundary,
    )
    for a in arrays:
        a.setflags(write=False)
    return Triangulation(*arrays, volume=volume)


# --------------------------------------------------------------------------- #
# helpers
def _small_facets(
    x: NDArray[np.float64],
    simplices: NDArray[np.intp],
    alpha: float,
    h: float,
    h_local: ArrayLike | None,
) -> NDArray[np.bool_]:
    """Simplices whose every facet has a circumradius below ``alpha h``.

    With ``h_local``: below ``alpha`` times the largest spacing of the
    simplex's vertices (the alpha test of :func:`alpha_shape`).
    """
    n, d1 = simplices.shape
    d = d1 - 1
    if n == 0:
        return np.zeros(0, dtype=bool)
    faces = simplices[:, _FACES[d]]  # (n, d+1, d)
    p = x[faces]  # (n, d+1, d, dim)
    if d == 2:  # facets are edges: half their length
        r = 0.5 * np.linalg.norm(p[:, :, 1] - p[:, :, 0], axis=-1)
    else:  # triangles: R = abc / (4 area)
        a = p[:, :, 1] - p[:, :, 0]
        b = p[:, :, 2] - p[:, :, 0]
        c = p[:, :, 2] - p[:, :, 1]
        area2 = np.linalg.norm(np.cross(a, b), axis=-1)  # twice the area
        num = (
            np.linalg.norm(a, axis=-1)
            * np.linalg.norm(b, axis=-1)
            * np.linalg.norm(c, axis=-1)
        )
        r = np.full(area2.shape, np.inf)
        np.divide(num, 2.0 * area2, out=r, where=area2 > 0.0)
    if h_local is None:
        return r.max(axis=1) < alpha * h
    hl = np.asarray(h_local, dtype=float).reshape(-1)
    return r.max(axis=1) < alpha * hl[simplices].max(axis=1)


def _regular_triangulation(
    x: NDArray[np.float64], h: float, jitter: float, seed: int
) -> NDArray[np.intp]:
    """Delaunay triangulation with ties broken by perturbing the lifted coordinate.

    Returns the candidate simplices (arbitrary orientation), or an empty array if
    qhull cannot triangulate the points (all collinear or coplanar).
    """
    n, d = x.shape
    # Centre and scale by h so the lifted coordinate is O((L/h)^2) and the
    # perturbation is a fixed fraction of h^2 whatever the units.
    xs = (x - x.mean(axis=0)) / h
    lift = np.einsum("ij,ij->i", xs, xs)
    if jitter > 0.0:
        lift = lift + jitter * np.random.default_rng(seed).uniform(-1.0, 1.0, n)
    lifted = np.column_stack([xs, lift])
    hull = None
    # "Qt" (triangulated output) can stop with a precision error ("twisted
    # facet") on near-lattice 3D point sets, e.g. a cubic lattice after one small
    # step (tests/data/qhull_twisted_facet_3d.npz); qhull's joggled input "QJ"
    # always gives simplicial facets.  It is only the fallback, so that runs that
    # never need it are unchanged.
    for options in ("Qt Qbb", "QJ Qbb"):
        try:
            hull = ConvexHull(lifted, qhull_options=options)
            break
        except (QhullError, ValueError):
            continue
    if hull is None:
        return np.empty((0, d + 1), dtype=np.intp)
    # Lower hull facets (outward normal pointing down the lifted axis) project
    # onto the triangulation; vertical facets project to flat simplices, which
    # the volume test removes.
    lower = hull.equations[:, d] < 0.0
    return np.ascontiguousarray(hull.simplices[lower], dtype=np.intp)


def _validate_points(points: ArrayLike) -> NDArray[np.float64]:
    allowed = "a finite real array of shape (N, d) with d in {2, 3} and N >= d + 1"
    try:
        arr = np.asarray(points)
    except (TypeError, ValueError) as exc:
        raise ParameterError("points", points, allowed) from exc
    desc = f"array of shape {arr.shape}, dtype {arr.dtype}"
    if arr.dtype.kind not in "biuf":
        raise ParameterError("points", desc, allowed)
    if arr.ndim != 2 or arr.shape[1] not in (2, 3):
        raise ParameterError("points", desc, allowed)
    if arr.shape[0] < arr.shape[1] + 1:
        raise ParameterError(
            "points", desc, allowed + f" (got N = {arr.shape[0]} points)"
        )
    x = np.array(arr, dtype=np.float64, order="C")
    bad = ~np.isfinite(x).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ParameterError(
            "points",
            desc,
            allowed + f" (row {i} is {x[i].tolist()}; {int(bad.sum())} bad rows)",
        )
    return x


def _to_float(name: str, value: object) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ParameterError(name, value, "a real number")
    return float(value)


def _positive_float(name: str, value: object) -> float:
    v = _to_float(name, value)
    if not (math.isfinite(v) and v > 0.0):
        raise ParameterError(name, value, "a finite number > 0")
    return v


def _float_in(name: str, value: object, lo: float, hi: float) -> float:
    v = _to_float(name, value)
    if not (math.isfinite(v) and lo <= v <= hi):
        rng = f"in [{lo}, {hi}]" if math.isfinite(hi) else f">= {lo}"
        raise ParameterError(name, value, f"a finite number {rng}")
    return v


def check_triangulation(tri: object) -> None:
    """Raise :class:`ParameterError` unless ``tri`` is a :class:`Triangulation`."""
    if not isinstance(tri, Triangulation):
        raise ParameterError(
            "tri", type(tri).__name__, "a Triangulation from alpha_shape()"
        )
