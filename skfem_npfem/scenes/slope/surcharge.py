"""A strip surcharge on the slope's crest: its load, its collapse pressure.

A uniform pressure ``surcharge`` on a strip ``surcharge_width`` wide whose
edge nearer the slope is ``surcharge_offset`` behind the crest's edge (a
flexible strip footing, or a stockpile) loads the crest's surface particles
with the consistent nodal forces of the pressure
(:func:`~skfem_npfem.loads.surface_load`).  It is a dead load in the initial
stresses (``initial_stress=gravity``), in the factor of safety and the run-out;
with ``analysis=limit`` the strip's collapse pressure
(:func:`surcharge_collapse`) is one more limit analysis, gravity (and a
constant ``kh``) held as the dead load.  ``surcharge_footing`` makes the
strip a rigid footing in that analysis: its surface particles move down as
one (``smooth``), and do not slide (``rough``); the collapse pressure is then
the footing's bearing capacity near the slope.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ...constants import GRAVITY
from ...errors import ParameterError, SolverError
from ...limit.analysis import limit_analysis
from ...limit.safety import CAP
from ...loads import surface_load
from ...materials import Material
from ...mesh.regions import CrossSection
from ..common import solver_from
from ..params import POSITIVE, Param
from .section import toe_and_crest

__all__ = [
    "SURCHARGE_METRICS",
    "SURCHARGE_PARAMS",
    "check_surcharge",
    "dead_load_multiplier",
    "strip",
    "surcharge_collapse",
    "surcharge_load",
]

#: What the strip is in its collapse analysis.
FOOTINGS = ("flexible", "smooth", "rough")

SURCHARGE_PARAMS = [
    Param(
        "surcharge",
        0.0,
        "Pa",
        "uniform pressure on a strip of the crest (needs surcharge_width): a "
        "dead load in the initial stresses, the factor of safety and the run-out",
        float,
        lo=0,
    ),
    Param(
        "surcharge_width",
        None,
        "m",
        "width of the surcharge's strip; with analysis=limit its collapse "
        "pressure is reported (default: no strip)",
        float,
        **POSITIVE,
    ),
    Param(
        "surcharge_offset",
        0.0,
        "m",
        "distance from the crest's edge to the strip's nearer edge",
        float,
        lo=0,
    ),
    Param(
        "surcharge_footing",
        "flexible",
        "-",
        "the strip in the collapse analysis: flexible (a uniform pressure), or "
        "a rigid footing, smooth (its particles move down as one) or rough "
        "(and do not slide)",
        str,
        FOOTINGS,
    ),
]

SURCHARGE_METRICS = {
    "surcharge_collapse": "analysis=limit (or push_depth > 0) with "
    "surcharge_width: the pressure on "
    "the strip at which the slope collapses with its strengths unreduced, Pa "
    "(one more limit analysis: gravity and a constant kh the dead load, capped "
    "at 1e3 times the largest cohesion or weight of the section's height); "
    "null without a strip or when the slope fails without it; with "
    "surcharge_footing smooth or rough, a rigid footing's bearing capacity",
}


def check_surcharge(values: Mapping[str, Any]) -> None:
    """A surcharge needs a strip; the strip must lie on the parametric crest."""
    width = values["surcharge_width"]
    if values["surcharge"] > 0 and width is None:
        raise ParameterError(
            "surcharge_width", None, "a width > 0 (m) with surcharge > 0"
        )
    if width is None or values["geometry"]:
        return
    room = values["crest_length"]
    if room is None:  # checked before the derived defaults are filled
        room = 1.5 * values["height"]
    if values["surcharge_offset"] + width > room * (1 + 1e-12):
        raise ParameterError(
            "surcharge_width",
            width,
            f"at most the crest's {room:g} m less surcharge_offset "
            f"({values['surcharge_offset']:g} m): the strip lies on the crest",
        )


def strip(x: np.ndarray, sec: CrossSection, values: Mapping[str, Any]) -> np.ndarray:
    """The crest's surface particles under the strip (a mask).

    The crest is the section's top (``y`` of its highest point); the strip
    runs from ``surcharge_offset`` to ``surcharge_offset + surcharge_width``
    behind the crest's edge (toward ``-x``).  At least two particles, else a
    :class:`ParameterError` names ``surcharge_width``.
    """
    _, _, x_crest, y_crest = toe_and_crest(sec, values)
    near = x_crest - values["surcharge_offset"]
    far = near - values["surcharge_width"]
    tol = 1e-9 * max(1.0, float(np.ptp(x[:, 0])))
    on = (
        (np.abs(x[:, 1] - y_crest) <= tol)
        & (x[:, 0] >= far - tol)
        & (x[:, 0] <= near + tol)
    )
    if on.sum() < 2:
        raise ParameterError(
            "surcharge_width",
            values["surcharge_width"],
            f"a strip holding at least two surface particles (it holds {on.sum()}): "
            "at least the spacing, on the crest",
        )
    return on


def surcharge_load(
    x: np.ndarray,
    sec: CrossSection,
    values: Mapping[str, Any],
    pressure: float | None = None,
) -> np.ndarray | None:
    """Nodal forces of ``pressure`` (default ``surcharge``) on the strip, N.

    None when there is no strip, or no pressure on it.
    """
    p = values["surcharge"] if pressure is None else pressure
    if values["surcharge_width"] is None or p == 0:
        return None
    return surface_load(x, strip(x, sec, values), p)


def surcharge_collapse(
    values: Mapping[str, Any],
    body: Any,
    mats: list[Material],
    ni: Any,
    dead: np.ndarray,
) -> float | None:
    """The strip's collapse pressure with the strengths unreduced, Pa.

    One limit analysis on ``ni`` (the body's strain operator): ``dead``
    (gravity, the water's force, a constant ``kh``) held, the load of a unit
    pressure on the strip the reference.  ``body`` is the slope's
    :class:`~.body.SlopeBody`; None without a strip or when the dead load
    alone brings the slope down.
    """
    if values["surcharge_width"] is None:
        return None
    unit = surcharge_load(body.pts, body.sec, values, 1.0)
    # A stress scale of the slope: its largest cohesion or its deepest weight.
    depth = float(np.ptp(body.pts[:, 1]))
    weight = GRAVITY * depth * max(m.rho for m in mats)
    scale = max(max(getattr(m, "c", 0.0) for m in mats), weight)
    cap = CAP * max(scale, 1.0)
    kind = values["surcharge_footing"]
    if kind == "flexible":
        return dead_load_multiplier(values, body, mats, ni, unit, dead, cap)
    # A rigid footing: the strip's vertical dofs one unknown (the load's sum
    # is what acts on it), its horizontal ones held when it is rough.
    on = np.flatnonzero(strip(body.pts, body.sec, values))
    fixed = np.asarray(body.fixed, bool).copy()
    if kind == "rough":
        fixed[on, 0] = True
    rigid = {"tied": [2 * on + 1], "fixed": fixed}
    return dead_load_multiplier(values, body, mats, ni, unit, dead, cap, **rigid)


def dead_load_multiplier(
    values: Mapping[str, Any],
    body: Any,
    mats: list[Material],
    ni: Any,
    load: np.ndarray,
    dead: np.ndarray,
    cap: float,
    tied: list[np.ndarray] | None = None,
    fixed: np.ndarray | None = None,
) -> float | None:
    """The collapse multiplier of ``load`` with ``dead`` held, on the slope.

    One limit analysis on the body's initial mesh (``ni``: its strain
    operator; ``cap`` bounds the multiplier; ``tied`` dofs move as one,
    ``fixed`` replaces the body's supports); None when ``dead`` alone brings
    the slope down (the program is infeasible).
    """
    try:
        res = limit_analysis(
            ni,
            mats,
            body.material,
            load,
            dead_load=dead,
            fixed=body.fixed if fixed is None else fixed,
            tied=tied,
            options=solver_from(values),
            max_multiplier=cap,
            strength=body.strength,
        )
    except SolverError as err:
        if err.status in ("PrimalInfeasible", "AlmostPrimalInfeasible"):
            return None
        raise
    return float(res.multiplier)
