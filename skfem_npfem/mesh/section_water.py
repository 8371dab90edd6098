"""The water of a cross-section: its phreatic line and its heads.

A cross-section file (:mod:`.section_file`) may give

* ``"water"``: the phreatic line, a polyline ``[[x, z], ...]`` with ``x``
  strictly increasing that spans the section's ``x``-range, or the name of a
  boundary of the section (a line of the file's ``"boundaries"`` or a line
  group of its mesh), whose points are then the line;
* ``"heads"``: the total heads of steady seepage, a list of
  ``{"boundary": NAME, "head": H}`` or ``{"line": [[x, z], ...], "head": H}``
  (``H`` in m, the elevation of the water level that the boundary sees).

The boundaries a head may name: ``base``, ``left``, ``right`` (the section's
lowest ``z``, smallest and largest ``x``: the points of its regions' polygons
there, in order), and every named line of the file (``"boundaries"`` of a
polygon section, the line groups of a mesh section), which replaces a built-in
one of the same name.

:func:`section_water` turns a section's phreatic line into the
:class:`~skfem_npfem.water.WaterTable` of a model.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from ..water.table import WaterTable
from .regions import CrossSection, Region

__all__ = [
    "BUILT_IN_BOUNDARIES",
    "read_boundaries",
    "read_heads",
    "read_polyline",
    "read_water",
    "section_boundaries",
    "section_water",
]

#: Boundaries every section has (the supports' base and sides).
BUILT_IN_BOUNDARIES = ("base", "left", "right")


def read_polyline(where: str, value: object) -> np.ndarray:
    """A polyline ``[[x, z], ...]`` of at least two finite points, checked."""
    try:
        line = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        line = np.zeros((0,))
    if line.ndim != 2 or line.shape[1] != 2 or len(line) < 2:
        raise ParameterError(
            where, value, "a polyline [[x, z], ...] of 2 points or more"
        )
    if not np.all(np.isfinite(line)):
        raise ParameterError(where, value, "finite coordinates (m)")
    return line


def read_boundaries(value: object) -> dict[str, np.ndarray]:
    """The ``"boundaries"`` key of a polygon section: name -> polyline (k, 2)."""
    if not isinstance(value, dict):
        raise ParameterError(
            "boundaries", value, "an object: name -> polyline [[x, z], ...]"
        )
    return {n: read_polyline(f"boundaries.{n}", v) for n, v in value.items()}


def section_boundaries(
    regions: list[Region], named: dict[str, np.ndarray]
) -> dict[str, np.ndarray]:
    """The boundaries of a section: the built-in ones and the file's ``named``.

    ``base``: the polygons' vertices at the lowest ``z``, by ``x``; ``left``
    and ``right``: those at the smallest and largest ``x``, by ``z``.
    """
    pts = np.unique(np.concatenate([r.polygon for r in regions]), axis=0)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    tol = 1e-9 * max(float(np.ptp(pts)), 1.0)
    out = {}
    for name, axis, at, along in (
        ("base", 1, lo[1], 0),
        ("left", 0, lo[0], 1),
        ("right", 0, hi[0], 1),
    ):
        side = pts[np.abs(pts[:, axis] - at) < tol]
        out[name] = side[np.argsort(side[:, along], kind="stable")]
    out.update(named)
    return out


def read_water(
    value: object, regions: list[Region], boundaries: dict[str, np.ndarray]
) -> np.ndarray:
    """The ``"water"`` key: the phreatic line (k, 2), checked against the section.

    Raises
    ------
    ParameterError
        ``water``: not a polyline or a boundary name, ``x`` not strictly
        increasing, or a line that does not span the section's ``x``-range
        (the message gives the range).
    """
    if isinstance(value, str):
        if value not in boundaries:
            raise ParameterError(
                "water",
                value,
                "a polyline [[x, z], ...] or a boundary of the section: "
                + ", ".join(boundaries),
            )
        line = boundaries[value]
        if len(line) > 1 and line[-1, 0] < line[0, 0]:
            line = line[::-1]
    else:
        line = read_polyline("water", value)
    line = WaterTable(line=line).line  # x strictly increasing, finite
    pts = np.concatenate([r.polygon for r in regions])
    lo, hi = float(pts[:, 0].min()), float(pts[:, 0].max())
    tol = 1e-9 * max(hi - lo, 1.0)
    if line[0, 0] > lo + tol or line[-1, 0] < hi - tol:
        raise ParameterError(
            "water",
            f"a line over x in [{line[0, 0]:g}, {line[-1, 0]:g}]",
            f"a line that spans the section's x-range [{lo:g}, {hi:g}] "
            "(extend it to both sides)",
        )
    return line


def read_heads(
    value: object, boundaries: dict[str, np.ndarray]
) -> list[tuple[str, np.ndarray, float]]:
    """The ``"heads"`` key: (boundary name, polyline, head) of each entry.

    A ``"line"`` entry is named ``heads[k]`` (its place in the file).

    Raises
    ------
    ParameterError
        Not a list of objects; an entry without exactly one of ``boundary``
        and ``line``; a boundary the section does not have (the message lists
        those it has); a head that is not a finite number.
    """
    if not isinstance(value, list):
        raise ParameterError(
            "heads", value, 'a list of {"boundary": NAME, "head": H (m)}'
        )
    out = []
    for k, entry in enumerate(value):
        where = f"heads[{k}]"
        if not isinstance(entry, dict) or ("boundary" in entry) == ("line" in entry):
            raise ParameterError(
                where,
                entry,
                'an object with "head" and one of "boundary" (a name) and '
                '"line" ([[x, z], ...])',
            )
        extra = set(entry) - {"boundary", "line", "head"}
        if extra:
            raise ParameterError(
                f"{where}.{sorted(extra)[0]}",
                entry[sorted(extra)[0]],
                "no such key: boundary or line, and head",
            )
        head = entry.get("head")
        if (
            isinstance(head, bool)
            or not isinstance(head, int | float)
            or not math.isfinite(head)
        ):
            raise ParameterError(f"{where}.head", head, "a finite head (m)")
        if "line" in entry:
            out.append(
                (where, read_polyline(f"{where}.line", entry["line"]), float(head))
            )
            continue
        name = entry["boundary"]
        if not isinstance(name, str) or name not in boundaries:
            raise ParameterError(
                f"{where}.boundary",
                name,
                "a boundary of the section: " + ", ".join(boundaries),
            )
        out.append((name, boundaries[name], float(head)))
    return out


def section_water(section: CrossSection, rho_w: float = 1000.0) -> WaterTable | None:
    """The water table of a section's phreatic line (None: a dry section).

    Parameters
    ----------
    section : CrossSection
        A section read by :func:`~skfem_npfem.mesh.section_file.read_cross_section`.
    rho_w : float
        Density of the water, kg/m^3: checked here (> 0) so that a bad value
        is refused with the section; the table itself does not depend on it
        (the model's :class:`~skfem_npfem.water.Water` carries it).

    Returns
    -------
    WaterTable or None

    Examples
    --------
    >>> sq = Region("soil", np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]]))
    >>> sec = CrossSection([sq], {"soil": {}}, water=np.array([[0.0, 1.0], [4.0, 1.5]]))
    >>> section_water(sec).elevation(np.array([[2.0, 0.0]]))
    array([1.25])
    """
    if (
        isinstance(rho_w, bool)
        or not isinstance(rho_w, int | float)
        or not (math.isfinite(rho_w) and rho_w > 0)
    ):
        raise ParameterError("rho_w", rho_w, "a density > 0 (kg/m^3)")
    if section.water is None:
        return None
    return WaterTable(line=section.water)
