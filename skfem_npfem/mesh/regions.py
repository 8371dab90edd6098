"""Cross-sections from polygons: checked regions filled with particles and a mesh.

A cross-section is a list of simple, closed polygons (one per region, each
with a material).  :func:`check_regions` refuses what cannot be meshed (open or
self-intersecting polygons, overlapping regions, regions smaller than the
spacing, regions that float: neither on the base nor sharing an edge with a
region that is) with one :class:`~skfem_npfem.errors.ParameterError` each,
naming the region; :func:`region_thickness` measures how thick a region is;
:func:`fill_regions` puts particles on the boundaries (spacing ``h`` along
every edge, shared edges once) and on a lattice inside (kept at least
``h/2`` from the boundaries), triangulates them (Delaunay) and keeps the
triangles whose centroid lies in a region.  A node on an edge shared by two
regions takes the material of the first region listed.

The JSON file of a cross-section is read and checked by
:mod:`.section_file`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import Delaunay, cKDTree

from ..errors import ParameterError
from .simplices import orientation, segment_distance

__all__ = [
    "CrossSection",
    "Region",
    "check_regions",
    "fill_regions",
    "mesh_regions",
    "point_in_polygon",
    "point_spacing",
    "region_thickness",
]


@dataclass
class Region:
    """One region: a closed polygon (first vertex not repeated) and a material.

    ``spacing``: the region's own particle spacing (finer where asked); None
    takes the section's.
    """

    material: str
    polygon: np.ndarray
    spacing: float | None = None


@dataclass
class CrossSection:
    """A cross-section: regions, materials (name -> properties), supports.

    ``water``: the phreatic line (k, 2), None for a dry section; ``heads``:
    (boundary name, polyline (k, 2), head in m) of each seepage boundary
    (:mod:`.section_water`).
    """

    regions: list[Region]
    materials: dict[str, dict[str, float]]
    supports: dict[str, str] = field(
        default_factory=lambda: {"base": "fixed", "sides": "rollers"}
    )
    water: np.ndarray | None = None
    heads: list[tuple[str, np.ndarray, float]] = field(default_factory=list)


def point_in_polygon(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd test of ``points`` (n, 2) against a polygon (m, 2), vectorised."""
    x, y = points[:, 0][:, None], points[:, 1][:, None]
    x0, y0 = poly[:, 0][None, :], poly[:, 1][None, :]
    x1, y1 = np.roll(poly[:, 0], -1)[None, :], np.roll(poly[:, 1], -1)[None, :]
    crosses = (y0 > y) != (y1 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
    return np.count_nonzero(crosses & (x < xc), axis=1) % 2 == 1


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of every point (n, 2) to the nearest of the segments a-b (m, 2)."""
    return segment_distance(points[:, None, :], a[None], b[None]).min(axis=1)


def _area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _proper_crossings(p: np.ndarray, q: np.ndarray, skip_adjacent: bool) -> bool:
    """Whether an edge of polygon p properly crosses an edge of q."""
    a, b = p, np.roll(p, -1, axis=0)
    c, d = q, np.roll(q, -1, axis=0)

    A, B = a[:, None, :], b[:, None, :]
    C, D = c[None, :, :], d[None, :, :]
    scale = max(float(np.ptp(p)), float(np.ptp(q)), 1e-300) ** 2
    eps = 1e-12 * scale
    o1, o2 = orientation(A, B, C), orientation(A, B, D)
    o3, o4 = orientation(C, D, A), orientation(C, D, B)
    cross = (o1 * o2 < -eps * eps) & (o3 * o4 < -eps * eps)
    cross &= (np.abs(o1) > eps) & (np.abs(o2) > eps)
    cross &= (np.abs(o3) > eps) & (np.abs(o4) > eps)
    if skip_adjacent:
        n = len(p)
        i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        cross &= (np.abs(i - j) > 1) & ~(
            ((i == 0) & (j == n - 1)) | ((j == 0) & (i == n - 1))
        )
    return bool(np.any(cross))


def check_regions(regions: list[Region], spacing: float) -> None:
    """Refuse polygons that cannot be meshed at ``spacing``.

    Raises
    ------
    ParameterError
        A polygon with fewer than 3 distinct vertices, a self-intersecting
        one, two regions that overlap, or a region whose area is below
        ``spacing^2`` (it would hold no particle inside).
    """
    if not regions:
        raise ParameterError("regions", [], "at least one region (a closed polygon)")
    for k, r in enumerate(regions):
        poly = r.polygon
        if len(np.unique(np.round(poly, 12), axis=0)) < 3:
            raise ParameterError(
                f"regions[{k}].polygon", poly.tolist(), "at least 3 distinct vertices"
            )
        if _proper_crossings(poly, poly, skip_adjacent=True):
            raise ParameterError(
                f"regions[{k}].polygon",
                f"{len(poly)} vertices",
                "a simple polygon: its edges cross each other (self-intersecting)",
            )
        area = abs(_area(poly))
        hr = spacing if r.spacing is None else r.spacing
        if area < hr**2:
            raise ParameterError(
                f"regions[{k}]",
                f"area {area:.4g} m^2",
                f"at least spacing^2 = {hr**2:.4g} m^2 (a region smaller than "
                "the spacing holds no particle; refine the spacing or drop it)",
            )
    # Overlap: an edge crossing, or a lattice point strictly inside two regions.
    lo = np.min([r.polygon.min(axis=0) for r in regions], axis=0)
    hi = np.max([r.polygon.max(axis=0) for r in regions], axis=0)
    step = spacing / 2
    gx = np.arange(lo[0] + step / 2, hi[0], step)
    gy = np.arange(lo[1] + step / 2, hi[1], step)
    grid = np.column_stack([g.ravel() for g in np.meshgrid(gx, gy)])
    inside = []
    for r in regions:
        mask = point_in_polygon(grid, r.polygon)
        a, b = r.polygon, np.roll(r.polygon, -1, axis=0)
        if mask.any():
            far = _segment_distance(grid[mask], a, b) > 1e-9 * spacing
            idx = np.flatnonzero(mask)
            mask[idx[~far]] = False
        inside.append(mask)
    for i in range(len(regions)):
        for j in range(i + 1, len(regions)):
            both = inside[i] & inside[j]
            crossing = _proper_crossings(
                regions[i].polygon, regions[j].polygon, skip_adjacent=False
            )
            if both.any() or crossing:
                raise ParameterError(
                    f"regions[{j}]",
                    f"material {regions[j].material!r}",
                    f"regions that do not overlap (it overlaps regions[{i}]); "
                    "neighbouring regions share edges",
                )
    _check_supported(regions, spacing)


def _edge_samples(poly: np.ndarray, step: float) -> np.ndarray:
    """Points inside the edges of a polygon (no vertex), ``step`` apart at most."""
    a, b = poly, np.roll(poly, -1, axis=0)
    n = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / step)).astype(int)
    k = np.repeat(np.arange(len(a)), n)
    t = (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n) + 0.5) / np.repeat(n, n)
    return a[k] + t[:, None] * (b[k] - a[k])


def _check_supported(regions: list[Region], spacing: float) -> None:
    """Refuse a region that neither rests on the base nor shares an edge with one.

    Two regions are neighbours when they share a stretch of edge (touching at a
    corner only is a hinge, not a support); a region is supported when a chain
    of neighbours leads to a region with an edge on the base (the section's
    lowest ``y``).  Anything else floats: no stress field carries its weight,
    and its limit analysis or strength reduction could not end.
    """
    allp = np.concatenate([r.polygon for r in regions])
    tol = 1e-9 * max(float(np.ptp(allp)), spacing)
    base = float(allp[:, 1].min())
    samples = [_edge_samples(r.polygon, spacing / 4) for r in regions]
    ends = [(r.polygon, np.roll(r.polygon, -1, axis=0)) for r in regions]
    held = np.array([bool(np.any(np.abs(s[:, 1] - base) < tol)) for s in samples])
    n = len(regions)
    touch = np.zeros((n, n), bool)
    for i in range(n):
        for j in range(n):
            if i != j:
                touch[i, j] = bool(
                    np.any(_segment_distance(samples[i], *ends[j]) < tol)
                )
    touch |= touch.T
    for _ in range(n):
        held = held | (touch & held[None, :]).any(axis=1)
    if held.all():
        return
    k = int(np.flatnonzero(~held)[0])
    others = [j for j in range(n) if j != k]
    gap = ""
    if others:
        pts = np.concatenate([samples[k], regions[k].polygon])
        dist = [float(_segment_distance(pts, *ends[j]).min()) for j in others]
        j = others[int(np.argmin(dist))]
        gap = (
            f"; it touches regions[{j}] at a point only (a hinge)"
            if min(dist) < tol
            else f"; it is {min(dist):.4g} m from the nearest region, regions[{j}]"
        )
    raise ParameterError(
        f"regions[{k}]",
        f"material {regions[k].material!r}",
        "a region that rests on the base (the lowest y of the section) or shares "
        "a stretch of edge with a region that does; this one floats, so nothing "
        f"carries its weight{gap}",
    )


def region_thickness(region: Region, spacing: float) -> float:
    """Thickness of a region: the diameter of the largest circle inside it.

    Measured on a lattice of step ``spacing / 8`` (a layer of thickness t
    gives t to within a sixteenth of a spacing, from below; exactly when the
    layer is a whole number of eighths of a spacing thick).

    Parameters
    ----------
    region : Region
        The region.
    spacing : float
        The section's spacing (the region's own, if it has one, is used).

    Returns
    -------
    float
        The thickness, m.

    Examples
    --------
    >>> square = np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 2.0], [0.0, 2.0]])
    >>> abs(region_thickness(Region("clay", square), 1.0) - 2.0) <= 1.0 / 8
    True
    """
    h = spacing if region.spacing is None else region.spacing
    poly = region.polygon
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    step = h / 8
    gx = np.arange(lo[0], hi[0] + step / 2, step)
    gy = np.arange(lo[1], hi[1] + step / 2, step)
    grid = np.column_stack([g.ravel() for g in np.meshgrid(gx, gy)])
    grid = grid[point_in_polygon(grid, poly)]
    if not grid.size:
        return 0.0
    a, b = poly, np.roll(poly, -1, axis=0)
    dist = np.concatenate(
        [
            _segment_distance(g, a, b)
            for g in np.array_split(grid, 1 + len(grid) // 4096)
        ]
    )
    return 2 * float(dist.max())


def fill_regions(
    regions: list[Region], spacing: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Particles and triangles of the regions at ``spacing``.

    Returns
    -------
    points : ndarray (n, 2)
    triangles : ndarray (3, m) int
        Counter-clockwise triangles (scikit-fem's ``t``).
    region : ndarray (n,) int
        Region index of every point (the first listed on shared edges).
    """
    h = float(spacing)
    hs = [h if r.spacing is None else float(r.spacing) for r in regions]
    # Vertices first, then edge points region by region from the finest.
    verts = [np.concatenate([r.polygon for r in regions])]
    bnd, local = [], []
    for k in np.argsort(hs, kind="stable"):
        a, b = regions[k].polygon, np.roll(regions[k].polygon, -1, axis=0)
        for p0, p1 in zip(a, b, strict=True):
            n = max(1, math.ceil(np.linalg.norm(p1 - p0) / hs[k] - 1e-9))
            t = np.arange(1, n)[:, None] / n
            bnd.append(p0 + t * (p1 - p0))
            local.append(np.full(n - 1, hs[k]))
    bnd = np.concatenate(verts + bnd)
    local = np.concatenate([np.zeros(len(verts[0])), *local])
    scale = max(float(np.ptp(bnd)), h)
    _, first = np.unique(np.round(bnd / (1e-9 * scale)), axis=0, return_index=True)
    first = np.sort(first)
    bnd, local = bnd[first], local[first]
    # Edges shared by regions of different spacings (or T-junctions) give
    # points closer than their spacing: keep the earlier (finer) one.
    pairs = cKDTree(bnd).query_pairs(0.3 * min(hs), output_type="ndarray")
    if pairs.size:
        i, j = pairs.min(axis=1), pairs.max(axis=1)
        close = np.linalg.norm(bnd[i] - bnd[j], axis=1) < 0.3 * np.maximum(
            local[j], 1e-300
        )
        keep = np.ones(len(bnd), bool)
        keep[j[close & (local[j] > 0)]] = False
        bnd = bnd[keep]
    inner = []
    edges_a = np.concatenate([r.polygon for r in regions])
    edges_b = np.concatenate([np.roll(r.polygon, -1, axis=0) for r in regions])
    for r, hr in zip(regions, hs, strict=True):
        lo, hi = r.polygon.min(axis=0), r.polygon.max(axis=0)
        gx = np.arange(lo[0] + hr / 2, hi[0], hr)
        gy = np.arange(lo[1] + hr / 2, hi[1], hr * math.sqrt(3) / 2)
        X, Y = np.meshgrid(gx, gy)
        X = X + (np.arange(gy.size)[:, None] % 2) * hr / 2  # triangular lattice
        grid = np.column_stack([X.ravel(), Y.ravel()])
        grid = grid[point_in_polygon(grid, r.polygon)]
        if grid.size:
            grid = grid[_segment_distance(grid, edges_a, edges_b) >= 0.5 * hr]
        inner.append(grid)
    inner = np.concatenate(inner) if inner else np.zeros((0, 2))
    return mesh_regions(np.concatenate([bnd, inner]), regions, h)


