"""Mesh sources: how the particles become a mesh for one step.

A mesh source (:class:`MeshSource`) is called by :func:`~skfem_npfem.advance`
with the particle positions at the start of a step and returns the active
particles and the (local) connectivity of that step's mesh.
:class:`FixedMesh` keeps one connectivity (small deformations);
:class:`AlphaShapeMesher` is the PFEM one: it runs
:func:`~skfem_npfem.mesh.delaunay.alpha_shape` afresh every step.  Nothing is
mapped between meshes: every state variable lives on the particles, so the mesh is
thrown away after the step.  The last triangulation is kept for output (cells,
free-surface flags).  :func:`main_body` finds the main body of a flow for
run-out measurements.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from skfem import Mesh

from ..errors import NpfemError, ParameterError
from .delaunay import Triangulation, alpha_shape
from .smoothing import check_p1_mesh
from .surface import free_surface

__all__ = [
    "AlphaShapeMesher",
    "FixedMesh",
    "MeshSource",
    "Wall",
    "as_mesh_source",
    "folded_facets",
    "main_body",
    "mesh_particles",
    "seal_with",
]


class Wall(Protocol):
    """What a mesher reads of a wall (:class:`~skfem_npfem.RigidWall`)."""

    def gap(self, x: np.ndarray) -> np.ndarray:
        """Signed distance of points (n, d) from the wall (positive: body side)."""
        ...


class MeshSource(Protocol):
    """Turns particle positions into a mesh for one step."""

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(active_index (N_a,), local_t (d+1, ne))`` for positions x."""
        ...


@dataclass
class FixedMesh:
    """Keep the initial connectivity (small-deformation problems, no remeshing).

    Parameters
    ----------
    t : skfem.Mesh or ndarray (d+1, ne)
        The mesh the particles were made from (a ``MeshTri``/``MeshTet``, as
        for :meth:`~skfem_npfem.Particles.from_mesh`: particle ``i`` is node
        ``i``), or its connectivity over all particles (every particle in an
        element).  ``FixedMesh(mesh)`` and ``FixedMesh(mesh.t)`` are the same
        mesh source.

    Raises
    ------
    ParameterError
        If ``t`` is a scikit-fem mesh other than P1 triangles/tetrahedra; when
        called, if ``t`` indexes particles that do not exist, a mesh has
        another number of nodes than there are particles, or the mesh is
        tangled (two elements on the same side of a shared side).
    NpfemError
        When called, if an element has turned inside out: the deformation is
        too large for a fixed connectivity (use smaller steps).

    Examples
    --------
    >>> from skfem import MeshTri
    >>> mesh = MeshTri().refined(1)
    >>> active, t = FixedMesh(mesh)(mesh.p.T)
    >>> active.size, t.shape
    (9, (3, 8))
    """

    t: np.ndarray

    def __post_init__(self) -> None:
        self._n_nodes: int | None = None
        if isinstance(self.t, Mesh):
            mesh = check_p1_mesh(self.t, "t")
            self._n_nodes = int(mesh.p.shape[1])
            self.t = mesh.t
        self.t = np.asarray(self.t, dtype=np.int64)
        self._active = np.unique(self.t)
        self._signs: np.ndarray | None = None

    def _check_orientation(self, x: np.ndarray) -> None:
        """Refuse a folded mesh: tangled at the start, or an element flipped later."""
        d = x.shape[1]
        if self.t.shape[0] != d + 1:
            return
        v = x[self.t[1:]] - x[self.t[0]][None]  # (d, ne, d)
        signs = np.sign(np.linalg.det(np.moveaxis(v, 0, 1)))
        if self._signs is None:
            folded = folded_facets(x, self.t)
            if folded.size:
                a, b = (int(e) for e in folded[0])
                raise ParameterError(
                    "t",
                    f"a tangled mesh: {len(folded)} shared side(s) with both "
                    f"elements on the same side, first elements {a} and {b}",
                    "a mesh whose elements do not overlap (an inverted element "
                    "folds over its neighbours; check the node order and positions)",
                )
            self._signs = signs
            return
        flipped = (signs * self._signs) < 0
        if np.any(flipped):
            e = int(np.flatnonzero(flipped)[0])
            raise NpfemError(
                f"{int(flipped.sum())} element(s) of the fixed mesh turned inside "
                f"out (first: element {e}); the deformation is too large for a "
                "fixed connectivity: use smaller steps (dt, or the load increment "
                "of a static run) or remeshing (AlphaShapeMesher)"
            )

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # noqa: D102
        n = x.shape[0]
        if self._n_nodes is not None and self._n_nodes != n:
            raise ParameterError(
                "particles",
                f"{n} particles",
                f"one particle per node of the mesh ({self._n_nodes} nodes; "
                "build them with Particles.from_mesh(mesh, ...))",
            )
        if self.t.size and (self.t.min() < 0 or self.t.max() >= n):
            raise ParameterError(
                "t",
                f"indices {int(self.t.min())}..{int(self.t.max())}",
                f"particle indices in 0..{n - 1}",
            )
        self._check_orientation(x)
        if self._active.size != x.shape[0]:
            local = np.searchsorted(self._active, self.t)
            return self._active, local
        return self._active, self.t


