"""The piezocone (CPTu) of the cone-penetration scene: u2 and its dissipation.

With ``drainage=coupled`` the pore water flows by Darcy's law (conductivity
``k``) while the cone goes down: the cone is impermeable (its contacts), the
soil's surface drained, the base, the far side and the axis impermeable.  The
excess pore pressure at the shoulder, where a piezocone's u2 filter sits, is
recorded every step.

``dissipation=true`` adds a dissipation test: once pushed by ``penetration``
the cone is held (velocity 0) and the excess pore pressure drains away in
coupled steps.  Time is Teh & Houlsby's (1991) modified time factor
``T* = c_h t / (R^2 sqrt(I_r))`` (``R = D/2``, ``I_r = G/s_u``,
``c_h = k M / gamma_w`` with ``M`` the skeleton's constrained modulus
``2 G (1 - nu) / (1 - 2 nu)``, ``nu`` its drained ratio): the first step is
``dT``, each next ``dt_growth`` times the last, at most ``dT_max``, until
``T_end`` (the consolidation scene's stepping, in T*).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...boundary import RigidBody
from ...constants import GRAVITY
from ...errors import ParameterError
from ...particles import Particles
from ...run.simulation import Simulation
from ..consolidation.scene import growing_step
from ..params import Param
from ..water import is_wet
from .penetration_common import steady_factor

__all__ = [
    "DISSIPATION_METRICS",
    "DISSIPATION_PARAMS",
    "TEH_HOULSBY_T50_U2",
    "TEH_HOULSBY_U2",
    "HeldBody",
    "attach_piezocone",
    "check_dissipation",
    "consolidation_coefficient",
    "dissipation_metrics",
    "dissipation_stage",
    "half_time",
    "hold_on_restore",
    "in_push",
    "steady_mean",
    "time_factor_seconds",
]

#: Teh & Houlsby (1991), Geotechnique 41(1) 17-34: the modified time factor
#: T* at 50 % dissipation at the shoulder (u2) of a 60-degree cone.
TEH_HOULSBY_T50_U2 = 0.245

#: Teh & Houlsby (1991), their table of T* at the shoulder (u2): ``(U, T*)``
#: for degrees of dissipation ``U = 1 - u/u0`` of 20 to 80 %.
TEH_HOULSBY_U2 = (
    (0.2, 0.038),
    (0.3, 0.078),
    (0.4, 0.142),
    (0.5, 0.245),
    (0.6, 0.439),
    (0.7, 0.804),
    (0.8, 1.60),
)

DISSIPATION_PARAMS = [
    Param(
        "dissipation",
        False,
        "-",
        "after the push, hold the cone (velocity 0) and let the excess pore "
        "pressure dissipate (a CPTu dissipation test; drainage=coupled)",
        bool,
    ),
    Param(
        "dT",
        1.0e-3,
        "-",
        "dissipation: first time step as Teh & Houlsby's modified time factor "
        "T* = c_h t / (R^2 sqrt(I_r))",
        float,
        lo=1e-9,
        hi=10.0,
    ),
    Param(
        "dt_growth",
        1.3,
        "-",
        "dissipation: ratio of a time step to the one before",
        float,
        lo=1.0,
        hi=10.0,
    ),
    Param(
        "dT_max",
        1.0,
        "-",
        "dissipation: longest time step as a time factor T*",
        float,
        lo=1e-9,
        hi=100.0,
    ),
    Param(
        "T_end",
        5.0,
        "-",
        "dissipation: its duration as a time factor T*",
        float,
        lo=1e-9,
        hi=1e3,
    ),
]

DISSIPATION_METRICS = {
    "u2_max": "drainage=undrained or coupled: the largest excess pore pressure "
    "at the shoulder (u2, as shoulder_excess_pore_pressure) over the push, Pa",
    "u2_end": "drainage=undrained or coupled: u2 at the end of the push, Pa "
    "(u2(0) of the dissipation test)",
    "u2_steady": "drainage=undrained or coupled: the mean of u2 over the steady "
    "part of the push (its last steady_window x D), Pa (one step's u2 "
    "scatters about it by 10 to 25 %)",
    "consolidation_coefficient": "drainage=coupled: c_h = k M / gamma_w "
    "(M = 2 G (1 - nu)/(1 - 2 nu), the skeleton's constrained modulus), m^2/s",
    "normalised_velocity": "drainage=coupled: V = speed D / c_h (undrained "
    "penetration for V above about 30)",
    "dissipation": "dissipation=true: list of [T*, u2(t)/u2(0)] from the end of "
    "the push (T* = c_h t / (R^2 sqrt(I_r)), R = D/2, I_r = rigidity_index, "
    "u2(0) = u2_end)",
    "t50_star": "dissipation=true: T* at which u2 fell to half u2(0) (log-linear "
    "between steps; None if it did not)",
    "t50_star_reference": "Teh & Houlsby (1991): T*_50 = 0.245 at u2",
}


@dataclass(frozen=True)
class HeldBody(RigidBody):
    """A rigid body held still, displaced by ``offset`` from its ``vertices``.

    The cone of a dissipation test: its position that of the pushed cone at
    the end of the push, its velocity (which the contact rows move it by) a
    creep (:data:`CREEP`) that its outline does not follow.
    """

    offset: tuple[float, float] = (0.0, 0.0)

    def displacement(self, t: float) -> np.ndarray:
        """The constant ``offset`` (d,), m."""
        return np.asarray(self.offset, float)


#: The held cone creeps on at this fraction of its speed: its contact rows pick
#: a corner's face by the body's approach, so a corner (the shoulder, the tip)
#: keeps the normal it had in the push (a still body would take the corner's
#: bisector, which put a spike of 3 u2 on the nodes there).  Over 10^4 s at
#: 2 cm/s that is 2e-7 m, against a spacing of D/10 = 3.6e-3 m.
CREEP = 1e-9


def held(body: RigidBody, t: float) -> HeldBody:
    """``body`` stopped where it is at time ``t`` (creeping at :data:`CREEP`)."""
    return HeldBody(
        body.vertices,
        velocity=CREEP * body.velocity,
        adhesion=body.adhesion,
        name=body.name,
        reference=body.reference,
        offset=tuple(float(v) for v in body.displacement(t)),
    )


def check_dissipation(values: Mapping[str, Any]) -> None:
    """Refuse a dissipation test without coupled drainage.

    Raises
    ------
    ParameterError
        ``dissipation=true`` with a ``drainage`` other than ``coupled``, or
        ``dT_max`` under ``dT``.
    """
    if not values["dissipation"]:
        return
    if values["drainage"] != "coupled":
        raise ParameterError(
            "dissipation",
            True,
            "false unless drainage=coupled (the excess pore pressure dissipates "
            "by Darcy flow; give drainage=coupled and k)",
        )
    if values["dT_max"] < values["dT"]:
        raise ParameterError("dT_max", values["dT_max"], f">= dT = {values['dT']:g}")


def consolidation_coefficient(values: Mapping[str, Any]) -> float:
    """``c_h = k M / gamma_w``, m^2/s (``M`` of the skeleton: ``G``, ``nu``)."""
    G = values["rigidity_index"] * values["su"]
    nu = values["nu"]
    M = 2 * G * (1 - nu) / (1 - 2 * nu)
    return values["k"] * M / (values["rho_w"] * GRAVITY)


def time_factor_seconds(values: Mapping[str, Any]) -> float:
    """Seconds per unit of ``T* = c_h t / (R^2 sqrt(I_r))``."""
    R = values["diameter"] / 2
    return (
        R**2 * math.sqrt(values["rigidity_index"]) / consolidation_coefficient(values)
    )


def half_time(curve: list[list[float]], level: float = 0.5) -> float | None:
    """T* where ``[T*, u/u0]`` first falls to ``level`` (log-linear in T*).

    ``level = 1 - U`` reads the time of a degree of dissipation ``U``.

    Examples
    --------
    >>> round(half_time([[0.0, 1.0], [0.1, 0.8], [1.0, 0.3]]), 4)
    0.3981
    """
    c = np.asarray(curve, float)
    below = np.flatnonzero(c[:, 1] <= level)
    if below.size == 0:
        return None
    i = int(below[0])
    if i == 0:
        return float(c[0, 0])
    (t0, u0), (t1, u1) = c[i - 1], c[i]
    s = (u0 - level) / (u0 - u1)
    if t0 <= 0.0:
        return float(t0 + s * (t1 - t0))
    return float(math.exp(math.log(t0) + s * (math.log(t1) - math.log(t0))))


def dissipation_stage(
    values: Mapping[str, Any],
    t_push: float,
    shoulder: Callable[[np.ndarray, float], np.ndarray],
) -> Callable[[Simulation, Particles, Any], bool]:
    """The callback of a coupled cone: u2 every step, the cone held after the push.

    ``shoulder(x, push)`` picks the particles of the u2 filter after ``push``
    x D.  Each step records ``u2`` (Pa); after the step that ends the push,
    with ``dissipation``, the cone is held (:class:`HeldBody`) and the steps
    grow from ``dT`` (in T*) by ``dt_growth`` up to ``dT_max``.
    """
    D = values["diameter"]
    unit = time_factor_seconds(values) if values["dissipation"] else 1.0

    def callback(sim: Simulation, p: Particles, step) -> bool:
        extra = step.record.extra
        push = -extra.get("cone_y", 0.0) / D
        near = shoulder(p.x, push)
        extra["u2"] = float(p.excess_pore_pressure[near].mean()) if near.any() else 0.0
        if not values["dissipation"] or sim.time < t_push * (1 - 1e-9):
            return False
        if not isinstance(sim.model.bodies[0], HeldBody):
            sim.model.bodies[0] = held(sim.model.bodies[0], t_push)
            sim.dt = values["dT"] * unit
            return False
        sim.dt = growing_step(
            step.record.dt,
            values["dt_growth"],
            values["dT_max"] * unit,
            sim.time,
            [],
            unit,
        )
        return False

    return callback


def attach_piezocone(
    sim: Simulation,
    values: Mapping[str, Any],
    t_push: float,
    shoulder: Callable[[np.ndarray, float], np.ndarray],
) -> float:
    """Record u2 on a wet cone's steps and add the dissipation test; the end time.

    A dry cone is left as it is.  With ``dissipation`` the run goes on for
    ``T_end`` (in T*) after the push, in steps of at most ``dT_max``.
    """
    if is_wet(values):
        sim.callbacks.append(dissipation_stage(values, t_push, shoulder))
    if not values["dissipation"]:
        return t_push
    unit = time_factor_seconds(values)
    sim.dt_max = max(sim.dt, values["dT_max"] * unit)
    hold_on_restore(sim, t_push)
    return t_push + values["T_end"] * unit


def hold_on_restore(sim: Simulation, t_push: float) -> None:
    """A dissipation run resumed after the push restarts with the cone held."""
    restore = sim.restore

    def resumed(path):
        meta = restore(path)
        if sim.time >= t_push * (1 - 1e-9):
            sim.model.bodies[0] = held(sim.model.bodies[0], t_push)
        return meta

    sim.restore = resumed


def dissipation_metrics(
    sim: Simulation, values: Mapping[str, Any], t_push: float
) -> dict[str, Any]:
    """``u2_max`` and, coupled, c_h, V and the dissipation curve with its T*_50."""
    recs = sim.records
    pushed = [r for r in in_push(sim, t_push) if "u2" in r.extra]
    push = [r.extra["u2"] for r in pushed]
    out: dict[str, Any] = {
        "u2_max": max(push) if push else None,
        "u2_end": push[-1] if push else None,
        "u2_steady": steady_mean(pushed, values) if push else None,
    }
    if values["drainage"] != "coupled":
        return out
    ch = consolidation_coefficient(values)
    out["consolidation_coefficient"] = ch
    out["normalised_velocity"] = values["speed"] * values["diameter"] / ch
    if not values["dissipation"]:
        return out
    unit = time_factor_seconds(values)
    u0 = out["u2_end"]
    after = [r for r in recs if r.time > t_push * (1 + 1e-9)]
    curve = [[0.0, 1.0]] if u0 else []
    if u0:
        curve += [[(r.time - t_push) / unit, r.extra["u2"] / u0] for r in after]
    out["dissipation"] = curve
    out["t50_star"] = half_time(curve) if curve else None
    out["t50_star_reference"] = TEH_HOULSBY_T50_U2
    return out


def steady_mean(pushed: list, values: Mapping[str, Any]) -> float:
    """The mean u2 of the records over the push's last ``steady_window`` x D.

    The mean of the linear interpolant of u2 against depth over the window,
    as the steady cone factor's (:func:`~.penetration_common.steady_factor`).

    u2 is the mean excess pore pressure of the few particles of the filter,
    which change as the soil flows past the shoulder: one step's value
    scatters by 10 to 25 % about this mean (coefficient of variation over the
    last diameter at D/8), and a dissipation curve normalised by it carries
    that scatter into its T*_50 (docs/validation/cone_penetration.md, "CPTu").
    The steady mean is the u2 a piezocone reads in the push without the
    scatter.
    """
    D = values["diameter"]
    curve = [[-r.extra.get("cone_y", 0.0) / D, r.extra["u2"]] for r in pushed]
    return steady_factor(curve, values["steady_window"]).mean


def in_push(sim: Simulation, t_push: float) -> list:
    """The records of the push (a dissipation test's steps left out)."""
    return [r for r in sim.records if r.time <= t_push * (1 + 1e-9)]
