"""What a picture of a result shows besides the particles: a scene's scenery.

Each scene describes its own scenery (:attr:`Scene.scenery
<skfem_npfem.scenes.base.Scene>`): the floor, walls and footing, the initial
outline of the body, the reference run-out of the collapse, the footing's
load-settlement curve and how to label a step (time, or settlement for the
footing, whose pseudo-time is its settlement).  This module holds the
description (:class:`Scenery`) and the small helpers the scenes share; the
drawing code (:mod:`skfem_npfem.viz`) reads it and holds no scene knowledge.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Scenery", "box", "number", "section_lines", "time_label"]


@dataclass
class Scenery:
    """Everything drawn around the particles of a 2D result.

    Attributes
    ----------
    scene : str
        Scene name ("" when unknown).
    floor : float or None
        Height of a rigid base (the collapse floor, the fixed base of the
        column and of the footing's soil block), m.
    floor_label : str
        Legend text of the base.
    walls : list of (float, int, str)
        Vertical walls: x position, the side the body is on (+1: right of the
        wall), legend text.
    outline : ndarray (n, 2) or None
        Closed polygon of the body at the start.
    footing : (float, float, float) or None
        ``(x0, x1, surface)``: the footing spans x0..x1 on the soil surface.
    symmetry : float or None
        x of a symmetry axis (the footing's half model, the axis of an
        axisymmetric section).
    symmetry_label : str
        Legend text of the symmetry axis.
    axes : (str, str)
        Names of the horizontal and vertical coordinates (``("r", "z")`` for
        an axisymmetric section).
    view : (float, float, float) or None
        3D: direction from the body to the camera (None: the isometric
        ``(1, 1, 1)``); with it the picture is a perspective view with the
        floor and axes in metres (the quarter cylinder looks at its two
        symmetry planes, where the interior of the column is).
    field_names : dict of str to str
        What a field is called in this scene when :data:`skfem_npfem.viz.loading.FIELDS`
        does not say it right (axisymmetry: ``stress_zz`` is the hoop stress).
    runout_reference : float or None
        Lube et al. (2005) final run-out, m from x = 0 (the collapse; Lube et
        al. 2004's run-out radius for an axisymmetric collapse).
    runout_label : str
        Legend text of the reference run-out (before its value).
    front : callable or None
        ``front(points, mass) -> float``: the run-out of a step (the collapse:
        its 99 % mass front), m, drawn as a line (None: none drawn).
    symmetric : bool
        Collapse against the wall at x = 0 (run-out measured from it).
    tau : float or None
        ``sqrt(H0 / g)`` of the collapse, s.
    load_curve : ndarray (n, 2) or None
        Footing: settlement (m) and pressure (Pa) per step.
    q_reference : float or None
        Footing: Prandtl-Reissner ``N_c c`` of a weightless soil, Pa.
    half_width : float or None
        Footing half width b, m.
    boundaries : ndarray (n, 2) or None
        Lines between the regions of a cross-section (layer boundaries), a
        polyline whose pieces are separated by rows of NaN.
    water_level : float or None
        Elevation of a horizontal water table, m, drawn across the picture.
    water_line : ndarray (n, 2) or None
        A section's water table, a polyline ``(x, z)`` (drawn instead of
        ``water_level``).
    window : (float, float, float, float) or None
        ``(x0, x1, y0, y1)``: the part of the domain the pictures show, m
        (None: every particle; the cone: a few D around the tip's path).
    window_note : str
        What the window is, said in the picture's title.
    factor_curve : ndarray (n, 2) or None
        Cone: ``w/D`` and the cone factor ``N_c`` per step.
    factor_reference : float or None
        Cone: Teh & Houlsby's cone factor.
    diameter : float or None
        Cone diameter D, m (the depth axis of the factor curve).
    unit : (str, str, float) or None
        The scene's own unit of ``--times`` and file names: file-name prefix,
        name and seconds per unit (the cone: ``("wD", "w/D", D / speed)``);
        None: time (or the footing's settlement).
    bodies : list of (ndarray (m, 2), ndarray (2,), str)
        Rigid bodies: the outline at time 0, the velocity (m/s) and the legend
        text; a picture of time t draws the outline moved by ``velocity * t``.
    label : callable
        ``label(t)``: the text naming a step of time t in titles.
    """

    scene: str = ""
    floor: float | None = None
    floor_label: str = "rigid base"
    walls: list[tuple[float, int, str]] = field(default_factory=list)
    outline: np.ndarray | None = None
    footing: tuple[float, float, float] | None = None
    symmetry: float | None = None
    symmetry_label: str = "symmetry axis"
    axes: tuple[str, str] = ("x", "y")
    field_names: dict[str, str] = field(default_factory=dict)
    view: tuple[float, float, float] | None = None
    runout_reference: float | None = None
    runout_label: str = "reference run-out"
    front: Callable[[np.ndarray, np.ndarray], float] | None = None
    symmetric: bool = True
    tau: float | None = None
    load_curve: np.ndarray | None = None
    q_reference: float | None = None
    half_width: float | None = None
    boundaries: np.ndarray | None = None
    water_level: float | None = None
    water_line: np.ndarray | None = None
    window: tuple[float, float, float, float] | None = None
    window_note: str = ""
    factor_curve: np.ndarray | None = None
    factor_reference: float | None = None
    diameter: float | None = None
    unit: tuple[str, str, float] | None = None
    bodies: list[tuple[np.ndarray, np.ndarray, str]] = field(default_factory=list)
    label: Callable[[float], str] = field(default=lambda t: f"t = {t:.4g} s")

    def settlement_label(self, t: float) -> str:
        """The footing's step label: settlement in mm and relative to B = 2b."""
        text = f"settlement s = {1e3 * t:.3g} mm"
        if self.half_width:
            text += f"  (s/B = {t / (2 * self.half_width):.3g})"
        return text


def box(x0: float, x1: float, y0: float, y1: float) -> np.ndarray:
    """The closed polygon of the rectangle ``[x0, x1] x [y0, y1]``."""
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])


def number(params: dict, name: str, default: float | None = None) -> float | None:
    """``params[name]`` as a finite float, else ``default`` (scene.json values)."""
    try:
        value = float(params[name])
    except (KeyError, TypeError, ValueError):
        return default
    return value if math.isfinite(value) else default


def time_label(tau: float, height: str = "H0") -> Callable[[float], str]:
    """A step label with the time in s and normalised by ``tau = sqrt(H/g)``."""
    return lambda t: f"t = {t:.3g} s   (t/\u221a({height}/g) = {t / tau:.2f})"


def section_lines(polygons: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The outline and the layer boundaries of a cross-section's regions.

    Each region's edges are cut at the other regions' vertices lying on
    them; a piece along another region's edge is a boundary between layers,
    the others are the section's outline.  Both are polylines whose pieces
    are separated by rows of NaN (empty: no row).

    Examples
    --------
    >>> low = box(0.0, 4.0, 0.0, 1.0)[:-1]
    >>> up = np.array([[0.0, 1.0], [2.0, 1.0], [0.0, 2.0]])
    >>> outline, between = section_lines([low, up])
    >>> between[~np.isnan(between[:, 0])].tolist()
    [[2.0, 1.0], [0.0, 1.0]]
    """
    edges = []  # (region, a, b)
    for k, poly in enumerate(polygons):
        p = np.asarray(poly, float)
        for a, b in zip(p, np.roll(p, -1, axis=0), strict=True):
            if np.linalg.norm(b - a) > 0:
                edges.append((k, a, b))
    size = max((float(np.ptp(np.asarray(q, float))) for q in polygons), default=1.0)
    tol = 1e-9 * max(size, 1.0)
    outer, inner = [], []
    for k, a, b in edges:
        d = b - a
        ts = [0.0, 1.0]
        for j, poly in enumerate(polygons):
            if j == k:
                continue
            q = np.asarray(poly, float)
            t = (q - a) @ d / (d @ d)
            off = np.linalg.norm(q - (a + np.outer(t, d)), axis=1)
            ts += [float(v) for v in t[(off < tol) & (t > 0) & (t < 1)]]
        ts = sorted(set(ts))
        for t0, t1 in itertools.pairwise(ts):
            p0, p1 = a + t0 * d, a + t1 * d
            mid = 0.5 * (p0 + p1)
            shared = any(_on_edge(mid, e[1], e[2], tol) for e in edges if e[0] != k)
            (inner if shared else outer).append((p0, p1))
    return _polyline(outer), _polyline(inner)


def _on_edge(x: np.ndarray, a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """Whether point ``x`` lies on the segment ``a``-``b``."""
    d = b - a
    t = float((x - a) @ d / (d @ d))
    return -tol <= t <= 1 + tol and float(np.linalg.norm(a + t * d - x)) < tol


def _polyline(pieces: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Segments as one polyline, NaN rows between them (shared edges once)."""
    seen, rows = set(), []
    for p0, p1 in pieces:
        key = tuple(sorted([tuple(np.round(p0, 9)), tuple(np.round(p1, 9))]))
        if key in seen:
            continue
        seen.add(key)
        rows += [p0, p1, np.full(2, np.nan)]
    return np.array(rows, float).reshape(-1, 2)