def as_mesh_source(source: MeshSource | Mesh | np.ndarray) -> MeshSource:
    """A mesh source from a mesh source, a scikit-fem mesh or a connectivity.

    A ``MeshTri``/``MeshTet`` or a connectivity array ``(d+1, ne)`` becomes a
    :class:`FixedMesh`; a callable (:class:`FixedMesh`,
    :class:`AlphaShapeMesher` or your own) is returned as it is.

    Raises
    ------
    ParameterError
        For anything else, or a scikit-fem mesh that is not P1 simplices.

    Examples
    --------
    >>> from skfem import MeshTri
    >>> type(as_mesh_source(MeshTri())).__name__
    'FixedMesh'
    """
    if isinstance(source, Mesh | np.ndarray):
        return FixedMesh(source)
    if callable(source):
        return source
    raise ParameterError(
        "mesh_source",
        type(source).__name__,
        "a scikit-fem MeshTri/MeshTet, a connectivity array (d+1, ne), or a "
        "mesh source such as FixedMesh or AlphaShapeMesher",
    )


class AlphaShapeMesher:
    """Remesh every step: Delaunay plus the alpha-shape test.

    Parameters
    ----------
    h : float
        Characteristic particle spacing, m (the initial lattice spacing).
    alpha : float
        Alpha-shape factor: simplices with circumradius ``>= alpha * h`` are
        dropped (1.2-1.6; larger keeps thin fronts longer but bridges gaps).
    walls : sequence of Wall
        Walls (e.g. :class:`~skfem_npfem.RigidWall`) used to tell free-surface
        particles from boundary particles that rest on a wall (within
        ``wall_distance * h`` of it).
    wall_distance : float
        Distance from a wall, in units of ``h``, under which a boundary particle
        is "on the wall" rather than on the free surface.
    min_quality, jitter : float
        Passed to :func:`~skfem_npfem.mesh.delaunay.alpha_shape` (defaults 1e-3 and
        1e-6); the jitter is deterministic, so equal positions give equal
        meshes (restarts reproduce).
    seed : int
        Seed of the jitter (default 0).
    spacing : array_like (N,), optional
        Initial spacing of each particle, m, for a graded lattice: the alpha
        test then uses the largest spacing of a simplex's particles (``h`` is
        the finest, :func:`~skfem_npfem.mesh.delaunay.alpha_shape`'s
        ``h_local``).  Particles keep their index, so the spacing travels with
        them.  None (default): ``h`` everywhere.
    keep_buried_slivers : bool or None
        Passed to :func:`~skfem_npfem.mesh.delaunay.alpha_shape`: mesh the
        slivers buried in the body.  None (default): in 3D only, where a
        nearly cubic lattice leaves the kept tetrahedra non-conforming
        otherwise; a 2D lattice has no slivers.
    seal_cavities : bool, default False
        Keep meshed the holes the alpha test would open inside the body: those
        that reach the outside only through supported particles (a prescribed
        velocity, or within ``wall_distance * h`` of one of ``walls``), or not
        at all (:mod:`~skfem_npfem.mesh.cavities`).  The step gives the mesher
        its particles' supports first (:func:`seal_with`,
        :func:`mesh_particles`).

    Attributes
    ----------
    last : Triangulation or None
        Triangulation of the last call (the mesh the last step was solved on).
    closed : ndarray (N,) bool or None
        With ``seal_cavities``: the particles the next triangulation treats as
        supported (set by :func:`seal_with`).

    Raises
    ------
    ParameterError
        If ``h``, ``alpha`` or ``wall_distance`` is not a finite number > 0;
        when called, if the alpha shape keeps no simplex (increase ``alpha``
        or ``h``).

    Examples
    --------
    >>> import numpy as np
    >>> g = np.linspace(0.0, 1.0, 5)
    >>> x = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    >>> mesher = AlphaShapeMesher(h=0.25)
    >>> active, t = mesher(x)
    >>> active.size, t.shape
    (25, (3, 32))
    """

    def __init__(
        self,
        h: float,
        alpha: float = 1.3,
        *,
        walls: Sequence[Wall] = (),
        wall_distance: float = 0.5,
        min_quality: float = 1e-3,
        jitter: float = 1e-6,
        seed: int = 0,
        spacing: np.ndarray | None = None,
        keep_buried_slivers: bool | None = None,
        seal_cavities: bool = False,
    ) -> None:
        for name, val in (("h", h), ("alpha", alpha), ("wall_distance", wall_distance)):
            if not (isinstance(val, int | float) and math.isfinite(val) and val > 0):
                raise ParameterError(name, val, "a finite number > 0")
        self.h = float(h)
        self.alpha = float(alpha)
        self.walls = list(walls)
        self.wall_distance = float(wall_distance)
        self.min_quality = min_quality
        self.jitter = jitter
        self.seed = seed
        self.keep_buried_slivers = keep_buried_slivers
        self.seal_cavities = bool(seal_cavities)
        self.closed: np.ndarray | None = None  # set per step with seal_cavities
        self.spacing = None
        if spacing is not None:
            hl = np.asarray(spacing, dtype=float).reshape(-1)
            if not np.all(np.isfinite(hl) & (hl > 0)):
                raise ParameterError("spacing", "values <= 0", "spacings > 0 (m)")
            self.spacing = hl
        self.last: Triangulation | None = None
        self._memo: tuple | None = None  # (positions, spacing, tri, settings)

    def triangulate(self, x: np.ndarray) -> Triangulation:
        """Alpha-shape triangulation of positions ``x`` (N, d).

        The same positions, spacings and settings as the last call give the
        last triangulation back (a refined run triangulates its particles
        before the step does; the triangulation is read-only and
        deterministic).
        """
        memo, settings = self._memo, self._settings()
        if (
            memo is not None
            and memo[3] == settings
            and np.array_equal(memo[0], x)
            and (memo[1] is None) == (self.spacing is None)
            and (self.spacing is None or np.array_equal(memo[1], self.spacing))
        ):
            return memo[2]
        tri = self._triangulate(x)
        spacing = None if self.spacing is None else self.spacing.copy()
        self._memo = (np.array(x, dtype=float), spacing, tri, settings)
        return tri

    def _settings(self) -> tuple:
        """What a triangulation depends on besides the positions and spacings."""
        keep = self.keep_buried_slivers
        closed = None if self.closed is None else self.closed.tobytes()
        return (
            self.h,
            self.alpha,
            self.min_quality,
            self.jitter,
            self.seed,
            keep,
            closed,
        )

    def _triangulate(self, x: np.ndarray) -> Triangulation:
        extra = {}
        closed = self.closed if self.seal_cavities else None
        for name, given, key in (
            ("spacing", self.spacing, "h_local"),
            ("closed", closed, "closed"),
        ):
            if given is None:
                continue
            if given.size != x.shape[0]:  # closed: seal_with gives one per particle
                raise ParameterError(
                    name, f"{given.size} values", f"one per particle ({x.shape[0]})"
                )
            extra[key] = given
        return alpha_shape(
            x,
            self.h,
            self.alpha,
            min_quality=self.min_quality,
            jitter=self.jitter,
            seed=self.seed,
            keep_buried_slivers=(
                x.shape[1] == 3
                if self.keep_buried_slivers is None
                else bool(self.keep_buried_slivers)
            ),
            **extra,
        )

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Remesh ``x``; return ``(active_index (N_a,), local_t (d+1, ne))``."""
        tri = self.triangulate(x)
        if tri.simplices.shape[0] == 0:
            raise ParameterError(
                "particles",
                f"{x.shape[0]} particles",
                "the alpha shape kept no simplex; increase alpha or h "
                f"(alpha={self.alpha:g}, h={self.h:g} m)",
            )
        self.last = tri
        return tri.active_index, np.ascontiguousarray(tri.local_simplices.T)

    def on_wall(self, tri: Triangulation | None = None) -> np.ndarray:
        """Particles within ``wall_distance * h`` of any wall (N,) bool."""
        tri = self.last if tri is None else tri
        near = np.zeros(tri.points.shape[0], bool)
        for wall in self.walls:
            near |= wall.gap(tri.points) < self.wall_distance * self.h
        return near

    def free_surface(self) -> np.ndarray | None:
        """Free-surface flags of the last mesh: boundary particles off the walls.

        Returns None before the first call.
        """
        if self.last is None:
            return None
        return free_surface(self.last, self.on_wall())


def seal_with(mesh_source: Any, particles: Any) -> None:
    """Give a mesher that seals cavities (``seal_cavities``) the supports.

    Its next triangulation of ``particles`` keeps the cavities that open only
    onto supported particles (:mod:`~skfem_npfem.mesh.cavities`): those with a
    prescribed velocity and those within ``wall_distance * h`` of one of the
    mesher's walls (a cone's axis).  A mesher without ``seal_cavities`` is left
    as it is.
    """
    if not getattr(mesh_source, "seal_cavities", False):
        return
    closed = np.asarray(particles.fixed, bool).any(axis=1)
    for wall in mesh_source.walls:
        closed |= wall.gap(particles.x) < mesh_source.wall_distance * mesh_source.h
    mesh_source.closed = closed


def mesh_particles(mesh_source: Any, particles: Any) -> tuple[np.ndarray, np.ndarray]:
    """The mesh ``mesh_source`` gives for ``particles``, told their supports first.

    :func:`seal_with`, then ``mesh_source(particles.x)``: every mesh of a run
    (the step's, a baseline's, the one written) is built so, sealed alike.

    Returns
    -------
    active, local_t : ndarray
        As :class:`MeshSource`.
    """
    seal_with(mesh_source, particles)
    return mesh_source(particles.x)


def folded_facets(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Pairs of elements that lie on the same side of the facet they share.

    In a valid mesh the two elements sharing an interior edge (2D) or face
    (3D) lie on opposite sides of it, whatever the order of their nodes; an
    inverted (tangled) element lies on the same side as its neighbour.  A
    facet shared by more than two elements also folds the mesh.

    Parameters
    ----------
    x : ndarray (N, d)
        Node positions.
    t : ndarray (d+1, ne)
        Connectivity.

    Returns
    -------
    ndarray (n_folded, 2)
        Element pairs, empty for a valid mesh.

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    >>> folded_facets(x, np.array([[0, 1, 2], [1, 3, 2]]).T).shape
    (0, 2)
    >>> x[3] = [0.2, 0.2]  # node 3 pulled across the shared edge 1-2
    >>> folded_facets(x, np.array([[0, 1, 2], [1, 3, 2]]).T).tolist()
    [[0, 1]]
    """
    t = np.asarray(t, dtype=np.int64)
    nv, ne = t.shape
    d = nv - 1
    if ne < 2 or x.shape[1] != d:
        return np.zeros((0, 2), np.int64)
    # facet k of element e: all nodes but the k-th; the k-th is "opposite"
    local = np.array([[j for j in range(nv) if j != k] for k in range(nv)])
    facets = np.sort(t[local].transpose(2, 0, 1).reshape(ne * nv, d), axis=1)
    opposite = t.T.reshape(-1)  # element-major: (e, k) -> t[k, e]
    owner = np.repeat(np.arange(ne), nv)
    _, inv, counts = np.unique(facets, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    order = np.argsort(inv, kind="stable")
    shared = np.flatnonzero(counts[inv[order]] == 2)[::2]
    i, j = order[shared], order[shared + 1]
    base = x[facets[i, 0]]
    span = np.stack([x[facets[i, k]] - base for k in range(1, d)], axis=1)

    def side(p: np.ndarray) -> np.ndarray:
        return np.sign(np.linalg.det(np.concatenate([span, (p - base)[:, None]], 1)))

    same = side(x[opposite[i]]) * side(x[opposite[j]]) > 0
    pairs = [np.stack([owner[i[same]], owner[j[same]]], axis=1)]
    for f in np.flatnonzero(counts > 2)[:10]:  # facets in 3+ elements (rare)
        e = owner[inv == f]
        pairs.append(np.array([[e[0], e[1]]]))
    return np.concatenate(pairs).astype(np.int64)


def main_body(x: np.ndarray, radius: float) -> np.ndarray:
    """Particles of the largest cluster of a particle cloud (N,) bool.

    Two particles are linked when they are closer than ``radius``; the main body
    is the largest set of linked particles.  Unlike the connectivity of an alpha
    shape (which breaks and heals as a thin spreading front thins out), this
    keeps a sparse deposit tail attached as long as its gaps stay below
    ``radius``; grains that flew further away are left out.

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [9.0, 0.0]])
    >>> main_body(x, radius=1.5).tolist()
    [True, True, True, False]
    """
    n = x.shape[0]
    pairs = cKDTree(x).query_pairs(radius, output_type="ndarray")
    graph = sp.coo_matrix(
        (np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(n, n)
    )
    _, labels = connected_components(graph, directed=False)
    return labels == np.argmax(np.bincount(labels))
