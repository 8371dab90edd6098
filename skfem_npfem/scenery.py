"""What a picture of a result shows besides the particles: the scene's scenery.

:func:`scenery` reads ``scene.json`` of a result folder (written by the scene
runner) and returns a :class:`Scenery`: the floor, walls and footing, the
initial outline of the body, the reference run-out of the collapse (Lube et
al. 2005), the footing's load-settlement curve (from the run's checkpoint, or a
``summary.json`` in the folder) and how to label a step (time, or settlement
for the footing, whose pseudo-time is its settlement).  A folder without a
known scene gets an empty scenery: the pictures still have axes in metres.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["Scenery", "mass_front", "scenery"]

_GRAVITY = 9.81


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
        x of a symmetry axis (the footing's half model).
    runout_reference : float or None
        Lube et al. (2005) final run-out, m from x = 0 (the collapse; Lube et
        al. 2004's run-out radius for an axisymmetric collapse).
    runout_label : str
        Legend text of the reference run-out (before its value).
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
    runout_reference: float | None = None
    runout_label: str = "Lube et al. 2005: L\u221e"
    symmetric: bool = True
    tau: float | None = None
    load_curve: np.ndarray | None = None
    q_reference: float | None = None
    half_width: float | None = None
    label: Callable[[float], str] = field(default=lambda t: f"t = {t:.4g} s")

    def settlement_label(self, t: float) -> str:
        """The footing's step label: settlement in mm and relative to B = 2b."""
        text = f"settlement s = {1e3 * t:.3g} mm"
        if self.half_width:
            text += f"  (s/B = {t / (2 * self.half_width):.3g})"
        return text


def _box(x0: float, x1: float, y0: float, y1: float) -> np.ndarray:
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])


def _num(params: dict, name: str, default: float | None = None) -> float | None:
    try:
        value = float(params[name])
    except (KeyError, TypeError, ValueError):
        return default
    return value if math.isfinite(value) else default


def _collapse(s: Scenery, p: dict) -> None:
    from .scenes.column_collapse import lube_runout

    # (results of an older version name the half-width "length")
    a, L0 = _num(p, "aspect"), _num(p, "half_width") or _num(p, "length")
    if p.get("geometry") == "axisymmetric":
        _axisymmetric_collapse(s, p)
        return
    if a is None or L0 is None:
        return
    H0, g = a * L0, _num(p, "gravity", _GRAVITY) or _GRAVITY
    s.symmetric = bool(p.get("symmetric", True))
    s.floor, s.floor_label = 0.0, "rough floor"
    s.outline = _box(0.0 if s.symmetric else -L0, L0, 0.0, H0)
    if s.symmetric:
        s.walls.append((0.0, 1, "smooth wall (symmetry plane)"))
    s.runout_reference = L0 * (1.0 + lube_runout(a))
    s.tau = math.sqrt(H0 / g)
    tau = s.tau
    s.label = lambda t: f"t = {t:.3g} s   (t/\u221a(H0/g) = {t / tau:.2f})"


def _axisymmetric_collapse(s: Scenery, p: dict) -> None:
    """The (r, z) half-section of a cylindrical column: axis, floor, Lube 2004."""
    from .scenes.collapse_runs import lube2004_runout

    r0, h0 = _num(p, "radius"), _num(p, "height")
    if r0 is None or h0 is None:
        return
    g = _num(p, "gravity", _GRAVITY) or _GRAVITY
    s.floor, s.floor_label = 0.0, "rough floor"
    s.outline = _box(0.0, r0, 0.0, h0)
    s.walls.append((0.0, 1, "axis r = 0 (symmetry)"))
    s.runout_reference = r0 * (1.0 + lube2004_runout(h0 / r0))
    s.runout_label = "Lube et al. 2004: r\u221e"
    tau = s.tau = math.sqrt(h0 / g)
    s.label = lambda t: f"t = {t:.3g} s   (t/\u221a(h0/g) = {t / tau:.2f})"


