"""Colour ranges of the result pictures.

The same range in every picture of a field, over all stored steps: for
stresses the 1-99 % range (compression only, tension only or symmetric), for
magnitudes 0..max, for plastic strain 0 to a high percentile of the
plastic values; arrows on the colour bar show values beyond the range.
"""

from __future__ import annotations

import numpy as np

from .render import (
    Style,
)

_STRESS_INDEX = {
    "stress_xx": 0,
    "stress_yy": 1,
    "stress_zz": 2,
    "stress_xy": 3,
    "stress_yz": 4,
    "stress_zx": 5,
}
#: Fields in Pa besides the stress components (scaled like them).
_PRESSURES = ("pressure", "pore_pressure", "excess_pore_pressure")
_UNITS = {"plastic_strain_eq": "-", "velocity": "m/s", "displacement": "m"}
#: Values per step pooled for the colour range, and the share cut at each end.
_SAMPLE, _TAIL = 4000, 0.01

__all__ = []


#: Top of the plastic-strain colour range: this quantile of the plastic values.
_PLASTIC_QUANTILE = 0.95


#: Smallest top of the colour range of the plastic strain (round-off below it).
_EPS_P_FLOOR = 1e-6


def _robust_range(values: np.ndarray, name: str = "") -> tuple[float, float]:
    """Range of pooled values without the outermost 1 % on either side.

    Plastic strain: 0 up to the 95th percentile of the plastic values (those
    above 1e-6 of the largest), so that a thin band of very large strains (the
    grains sliding on the floor) does not leave the body in one colour.
    """
    if not values.size:
        return 0.0, 0.0
    if name == "plastic_strain_eq":
        plastic = values[values > 1e-6 * values.max()]
        if plastic.size:
            return 0.0, float(np.quantile(plastic, _PLASTIC_QUANTILE))
        return 0.0, float(values.max())
    lo, hi = np.quantile(values, [_TAIL, 1 - _TAIL])
    return float(lo), float(hi)


def _extend(style: Style, lo: float, hi: float) -> str:
    """Colour bar arrows for values beyond the range (SI values lo..hi)."""
    a, b = (v * style.scale for v in style.clim)
    tol = 1e-9 * max(abs(a), abs(b), 1e-300)
    low, high = lo < a - tol, hi > b + tol
    return {(0, 0): "neither", (1, 0): "min", (0, 1): "max"}.get(
        (int(low), int(high)), "both"
    )


def _style(name: str, lo: float, hi: float, fixed: bool = False) -> Style:
    """Colour range, colour map and unit scale of a field.

    With ``fixed`` the range ``lo..hi`` (SI units) is used as given.
    """
    if name in _STRESS_INDEX or name in _PRESSURES:
        big = max(abs(lo), abs(hi))
        scale, unit = next(
            ((s, u) for s, u in ((1e6, "MPa"), (1e3, "kPa")) if big >= s),
            (1.0, "Pa"),
        )
        if fixed and hi > lo:
            cmap = "coolwarm" if lo < 0 < hi else "viridis"
            return Style((lo / scale, hi / scale), cmap, scale, unit)
        if big == 0:
            return Style((-1.0, 1.0), "coolwarm", scale, unit)
        if hi <= 0.05 * big:  # (nearly) compression only: min..0
            return Style((lo / scale, 0.0), "viridis", scale, unit)
        if lo >= -0.05 * big:  # (nearly) tension only: 0..max
            return Style((0.0, hi / scale), "viridis", scale, unit)
        return Style((-big / scale, big / scale), "coolwarm", scale, unit)
    cmap = "plasma" if name == "plastic_strain_eq" else "viridis"
    if fixed and hi > lo:
        return Style((lo, hi), cmap, 1.0, _UNITS[name])
    top = max(hi, _EPS_P_FLOOR) if name == "plastic_strain_eq" else hi
    if not top > 0:
        top = 1.0
    return Style((0.0, top), cmap, 1.0, _UNITS[name])
