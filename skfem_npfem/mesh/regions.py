"""Cross-sections from polygons: checked regions filled with particles and a mesh.

A cross-section is a list of simple, closed polygons (one per region, each
with a material).  :func:`check_regions` refuses what cannot be meshed (open or
self-intersecting polygons, overlapping regions, regions smaller than the
spacing) with one :class:`~skfem_npfem.errors.ParameterError` each, and
:func:`fill_regions` puts particles on the boundaries (spacing ``h`` along
every edge, shared edges once) and on a lattice inside (kept at least
``h/2`` from the boundaries), triangulates them (Delaunay) and keeps the
triangles whose centroid lies in a region.  A node on an edge shared by two
regions takes the material of the first region listed.

The geometry file of the ``slope`` scene (:func:`read_cross_section`) is JSON::

    {
      "materials": {
        "clay": {"c": 10000, "phi": 20, "rho": 2000},
        "sand": {"c": 0, "phi": 35, "rho": 1900, "E": 5e7, "nu": 0.3}
      },
      "regions": [
        {"material": "clay", "polygon": [[0, 0], [40, 0], [40, 5], [0, 5], [0, 0]]},
        {"material": "sand", "polygon": [[0, 5], [25, 5], [15, 15], [0, 15], [0, 5]]}
      ],
      "supports": {"base": "fixed", "sides": "rollers"}
    }

Lengths in m, stresses in Pa, angles in degrees, densities ``rho`` in kg/m^3 (the
unit weight is ``rho g``). A region may give its own ``"spacing"`` (finer where
asked: a thin layer, the zone where a slip is expected); edges it shares with
coarser regions take its points. A material may also give ``E``, ``nu`` and ``psi``
(defaults: the scene's). Polygons are closed: the last vertex repeats the first. The
base is the lowest ``y`` of the section (``fixed``: both velocities zero;
``rollers``: vertical only), the sides its smallest and largest ``x`` (``rollers``:
horizontal velocity zero; ``free``: no support).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial import Delaunay, cKDTree

from ..errors import ParameterError
from .simplices import orientation, segment_distance

__all__ = [
    "CrossSection",
    "Region",
    "check_regions",
    "fill_regions",
    "implausible_values",
    "point_in_polygon",
    "read_cross_section",
    "region_thickness",
]

#: Keys a material of a geometry file may have.
MATERIAL_KEYS = ("c", "phi", "psi", "rho", "E", "nu")
#: Physical ranges of a material's properties: (low, high, low open, high open, what).
MATERIAL_RANGES = {
    "c": (0.0, math.inf, False, True, "a cohesion >= 0 (Pa)"),
    "phi": (0.0, 90.0, False, True, "a friction angle in [0, 90) (degrees)"),
    "psi": (0.0, 90.0, False, True, "a dilation angle in [0, 90) (degrees)"),
    "rho": (0.0, math.inf, True, True, "a density > 0 (kg/m^3)"),
    "E": (0.0, math.inf, True, True, "a Young's modulus > 0 (Pa)"),
    "nu": (-1.0, 0.5, True, True, "a Poisson's ratio in (-1, 0.5)"),
}
#: Allowed supports.
BASES, SIDES = ("fixed", "rollers"), ("rollers", "free")


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
    """A cross-section: regions, materials (name -> properties), supports."""

    regions: list[Region]
    materials: dict[str, dict[str, float]]
    supports: dict[str, str] = field(
        default_factory=lambda: {"base": "fixed", "sides": "rollers"}
    )


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
        dist = [float(_segment_distance(samples[k], *ends[j]).min()) for j in others]
        j = others[int(np.argmin(dist))]
        gap = f"; it is {min(dist):.4g} m from the nearest region, regions[{j}]"
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
    gives t to within an eighth of a spacing, from below).

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
    gx = np.arange(lo[0] + step / 2, hi[0], step)
    gy = np.arange(lo[1] + step / 2, hi[1], step)
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
    pts = np.concatenate([bnd, inner])
    tri = Delaunay(pts).simplices
    cen = pts[tri].mean(axis=1)
    owner = np.full(len(tri), -1)
    for k in range(len(regions) - 1, -1, -1):
        owner[point_in_polygon(cen, regions[k].polygon)] = k
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


def _materials(mats: object) -> dict[str, dict[str, float]]:
    """The ``materials`` object of a cross-section file, checked."""
    if not isinstance(mats, dict) or not mats:
        raise ParameterError("materials", mats, "an object: name -> properties")
    materials: dict[str, dict[str, float]] = {}
    for name, props in mats.items():
        if not isinstance(props, dict):
            raise ParameterError(f"materials.{name}", props, "an object of properties")
        for key, val in props.items():
            where = f"materials.{name}.{key}"
            if key not in MATERIAL_KEYS:
                raise ParameterError(
                    where, val, "no such property: one of " + ", ".join(MATERIAL_KEYS)
                )
            if (
                isinstance(val, bool)
                or not isinstance(val, int | float)
                or not math.isfinite(val)
            ):
                raise ParameterError(where, val, "a finite number")
            lo, hi, lo_open, hi_open, what = MATERIAL_RANGES[key]
            if (
                val < lo
                or val > hi
                or (lo_open and val == lo)
                or (hi_open and val == hi)
            ):
                raise ParameterError(where, val, what)
        materials[name] = {k: float(v) for k, v in props.items()}
    return materials


def implausible_values(materials: dict[str, dict[str, float]]) -> list[str]:
    """One line for every material property that looks like a unit mistake.

    The file's units are SI (Pa, kg/m^3) and degrees; a value that is valid
    but implausible for a soil or rock most likely came in other units: a
    density ``rho`` outside 500-3000 kg/m^3 (a unit weight in kN/m^3, or
    t/m^3), a cohesion ``c`` below 100 Pa with a friction angle below 5
    degrees (kPa meant: such a soil hardly stands), a friction or dilation
    angle between 0 and 1 degree (radians meant; 0 is a purely cohesive
    soil), a Young's modulus ``E`` below 100 kPa (MPa meant).

    Parameters
    ----------
    materials : dict
        Material name -> properties, as in :class:`CrossSection`.

    Returns
    -------
    list of str
        The messages (empty when every value is plausible), each naming the
        property's place in the file (``materials.fill.phi``).

    Examples
    --------
    >>> implausible_values({"fill": {"rho": 20.0}})[0][:38]
    'materials.fill.rho = 20: a density in '
    >>> implausible_values({"clay": {"c": 20000.0, "phi": 10.0, "rho": 1900.0}})
    []
    """
    out = []
    for name, props in materials.items():
        rho, c, phi = props.get("rho"), props.get("c"), props.get("phi")
        if rho is not None and not 500 <= rho <= 3000:
            out.append(
                f"materials.{name}.rho = {rho:g}: a density in kg/m^3 is expected "
                "(soils and rocks 500-3000); a unit weight in kN/m^3 is about "
                f"rho g / 1000, so {rho:g} kN/m^3 would be rho = {rho * 1e3 / 9.81:.0f}"
            )
        if c is not None and c < 100 and (phi is None or phi < 5):
            out.append(
                f"materials.{name}.c = {c:g}: a cohesion in Pa is expected, and "
                f"below 100 Pa with a friction angle below 5 degrees a soil "
                f"hardly stands (kPa meant? {c:g} kPa is c = {c * 1e3:g})"
            )
        for key in ("phi", "psi"):
            val = props.get(key)
            if val is not None and 0 < val < 1:
                out.append(
                    f"materials.{name}.{key} = {val:g}: an angle in degrees is "
                    f"expected (radians meant? {val:g} rad is "
                    f"{math.degrees(val):.1f} degrees)"
                )
        E = props.get("E")
        if E is not None and E < 1e5:
            out.append(
                f"materials.{name}.E = {E:g}: a Young's modulus in Pa is expected "
                f"(soils 1e6-1e9; MPa meant? {E:g} MPa is E = {E * 1e6:g})"
            )
    return out


def _region(k: int, r: object, materials: dict[str, dict[str, float]]) -> Region:
    """Region ``k`` of a cross-section file, checked (the polygon left open)."""
    if not isinstance(r, dict) or "polygon" not in r or "material" not in r:
        raise ParameterError(
            f"regions[{k}]", r, "an object with 'material' and 'polygon'"
        )
    if r["material"] not in materials:
        raise ParameterError(
            f"regions[{k}].material",
            r["material"],
            "one of the materials of the file: " + ", ".join(materials),
        )
    try:
        poly = np.asarray(r["polygon"], dtype=float)
    except (TypeError, ValueError):
        poly = np.zeros((0,))
    if poly.ndim != 2 or poly.shape[1] != 2 or not np.all(np.isfinite(poly)):
        raise ParameterError(
            f"regions[{k}].polygon", r["polygon"], "a list of [x, y] vertices"
        )
    if len(poly) < 4 or not np.allclose(poly[0], poly[-1]):
        raise ParameterError(
            f"regions[{k}].polygon",
            f"{len(poly)} vertices, from {poly[0].tolist() if len(poly) else None} "
            f"to {poly[-1].tolist() if len(poly) else None}",
            "a closed polygon: at least 3 vertices and the last one repeating "
            "the first (this one is open)",
        )
    hr = r.get("spacing")
    if hr is not None and not (
        isinstance(hr, int | float)
        and not isinstance(hr, bool)
        and math.isfinite(hr)
        and hr > 0
    ):
        raise ParameterError(f"regions[{k}].spacing", hr, "a length > 0 (m)")
    return Region(r["material"], poly[:-1], hr)


def read_cross_section(path: str | Path) -> CrossSection:
    """Read and check the JSON geometry file (format in the module notes).

    Raises
    ------
    ParameterError
        For a file that cannot be read or parsed, a missing or unknown key, an
        open polygon, a region whose material is not in ``materials``, or a
        bad support.  Geometry checks that need the spacing are
        :func:`check_regions`.
    """
    p = Path(path)
    try:
        data = json.loads(p.read_text())
    except OSError as err:
        raise ParameterError(
            "geometry", str(path), f"a readable file ({err.strerror})"
        ) from None
    except json.JSONDecodeError as err:
        raise ParameterError(
            "geometry", str(path), f"a JSON file (line {err.lineno}: {err.msg})"
        ) from None
    if not isinstance(data, dict) or "regions" not in data or "materials" not in data:
        raise ParameterError(
            "geometry", str(path), "a JSON object with 'materials' and 'regions'"
        )
    materials = _materials(data["materials"])
    regions = [_region(k, r, materials) for k, r in enumerate(data["regions"])]
    supports = {"base": "fixed", "sides": "rollers"}
    for key, val in dict(data.get("supports", {})).items():
        allowed = {"base": BASES, "sides": SIDES}.get(key)
        if allowed is None:
            raise ParameterError(f"supports.{key}", val, "keys base and sides")
        if val not in allowed:
            raise ParameterError(f"supports.{key}", val, "one of " + ", ".join(allowed))
        supports[key] = val
    return CrossSection(regions, materials, supports)
