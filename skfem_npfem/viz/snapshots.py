"""Which stored steps a picture shows, and how their times are named.

Requested times are in the scene's unit (normalised time of a collapse,
settlement of the footing, w/D of the cone, seconds otherwise); a request
outside the stored steps draws the nearest step and names it by the time it shows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import warn_user

__all__ = []


def _time_label(value: float) -> str:
    """Short decimal text of a time for file names (4 significant digits)."""
    return np.format_float_positional(
        value, precision=4, unique=True, fractional=False, trim="-"
    )


def _frame_indices(n: int, max_frames: int) -> np.ndarray:
    """Evenly spread step indices (first and last included), at most max_frames."""
    if n <= max_frames:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, max_frames)).astype(int))


@dataclass(frozen=True)
class _TimeUnit:
    """How snapshot times are given, shown and put in file names.

    Attributes
    ----------
    prefix : str
        File-name prefix of the value: ``t`` (time), ``s`` (the footing's
        settlement, its pseudo-time) or the scene's own (``wD``: the cone's
        penetration w/D).
    name : str
        Unit in messages (``t/sqrt(H0/g)``, ``s``, ``m of settlement``).
    scale : float
        Seconds (pseudo-time) per unit.
    """

    prefix: str = "t"
    name: str = "s"
    scale: float = 1.0

    def text(self, value: float) -> str:
        """``value`` with its unit, e.g. ``t/sqrt(H0/g) = 5.25``."""
        if self.prefix == "s":
            return f"settlement {value:.4g} m"
        if self.name == "s":
            return f"t = {value:.4g} s"
        return f"{self.name} = {value:.4g}"


def _time_unit(sc, normalised: bool) -> _TimeUnit:
    """The unit of ``times`` for a result with scenery ``sc``."""
    if sc.unit is not None:  # the scene's own unit, whatever ``normalised``
        return _TimeUnit(*sc.unit)
    if sc.footing is not None:  # pseudo-time is the settlement, m
        return _TimeUnit("s", "m of settlement")
    if normalised and sc.tau is not None:
        h0 = "h0" if "h0" in sc.label(0.0) else "H0"
        return _TimeUnit("t", f"t/sqrt({h0}/g)", sc.tau)
    return _TimeUnit()


def _pick_snapshots(
    ts: np.ndarray, req: list[float] | None, unit: _TimeUnit | None = None
) -> dict[int, float]:
    """Map step index -> label (in ``unit``) of each snapshot.

    A requested time within half a step of a stored step keeps its value as
    the label; one outside the stored steps is labelled with the time of the
    step drawn (and a warning says so, in the same unit).
    """
    unit = _TimeUnit() if unit is None else unit
    scale = unit.scale
    if not req:  # 5 evenly spaced times, labelled with the step times
        picks = (np.argmin(np.abs(ts - t)) for t in np.linspace(ts[0], ts[-1], 5))
        return {int(i): float(ts[i] / scale) for i in dict.fromkeys(picks)}
    dt = float(np.median(np.diff(ts))) if len(ts) > 1 else 0.0
    snaps: dict[int, float] = {}
    for label in req:
        t_s = label * scale
        i = int(np.argmin(np.abs(ts - t_s)))
        if abs(ts[i] - t_s) > 0.5 * dt + 1e-9 * max(1.0, abs(t_s)):
            shown = float(np.float64(f"{ts[i] / scale:.4g}"))
            seconds = (
                ""
                if unit.name in ("s", "m of settlement")
                else (f" (t = {ts[i]:.4g} s)")
            )
            warn_user(
                f"{unit.text(label)} is outside the stored steps "
                f"({ts[0] / scale:.4g}..{ts[-1] / scale:.4g} {unit.name}); drawing "
                f"the step at {unit.text(shown)}{seconds}, saved as "
                f"_{unit.prefix}{_time_label(shown)}",
            )
            label = shown
        snaps.setdefault(i, label)
    return snaps