def _column(s: Scenery, p: dict) -> None:
    H, W = _num(p, "height"), _num(p, "width")
    if H is None or W is None:
        return
    s.floor, s.floor_label = 0.0, "fixed base"
    s.walls += [(0.0, 1, "smooth side walls (rollers)"), (W, -1, "")]
    s.outline = _box(0.0, W, 0.0, H)
    if p.get("mode") == "static":
        s.label = lambda t: f"static load step (pseudo-time {t:.3g})"


def _footing(s: Scenery, p: dict, folder: Path) -> None:
    from .scenes.strip_footing import n_c

    b, domain = _num(p, "half_width"), _num(p, "domain")
    if b is None or domain is None:
        return
    L = domain * b
    s.half_width = b
    s.floor, s.floor_label = 0.0, "fixed base"
    s.walls.append((L, -1, "rollers"))
    s.symmetry = 0.0
    s.outline = _box(0.0, L, 0.0, L)
    s.footing = (0.0, b, L)
    s.label = s.settlement_label
    c, phi = _num(p, "c", 0.0), _num(p, "phi", 0.0)
    # unit weight: rho g (a result of an older version: its parameter gamma)
    gamma = _num(p, "gamma", 0.0) or _num(p, "rho", 0.0) * _num(p, "gravity", _GRAVITY)
    if p.get("material") == "tresca":
        phi = 0.0
    if gamma == 0 and c and c > 0:
        s.q_reference = n_c(phi or 0.0) * c
    s.load_curve = _load_curve(folder)


def _load_curve(folder: Path) -> np.ndarray | None:
    """The footing's [settlement, pressure] per step: summary or checkpoint."""
    records: list[dict] = []
    for name in ("summary.json",):
        try:
            data = json.loads((folder / name).read_text())
            curve = data["metrics"]["load_curve"]
            return np.array(curve, dtype=float).reshape(-1, 2)
        except (OSError, ValueError, KeyError, TypeError):
            continue
    from .errors import CheckpointError
    from .io import latest_checkpoint, load_checkpoint

    path = latest_checkpoint(folder)
    if path is None:
        return None
    try:
        _, meta = load_checkpoint(path)
        records = list(meta.get("records", []))
    except CheckpointError:
        return None
    rows = []
    for r in records:
        extra = r.get("extra", {}) if isinstance(r, dict) else {}
        if "settlement" in extra and "pressure" in extra:
            rows.append([extra["settlement"], extra["pressure"]])
    return np.array(rows, dtype=float).reshape(-1, 2) if rows else None


def _half_width(params: dict) -> float | None:
    """The collapse's L0: ``half_width`` (``length`` in older results)."""
    return _num(params, "half_width") or _num(params, "length")


def scenery(folder: str | Path) -> Scenery:
    """The scenery of the result in ``folder`` (from its ``scene.json``)."""
    folder = Path(folder)
    try:
        info: Any = json.loads((folder / "scene.json").read_text())
        params = dict(info.get("parameters", {}))
        name = str(info.get("scene", ""))
    except (OSError, ValueError, AttributeError, TypeError):
        return Scenery()
    s = Scenery(scene=name)
    if name == "column-collapse":
        _collapse(s, params)
    elif name == "elastic-column":
        _column(s, params)
    elif name == "strip-footing":
        _footing(s, params, folder)
    elif _num(params, "aspect") and _half_width(params):
        # an unknown scene with the collapse's scales: normalised time only
        H0 = _num(params, "aspect") * _half_width(params)
        tau = math.sqrt(H0 / (_num(params, "gravity", _GRAVITY) or _GRAVITY))
        s.tau = tau
        s.label = lambda t: f"t = {t:.3g} s   (t/\u221a(H0/g) = {t / tau:.2f})"
    return s


def mass_front(x: np.ndarray, mass: np.ndarray, symmetric: bool) -> float:
    """The collapse's run-out: the 99 % mass front (see the scene's notes)."""
    from .scenes.column_collapse import mass_front as front

    return float(front(np.asarray(x)[:, :2], np.asarray(mass), symmetric))
