"""A cross-section drawn as a mesh file: its regions' outlines and named lines.

A cross-section file (:mod:`.section_file`) may give ``"mesh": "FILE"`` (gmsh
``.msh`` 2.2 or 4.1, or any plane triangle mesh with physical groups that
meshio reads) instead of polygons: its triangles, grouped by their physical
surface groups, are the regions, and its physical line groups are named
boundaries.  :func:`read_section_mesh` reads the file; :func:`group_outlines`
turns a group's triangles into the closed polygons around them (straight runs
of boundary nodes merged into one edge), so that a mesh section becomes the
same regions as the polygons a JSON section gives, and is filled with
particles the same way.
"""

from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass
from pathlib import Path

import meshio
import numpy as np

from ..errors import ParameterError

__all__ = ["SectionMesh", "group_outlines", "read_section_mesh"]

#: meshio cell types read as triangles and as lines (higher order: corners).
TRIANGLES, LINES = ("triangle", "triangle6"), ("line", "line3")


@dataclass
class SectionMesh:
    """A plane mesh's points, triangles by surface group, and named lines.

    ``groups`` and ``lines`` map a physical group's name (its number, as
    text, when the file names none) to its triangles (m, 3) and to its line
    segments (s, 2), indices into ``points`` (n, 2).
    """

    points: np.ndarray
    groups: dict[str, np.ndarray]
    lines: dict[str, np.ndarray]


