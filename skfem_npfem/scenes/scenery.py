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

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Scenery", "box", "number", "time_label"]


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
