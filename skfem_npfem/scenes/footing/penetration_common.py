"""What the penetration scenes share: graded lattices, interfaces, reports.

The footing (:mod:`~skfem_npfem.scenes.footing.penetration`) and the cone
(:mod:`~skfem_npfem.scenes.footing.cone`) build their soil on a graded lattice (its
growth is the strip footing's too), turn
the ``interface`` choice into an adhesion, warn about what makes a run's
loads doubtful, and the cone reads its steady factor off the curve.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np

from ...errors import ParameterError, warn_user
from ..params import Param
from ..soil_profile import check_layers
from ..water import derive_drainage
from .penetration_soil import derive_soil, refuse_soil

__all__ = [
    "ADHESION",
    "DROP",
    "DROP_WINDOW",
    "Steady",
    "axis_count",
    "count_drops",
    "derive_cone",
    "derive_footing",
    "graded_axis",
    "grow_axis",
    "grown_count",
    "interface_adhesion",
    "lattice_gap",
    "lattice_params",
    "locking_warnings",
    "penetration_warnings",
    "refuse_adhesion",
    "refuse_penetration",
    "running_drops",
    "steady_factor",
]

#: The ``adhesion`` parameter of ``interface=adhesion`` (footing and cone).
ADHESION = Param(
    "adhesion",
    0.5,
    "-",
    "adhesion factor alpha of interface=adhesion: |t| <= alpha s_u",
    float,
    lo=0.0,
    hi=1.0,
)


#: A load drop: a step whose load is under this fraction of the median load
#: of the steps around it (the footing's and the cone's definition).
DROP = 0.8

#: The window of :func:`running_drops`, in body widths (B or D) of push.
DROP_WINDOW = 0.5


def graded_axis(fine: float, h: float, length: float, ratio: float) -> np.ndarray:
    """Coordinates ``0..length``: spacing ``h`` up to ``fine``, then growing.

    Examples
    --------
    >>> graded_axis(1.0, 0.5, 3.0, 2.0).tolist()
    [0.0, 0.5, 1.0, 2.0, 3.0]
    """
    n_fine = max(1, math.ceil(min(fine, length) / h - 1e-9))
    xs = list(np.linspace(0.0, min(n_fine * h, length), n_fine + 1))
    return grow_axis(xs, xs[-1] - xs[-2], length, ratio)


def grow_axis(xs: list[float], step: float, length: float, ratio: float) -> np.ndarray:
    """``xs`` continued to ``length`` by gaps growing from ``step`` by ``ratio``.

    A last gap under 0.3 of the one before is merged into it.

    Examples
    --------
    >>> grow_axis([0.0, 1.0], 1.0, 4.5, 2.0).tolist()
    [0.0, 1.0, 3.0, 4.5]
    """
    xs = list(xs)
    while xs[-1] < length - 1e-12:
        step *= ratio
        xs.append(min(xs[-1] + step, length))
    if len(xs) > 3 and xs[-1] - xs[-2] < 0.3 * (xs[-2] - xs[-3]):
        xs.pop(-2)
    return np.array(xs)


def grown_count(rest: float, h: float, ratio: float) -> int:
    """Gaps :func:`grow_axis` adds over ``rest`` from a gap ``h`` (no merge)."""
    if ratio == 1.0:
        return math.ceil(rest / h)
    return math.ceil(math.log1p(rest * (ratio - 1) / (h * ratio)) / math.log(ratio))


def axis_count(fine: float, h: float, length: float, ratio: float) -> float:
    """Number of :func:`graded_axis` coordinates, estimated without building them."""
    n_fine = max(1, math.ceil(min(fine, length) / h - 1e-9))
    return n_fine + 1 + grown_count(max(length - n_fine * h, 0.0), h, ratio)


def lattice_gap(x: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """The larger of the lattice ``xs`` x ``ys``'s row and column gaps at each point."""
    gx, gy = np.diff(xs), np.diff(ys)
    ix = np.clip(np.searchsorted(xs, x[:, 0] - 1e-12), 0, gx.size - 1)
    iy = np.clip(np.searchsorted(ys, x[:, 1] - 1e-12), 0, gy.size - 1)
    return np.maximum(
        np.maximum(gx[ix], gx[np.maximum(ix - 1, 0)]),
        np.maximum(gy[iy], gy[np.maximum(iy - 1, 0)]),
    )


