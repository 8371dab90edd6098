"""A rigid footing pushed down on the slope's crest: its pressure-settlement curve.

``push_depth > 0`` (with ``analysis=incremental``) replaces the run-out by a
quasi-static push: the surcharge's strip (``surcharge_width`` wide,
``surcharge_offset`` behind the crest's edge) becomes a rigid
:class:`~skfem_npfem.RigidBody` resting on the crest, moved down by
``push_depth`` at ``push_speed``, a quarter of the spacing per step, from
the initial stresses of stage 1 with the strengths unreduced and gravity on.
The particles are re-triangulated every step (the slope's alpha shape), so
the soil heaves and the slope's face bulges as it would.

The footing is ``surcharge_footing``: ``smooth`` (a frictionless interface)
or ``rough`` (Tresca adhesion equal to the crest's cohesion in a soil with
``phi = 0``; Coulomb friction ``phi`` otherwise).  The pressure ``q`` is the
soil's vertical force on the footing over its width; ``push_curve`` lists
``[w, q]`` per step.  The reference is the same footing's collapse pressure by
limit analysis on the initial lattice (``surcharge_collapse``, computed for
the push too): ``push_capacity`` (the mean ``q`` over ``w`` from 0.05 to
0.15 ``B``) over it is
``push_capacity_ratio``.  docs/theory.md ("A footing pushed near a slope")
says what the two share and where they differ.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ...boundary import RigidBody
from ...constants import GRAVITY
from ...errors import ParameterError, SolverError, warn_user
from ...mesh.smoothing import nodal_integration
from ...step.model import Model
from ..common import fidelity_from, solver_from, window_mean
from ..params import POSITIVE, Param
from ..soil_profile import clay_law
from .section import section_materials, toe_and_crest
from .seismic import slope_loads
from .surcharge import strip, surcharge_collapse
from .water import slope_water

__all__ = [
    "PUSH_METRICS",
    "PUSH_PARAMS",
    "check_push",
    "push_metrics",
    "push_model",
    "push_time",
]

#: Fraction of the spacing the footing moves per step.
STEP_FRACTION = 0.25

#: Settlements over the footing's width between which ``push_capacity`` is
#: the mean pressure.
CAPACITY_WINDOW = (0.05, 0.15)

PUSH_PARAMS = [
    Param(
        "push_depth",
        0.0,
        "m",
        "with analysis=incremental: push the surcharge strip down as a rigid "
        "footing (surcharge_footing smooth or rough) by this much, "
        "quasi-static, strengths unreduced (0: no push; replaces the run-out)",
        float,
        lo=0,
    ),
    Param(
        "push_speed",
        1.0e-3,
        "m/s",
        "speed of the pushed footing (a quarter of the spacing per step; it "
        "matters only to a clay with rate_parameter > 0)",
        float,
        **POSITIVE,
    ),
]

PUSH_METRICS = {
    "push_curve": "push_depth > 0: list of [w, q] per step, the footing's "
    "settlement (m) and the soil's vertical force on it over its width (Pa); "
    "null without a push",
    "push_capacity": "mean of q over w from 0.05 to 0.15 surcharge_width (the "
    "curve's linear interpolant), Pa; null when the push stops short of it",
    "push_capacity_ratio": "push_capacity / surcharge_collapse (the same "
    "footing's collapse pressure by limit analysis on the initial lattice)",
}


def pushing(values: Mapping[str, Any]) -> bool:
    """Whether the run is a footing push (:func:`check_push` has passed)."""
    return values["push_depth"] > 0


def check_push(values: Mapping[str, Any]) -> None:
    """Refuse a push the scene cannot model, naming the parameter.

    A push needs ``analysis=incremental``, a strip (``surcharge_width``) that
    is a rigid footing (``surcharge_footing`` smooth or rough) and no dead
    pressure on it (``surcharge = 0``); it replaces the run-out
    (``runout=false``), runs without ``kh`` and goes at most the slope's
    height down.  That it runs dry is checked when it is built
    (:func:`push_model`: the water is known once the section is read).
    """
    depth = values["push_depth"]
    if depth == 0:
        return
    rules = [
        ("analysis", values["analysis"] != "limit", "incremental with push_depth > 0"),
        ("surcharge_width", values["surcharge_width"] is not None, "a width (m)"),
        (
            "surcharge_footing",
            values["surcharge_footing"] != "flexible",
            "smooth or rough with push_depth > 0 (the pushed strip is rigid)",
        ),
        (
            "surcharge",
            values["surcharge"] == 0,
            "0 with push_depth > 0 (the footing carries what the push needs)",
        ),
        (
            "runout",
            not values["runout"],
            "false with push_depth > 0 (the push replaces the run-out)",
        ),
        ("kh", values["kh"] in (0, 0.0), "0 with push_depth > 0 (a static push)"),
    ]
    for name, ok, allowed in rules:
        if not ok:
            raise ParameterError(name, values.get(name), allowed)
    if not values["geometry"] and depth > values["height"]:
        raise ParameterError(
            "push_depth", depth, f"at most the slope's height ({values['height']:g} m)"
        )


def footing(values: Mapping[str, Any], body: Any, mats: list[Any]) -> RigidBody:
    """The strip as a rigid footing resting on the crest, moving down.

    A rough footing's interface takes the soil under the strip: its friction
    angle, or (``phi = 0``) its cohesion there as the adhesion.
    """
    _, _, x_crest, y_crest = toe_and_crest(body.sec, values)
    near = x_crest - values["surcharge_offset"]
    far = near - values["surcharge_width"]
    top = y_crest + values["push_depth"] + values["surcharge_width"]
    law: dict[str, float] = {}
    if values["surcharge_footing"] == "rough":
        under = np.flatnonzero(strip(body.pts, body.sec, values))
        soil = mats[int(body.material[under[0]])]
        phi = getattr(soil, "phi", 0.0)
        if phi > 0:
            law["friction_angle"] = float(phi)
        else:
            grow = body.strength
            factor = 1.0 if grow is None else float(grow[under].mean())
            law["adhesion"] = float(soil.c) * factor
    return RigidBody(
        [[far, y_crest], [near, y_crest], [near, top], [far, top]],
        velocity=[0.0, -values["push_speed"]],
        name="footing",
        reference=[0.5 * (far + near), y_crest],
        **law,
    )


def push_time(values: Mapping[str, Any]) -> tuple[float, float]:
    """``(dt, t_end)`` of the push: a quarter of the spacing per step."""
    speed = values["push_speed"]
    dt = STEP_FRACTION * values["spacing"] / speed
    return dt, values["push_depth"] / speed


def push_model(values: Mapping[str, Any], body: Any) -> Model:
    """The quasi-static model of the push: gravity, the footing, no reduction.

    Raises
    ------
    ParameterError
        For a slope with pore water (``water_level``, or a cross-section
        file's water line): the push runs dry.
    """
    if slope_water(values, body.sec) is not None:
        raise ParameterError(
            "push_depth",
            values["push_depth"],
            "0 on a slope with pore water (the push runs dry: leave out "
            "water_level, or the section file's water line)",
        )
    mats = section_materials(body.sec, values, flow=True)
    return Model(
        dim=2,
        materials=mats,
        gravity=GRAVITY,
        mode="static",
        bodies=[footing(values, body, mats)],
        solver=solver_from(values),
        strength_law=clay_law(values),
        **fidelity_from(values, 0.0),
    )


def push_curve(records: list[Any], width: float) -> list[list[float]]:
    """``[w, q]`` of every step: settlement (m), vertical force over width (Pa)."""
    return [
        [-float(r.extra["footing_y"]), float(r.extra["footing_force_y"]) / width]
        for r in records
        if "footing_force_y" in r.extra
    ]


def push_metrics(sim: Any, values: Mapping[str, Any], body: Any) -> dict[str, Any]:
    """The push's metrics: its curve, its capacity and the limit analysis's."""
    B = values["surcharge_width"]
    curve = push_curve(sim.records, B)
    lo, hi = (f * B for f in CAPACITY_WINDOW)
    capacity = None
    if curve and curve[-1][0] >= hi * (1 - 1e-9):  # the whole window pushed
        capacity = window_mean(curve, 0.5 * (lo + hi), 0.5 * (hi - lo))[0]
    notes: list[str] = []
    ni = nodal_integration(body.mesh, (0, 1, 3))
    gravity, _ = slope_loads(ni, body.mats, body.material, body.mesh, None)
    try:
        collapse = surcharge_collapse(values, body, body.mats, ni, gravity)
    except SolverError as err:
        # A second analysis: its failure must not cost the push's curve.
        collapse = None
        notes.append(f"slope: the footing's collapse pressure was not found ({err})")
        warn_user(notes[-1])
    ratio = None
    if capacity is not None and collapse is not None and collapse > 0:
        ratio = capacity / collapse
    return {
        "notes": notes,
        "push_curve": curve,
        "push_capacity": capacity,
        "push_capacity_ratio": ratio,
        "surcharge_collapse": collapse,
    }