def _owners(centroids: np.ndarray, regions: list[Region]) -> np.ndarray:
    """Region of each centroid (the first listed where they overlap; -1: none)."""
    owner = np.full(len(centroids), -1)
    for k in range(len(regions) - 1, -1, -1):
        owner[point_in_polygon(centroids, regions[k].polygon)] = k
    return owner


def mesh_regions(
    pts: np.ndarray, regions: list[Region], h: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangulate points of the regions: Delaunay, kept where a region is.

    A triangle is kept when its centroid lies in a region and its area is
    above ``1e-10 h^2``; points no kept triangle uses are dropped.

    Parameters
    ----------
    pts : ndarray (n, 2)
        Points in (or on the boundaries of) the regions.
    regions : list of Region
    h : float
        The spacing that scales the area threshold, m.

    Returns
    -------
    points, triangles, region
        As :func:`fill_regions`.
    """
    tri = Delaunay(pts).simplices
    owner = _owners(pts[tri].mean(axis=1), regions)
    v = pts[tri]
    area2 = (v[:, 1, 0] - v[:, 0, 0]) * (v[:, 2, 1] - v[:, 0, 1]) - (
        v[:, 1, 1] - v[:, 0, 1]
    ) * (v[:, 2, 0] - v[:, 0, 0])
    keep = (owner >= 0) & (np.abs(area2) > 1e-10 * h * h)
    tri, owner, area2 = tri[keep], owner[keep], area2[keep]
    tri[area2 < 0] = tri[area2 < 0][:, [0, 2, 1]]
    used = np.unique(tri)
    new = np.full(len(pts), -1)
    new[used] = np.arange(used.size)
    region = np.full(used.size, len(regions))
    np.minimum.at(region, new[tri].ravel(), np.repeat(owner, 3))
    return pts[used], new[tri].T, region


def point_spacing(
    pts: np.ndarray, tri: np.ndarray, regions: list[Region], spacing: float
) -> np.ndarray | None:
    """Each point's spacing: the finest of the regions of its triangles.

    A region's own ``spacing`` (else ``spacing``) goes to the points of the
    triangles whose centroid it holds (the first listed region where regions
    overlap, as :func:`mesh_regions`); a point on an edge shared by regions of
    different spacings takes the finer, as :func:`fill_regions` placed it.

    Parameters
    ----------
    pts : ndarray (n, 2)
    tri : ndarray (3, m) int
        Triangles of the points (:func:`fill_regions`).
    regions : list of Region
    spacing : float
        The section's spacing, m.

    Returns
    -------
    ndarray (n,) or None
        Spacing per point, m; None when no region gives its own (every point
        at ``spacing``).

    Examples
    --------
    >>> a = Region("a", np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float))
    >>> b = Region("b", np.array([[0, 1], [2, 1], [2, 2], [0, 2]], float), 0.5)
    >>> pts, tri, _ = fill_regions([a, b], 1.0)
    >>> h = point_spacing(pts, tri, [a, b], 1.0)
    >>> sorted(set(h.tolist())), bool(np.all(h[pts[:, 1] >= 1.0 - 1e-9] == 0.5))
    ([0.5, 1.0], True)
    """
    if all(r.spacing is None for r in regions):
        return None
    hs = np.array([spacing if r.spacing is None else r.spacing for r in regions])
    owner = _owners(pts[tri.T].mean(axis=1), regions)
    out = np.full(pts.shape[0], np.inf)
    np.minimum.at(out, tri.T.ravel(), np.repeat(hs[owner], 3))
    return out