def lattice_params(body: str) -> list[Param]:
    """``grading`` of the lattice away from the ``body`` and ``alpha`` (the shape)."""
    return [
        Param(
            "grading",
            1.15,
            "-",
            f"spacing growth per row away from the {body}",
            float,
            lo=1.0,
            hi=2.0,
        ),
        Param(
            "alpha",
            1.3,
            "-",
            "alpha-shape factor of the remeshing",
            float,
            lo=0.8,
            hi=3.0,
        ),
    ]


def step_dt(values: Mapping[str, Any], h: float, fraction: float, body: str) -> float:
    """The time step: ``dt``, or the ``body`` moving ``fraction`` of ``h`` per step.

    Raises
    ------
    ParameterError
        If the body would move more than one spacing ``h`` per step.
    """
    dt = values["dt"]
    if dt is None:
        dt = fraction * h / values["speed"]
    if values["speed"] * dt > h * (1 + 1e-9):
        raise ParameterError(
            "speed",
            values["speed"],
            f"at most spacing/dt = {h / dt:g} m/s: the {body} may move at most "
            "one spacing per step (lower speed or dt)",
        )
    return dt


def interface_adhesion(values: Mapping[str, Any]) -> float:
    """Interface strength (Pa) of the ``interface`` choice."""
    choice = values["interface"]
    if choice == "smooth":
        return 0.0
    if choice == "rough":
        return values["su"]
    return values["adhesion"] * values["su"]


def derive_cone(values: dict[str, Any]) -> None:
    """cone-penetration's derived defaults, in place.

    ``spacing`` D/12, ``penetration`` 6 D, ``depth`` 10 D, and ``dt``: the
    cone moves half a spacing per step; ``drainage`` from ``water_level``;
    ``su`` of a Mohr-Coulomb clay: its plane-strain undrained strength at
    the mean effective stress ``sigma0`` (the soil round the cone shears as
    round an expanding cylindrical cavity, the vertical stress intermediate).
    """
    derive_drainage(values)
    check_layers(values)
    derive_soil(values, 1.0e4, values["sigma0"], "plane-strain")
    D = values["diameter"]
    if values["spacing"] is None:
        values["spacing"] = D / 12
    if values["penetration"] is None:
        values["penetration"] = 6 * D
    if values["depth"] is None:
        values["depth"] = 10 * D
    if values["dt"] is None:
        values["dt"] = 0.5 * values["spacing"] / values["speed"]


def derive_footing(values: dict[str, Any]) -> None:
    """footing-penetration's ``penetration`` (B) and ``dt`` (spacing/4 a step).

    Also ``drainage`` from ``water_level`` and ``su`` of a Mohr-Coulomb clay:
    its plane-strain undrained strength ``c cos(phi)`` (the weightless soil
    starts stress-free: ``p'_0 = 0``).
    """
    derive_drainage(values)
    check_layers(values)
    derive_soil(values, 1.0e3, 0.0, "plane-strain")
    if values["penetration"] is None:
        values["penetration"] = values["width"]
    if values["dt"] is None:
        values["dt"] = 0.25 * values["spacing"] / values["speed"]


def refuse_penetration(values: Mapping[str, Any], given: frozenset[str]) -> None:
    """Refuse ``adhesion`` (:func:`refuse_adhesion`) and the soil's unused parameters.

    Raises
    ------
    ParameterError
        Naming the parameter left out (:func:`refuse_soil`).
    """
    refuse_adhesion(values, given)
    refuse_soil(values, given)


def refuse_adhesion(values: Mapping[str, Any], given: frozenset[str]) -> None:
    """Refuse ``adhesion`` given with an interface other than ``adhesion``.

    Raises
    ------
    ParameterError
        Naming ``adhesion``, its value and the interface that uses it.
    """
    if "adhesion" in given and values["interface"] != "adhesion":
        raise ParameterError(
            "adhesion",
            values["adhesion"],
            f"left out with interface={values['interface']} (the adhesion "
            "factor is used by interface=adhesion only); choose "
            "interface=adhesion for |t| <= adhesion x s_u",
        )


