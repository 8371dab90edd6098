"""Run-out measures of a column collapse and the warnings that qualify them.

The run-out is the 99 % mass front (:func:`mass_front`); the main body's front
(:func:`front`) and the detached mass (:func:`detached_fraction`) say when a
few stray grains set it (:func:`detached_warnings`); :func:`collapse_time`
is when the front stops; :func:`rest_warnings` says when a run ended at
``t_end`` before the material came to rest.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...errors import warn_user
from ...run.rest import AtRest
from ...run.simulation import Simulation

__all__ = [
    "DETACHED_WARNING",
    "collapse_time",
    "detached_fraction",
    "detached_warnings",
    "front",
    "mass_front",
    "picture_front",
    "rest_warnings",
]


#: Detached mass fraction above which the summary warns that the 99 % mass
#: front may be set by grains outside the main body (coarse runs shed a few
#: grains that fly ahead of the deposit).
DETACHED_WARNING = 0.01


def mass_front(x: np.ndarray, mass: np.ndarray, symmetric: bool) -> float:
    """Run-out as a mass quantile (see the module notes)."""

    def quantile(q: float) -> float:
        order = np.argsort(x[:, 0])
        cum = np.cumsum(mass[order]) - 0.5 * mass[order]
        return float(np.interp(q * mass.sum(), cum, x[order, 0]))

    if symmetric:
        return quantile(0.99)
    return 0.5 * (quantile(0.995) - quantile(0.005))


def picture_front(
    points: np.ndarray, mass: np.ndarray, symmetric: bool = True
) -> float:
    """:func:`mass_front` of a picture's step: its points' (x, y) and masses."""
    return float(mass_front(np.asarray(points)[:, :2], np.asarray(mass), symmetric))


def front(x: np.ndarray, body: np.ndarray, symmetric: bool) -> tuple[float, float]:
    """Run-out and height of the main body (see the module notes)."""
    xb = x[body]
    if xb.shape[0] == 0:
        return float("nan"), float("nan")
    runout = xb[:, 0].max() if symmetric else 0.5 * (xb[:, 0].max() - xb[:, 0].min())
    return float(runout), float(xb[:, 1].max())


def detached_fraction(mass: np.ndarray, body: np.ndarray) -> float:
    """Mass outside the main body (mask ``body``) as a fraction of the total."""
    total = float(mass.sum())
    return float(mass[~body].sum()) / total if total > 0 else 0.0


def detached_warnings(
    scene: str, fraction: float | None, runout: float, main: float | None, L0: float
) -> list[str]:
    """The warning of a run whose detached mass exceeds :data:`DETACHED_WARNING`.

    ``runout`` is the 99 % mass front and ``main`` the edge of the main body
    (None where the geometry has none), both in m; ``L0`` the initial width.
    """
    if fraction is None or not fraction > DETACHED_WARNING:
        return []
    msg = (
        f"{scene}: {fraction:.1%} of the mass is detached from the main body "
        f"(above {DETACHED_WARNING:.0%}), so the 99 % mass front "
        f"(runout = {runout:.4g} m, normalised {(runout - L0) / L0:.3g}) may be "
        "set by stray grains"
    )
    if main is not None:
        msg += (
            f"; the main body reaches {main:.4g} m (normalised_runout_main_body = "
            f"{(main - L0) / L0:.3g})"
        )
    return [msg + "; a finer spacing sheds fewer grains"]


def collapse_time(times: np.ndarray, runout: np.ndarray, tol: float) -> float:
    """First time after which the run-out stays within ``tol`` of its final value."""
    if runout.size == 0:
        return float("nan")
    moving = np.flatnonzero(np.abs(runout - runout[-1]) > tol)
    if moving.size == 0:
        return float(times[0])
    k = moving[-1] + 1
    return float(times[min(k, times.size - 1)])


def rest_warnings(sim_: Simulation, values: Mapping[str, Any], stop: AtRest | None):
    """One warning if the run reached ``t_end`` before the at-rest rule stopped it.

    Also issued as a :class:`UserWarning` (the CLI prints it on stderr).  None
    without the rule (``rest_fraction = 0``) or before ``t_end`` (an
    interrupted run).
    """
    t_end, recs = values["t_end"], sim_.records
    if stop is None or not recs or sim_.time < t_end * (1 - 1e-12) or stop(sim_):
        return []
    if sim_.time < stop.min_time * (1 - 1e-12):
        why = f"before the earliest stop at rest, min_time = {stop.min_time:.4g} s"
    else:
        peak = max(r.kinetic_energy for r in recs)
        share = recs[-1].kinetic_energy / peak if peak > 0 else math.nan
        why = (
            f"while the kinetic energy was still {share:.3g} of its maximum "
            f"(rest: below rest_fraction = {stop.fraction:g})"
        )
    msg = (
        f"column-collapse: the run ended at t_end = {t_end:g} s {why}; the material "
        "is not at rest, so the run-out and height are not final (at_rest = "
        "false): raise t_end"
    )
    warn_user(msg)
    return [msg]