def _tagged(mesh: meshio.Mesh, types: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Cells (corners) of ``types`` and their physical tags (-1: none)."""
    phys = mesh.cell_data.get("gmsh:physical")
    cells, tags = [], []
    for i, block in enumerate(mesh.cells):
        if block.type in types:
            n = 3 if block.type in TRIANGLES else 2
            cells.append(np.asarray(block.data)[:, :n])
            tag = -np.ones(len(block.data), int) if phys is None else phys[i]
            tags.append(np.asarray(tag, int))
    if not cells:
        n = 3 if types == TRIANGLES else 2
        return np.zeros((0, n), int), np.zeros(0, int)
    return np.concatenate(cells), np.concatenate(tags)


def read_section_mesh(path: str | Path) -> SectionMesh:
    """Read a plane section's mesh file.

    Raises
    ------
    ParameterError
        ``mesh``: a file meshio cannot read, a mesh out of the ``x``-``y``
        plane, one without triangles, or triangles in no physical group.
    """
    said = io.StringIO()
    try:
        # meshio prints what it could not read, and exits on a file it
        # cannot read in any format its suffix allows.
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            mesh = meshio.read(path)
    except (Exception, SystemExit) as err:  # meshio raises many kinds of error
        lines = [ln.strip() for ln in said.getvalue().splitlines() if ln.strip()]
        why = str(err) if isinstance(err, Exception) and str(err) else ""
        why = why or (lines[-1] if lines else type(err).__name__)
        raise ParameterError(
            "mesh",
            str(path),
            f"a mesh file that meshio reads, e.g. gmsh .msh 2.2 or 4.1 ({why})",
        ) from None
    pts = np.asarray(mesh.points, float)
    if pts.shape[1] > 2 and np.any(pts[:, 2:] != 0):
        raise ParameterError(
            "mesh", str(path), "a plane mesh in x-y (z = 0): the section's (x, z)"
        )
    tri, ttag = _tagged(mesh, TRIANGLES)
    if not len(tri):
        kinds = ", ".join(sorted({b.type for b in mesh.cells})) or "no cells"
        raise ParameterError(
            "mesh", str(path), f"a mesh with triangles (this one has {kinds})"
        )
    if np.any(ttag < 0):
        raise ParameterError(
            "mesh",
            str(path),
            f"every triangle in a physical surface group naming its region "
            f"({np.count_nonzero(ttag < 0)} of {len(tri)} are in none)",
        )
    seg, stag = _tagged(mesh, LINES)
    names = {dim: {} for dim in (1, 2)}
    for name, (tag, dim) in ((k, v[:2]) for k, v in mesh.field_data.items()):
        names.setdefault(int(dim), {})[int(tag)] = name
    groups = {names[2].get(t, str(t)): tri[ttag == t] for t in np.unique(ttag).tolist()}
    lines = {
        names[1].get(t, str(t)): seg[stag == t]
        for t in np.unique(stag[stag >= 0]).tolist()
    }
    return SectionMesh(pts[:, :2], groups, lines)


def _merge_straight(poly: np.ndarray) -> np.ndarray:
    """Drop the vertices that lie on the straight line of their neighbours."""
    prev, nxt = np.roll(poly, 1, axis=0), np.roll(poly, -1, axis=0)
    d, e = nxt - prev, poly - prev
    cross = np.abs(d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0])
    tol = 1e-9 * max(float(np.ptp(poly)), 1e-300)
    return poly[cross > tol * np.linalg.norm(d, axis=1)]


def _loops(edges: np.ndarray) -> list[list[int]] | None:
    """Closed loops of oriented edges (None: a vertex with two ways on)."""
    if len(np.unique(edges[:, 0])) < len(edges):
        return None
    nxt = dict(zip(edges[:, 0].tolist(), edges[:, 1].tolist(), strict=True))
    loops = []
    while nxt:
        start = next(iter(nxt))
        loop, v = [start], nxt.pop(start)
        while v != start:
            if v not in nxt:
                return None
            loop.append(v)
            v = nxt.pop(v)
        loops.append(loop)
    return loops


def group_outlines(name: str, points: np.ndarray, tri: np.ndarray) -> list[np.ndarray]:
    """Counter-clockwise outlines (first vertex not repeated) of a group's triangles.

    One polygon per connected piece of the group, from its lowest, then
    leftmost vertex.

    Raises
    ------
    ParameterError
        ``mesh group NAME``: a piece with a hole, or pieces that touch at a
        single node (neither is a simple polygon).
    """
    v = points[tri]
    a2 = (v[:, 1, 0] - v[:, 0, 0]) * (v[:, 2, 1] - v[:, 0, 1]) - (
        v[:, 1, 1] - v[:, 0, 1]
    ) * (v[:, 2, 0] - v[:, 0, 0])
    tri = np.where((a2 < 0)[:, None], tri[:, [0, 2, 1]], tri)
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    _, inv, cnt = np.unique(
        np.sort(e, axis=1), axis=0, return_inverse=True, return_counts=True
    )
    loops = _loops(e[cnt[inv.ravel()] == 1])
    where = f"mesh group {name!r}"
    if loops is None:
        raise ParameterError(
            where,
            f"{len(tri)} triangles",
            "pieces that touch along edges, not at a node",
        )
    out = []
    for loop in loops:
        poly = _merge_straight(points[loop])
        x, y = poly[:, 0], poly[:, 1]
        if np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)) < 0:
            raise ParameterError(
                where,
                f"a hole around ({x.mean():.4g}, {y.mean():.4g})",
                "regions without holes (a region is a simple polygon): split the "
                "group into pieces that have none",
            )
        # Start at the lowest, then leftmost vertex (as a section is drawn).
        out.append(np.roll(poly, -int(np.lexsort((x, y))[0]), axis=0))
    return out


def line_polyline(name: str, seg: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The points (k, 2) of a line group, in order along it.

    Raises
    ------
    ParameterError
        ``mesh line NAME``: a line that branches or is in several pieces.
    """
    ids, deg = np.unique(seg, return_counts=True)
    ends = ids[deg == 1]
    if np.any(deg > 2) or len(ends) != 2:
        raise ParameterError(
            f"mesh line {name!r}",
            f"{len(seg)} segments",
            "one line, open at both ends (not branched, closed or in pieces)",
        )
    nbr: dict[int, list[int]] = {}
    for a, b in seg.tolist():
        nbr.setdefault(a, []).append(b)
        nbr.setdefault(b, []).append(a)
    order, prev = [int(ends[0])], -1
    while len(order) <= len(seg):
        nxt = [w for w in nbr[order[-1]] if w != prev]
        if not nxt:
            break
        prev = order[-1]
        order.append(nxt[0])
    if len(order) != len(seg) + 1:
        raise ParameterError(
            f"mesh line {name!r}", f"{len(seg)} segments", "one connected line"
        )
    return points[order]