def penetration_warnings(
    scene: str, deepest: float, spacing: float, dt_now: float
) -> list[str]:
    """A warning when a particle got deeper than half a spacing inside the body.

    The particle is put back on the outline after the step, so the run goes
    on, but the load of that step is off; a smaller step (the body moving less
    per step) keeps the soil out.  Returns the messages, each also issued as
    a ``UserWarning``.
    """
    if deepest <= 0.5 * spacing:
        return []
    msg = (
        f"{scene}: a particle got {deepest / spacing:.2f} spacings inside the body "
        f"(more than half a spacing) before it was put back; the loads of that step "
        f"are off: lower dt (now {dt_now:.4g} s) or refine the spacing"
    )
    warn_user(msg)
    return [msg]


def locking_warnings(values: Mapping[str, Any]) -> list[str]:
    """A warning when FEM-remap runs with P1 elements, which lock here.

    Tresca flow is isochoric, and constant-strain triangles cannot deform at
    constant volume in most patterns: the bearing factor comes out far too
    high (docs/validation/penetration_methods.md: +117 % at B/10 and +63 % at
    B/20 with E_u/s_u = 1000).  Returns the message, also issued as a
    ``UserWarning``.
    """
    if values.get("method") != "fem-remap" or values.get("element") not in (
        None,
        "p1",
    ):
        return []
    msg = (
        "footing-penetration: method=fem-remap with P1 elements locks under "
        "isochoric Tresca flow (the bearing factor comes out too high: +63 % at "
        "B/20 with E_u/s_u = 1000); use element=p2, or method=npfem"
    )
    warn_user(msg)
    return [msg]


class Steady(NamedTuple):
    """The steady part of a cone-factor curve (see :func:`steady_factor`)."""

    median: float
    mean: float
    range: list[float]
    drops: int


def steady_factor(curve: list[list[float]], window: float) -> Steady | None:
    """The steady cone factor: the curve's last ``window`` (in units of w/D).

    ``curve`` is a list of ``[w/D, N_c]`` per step.  The steady value is the
    median of the steps' N_c in the window (a single step where the soil round
    the cone gives way does not move it); the mean is that of the linear
    interpolant over the window (trapezoidal); ``drops`` counts the window's
    steps under 0.8 times the median.  None for an empty curve.

    Examples
    --------
    >>> s = steady_factor([[1.0, 4.0], [2.0, 6.0], [3.0, 2.0], [4.0, 6.0]], 2.5)
    >>> s.median, s.mean, s.range, s.drops
    (6.0, 4.3, [2.0, 6.0], 1)
    """
    if not curve:
        return None
    c = np.asarray(curve, float)
    hi = c[-1, 0]
    lo = max(hi - window, c[0, 0])
    if hi <= lo:
        q = float(c[-1, 1])
        return Steady(q, q, [q, q], 0)
    inner = c[(c[:, 0] > lo) & (c[:, 0] < hi)]
    ws = np.concatenate([[lo], inner[:, 0], [hi]])
    qs = np.interp(ws, c[:, 0], c[:, 1])
    mean = float(np.sum(0.5 * (qs[1:] + qs[:-1]) * np.diff(ws)) / (hi - lo))
    steps = c[(c[:, 0] > lo) & (c[:, 0] <= hi), 1]
    median, drops = count_drops(steps)
    return Steady(median, mean, [float(qs.min()), float(qs.max())], drops)


def count_drops(loads: np.ndarray) -> tuple[float, int]:
    """The median of ``loads`` and how many are under 0.8 times it.

    A load drop: a step where the soil round the body gives way (the cone's
    and the footing's definition).

    Examples
    --------
    >>> count_drops(np.array([5.0, 6.0, 3.0, 6.0]))
    (5.5, 1)
    """
    median = float(np.median(loads))
    return median, int(np.sum(loads < DROP * median))


def running_drops(curve: list[list[float]], window: float = DROP_WINDOW) -> int:
    """Load drops along a whole ``[push, load]`` curve.

    A step is a drop when its load is under :data:`DROP` times the median of
    the steps over the last ``window`` of push up to it (itself included), so
    a rising curve (the elastic start) has none and a single step where the
    soil round the body gives way is one.

    Examples
    --------
    >>> running_drops([[0.1, 1.0], [0.2, 4.0], [0.3, 4.0], [0.4, 2.0], [0.5, 4.0]])
    1
    """
    if not curve:
        return 0
    c = np.asarray(curve, float)
    first = np.searchsorted(c[:, 0], c[:, 0] - window * (1 + 1e-9))
    medians = np.array([np.median(c[a : i + 1, 1]) for i, a in enumerate(first)])
    return int(np.sum(c[:, 1] < DROP * medians))
