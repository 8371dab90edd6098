"""Scene ``cone-penetration``: a 60-degree cone with its shaft pushed through clay.

Axisymmetric (the ``(r, z)`` half-section), quasi-static steps with
remeshing.  A rigid cone of diameter ``diameter`` (default the standard
10 cm^2 cone, 35.7 mm) with a 60-degree apex and its shaft starts embedded
("wished in place"), its tip ``depth`` below the soil's surface, and is
pushed down at ``speed`` by ``penetration``.  The soil is a weightless
Tresca material (``s_u``, shear modulus ``rigidity_index * s_u``) under an
isotropic initial stress ``sigma_0``: the surface carries ``sigma_0`` as a
surcharge (the overburden of a deep test; ``surface=rollers`` holds it
instead, which closes the soil in a container that the shaft's growing
volume pressurises), the base is fixed, the far side on rollers, and the
axis is a frictionless wall.  Particles start on the cone's face and
shaft (an unsupported cavity would close plastically under ``sigma_0``) and
on a graded lattice: ``spacing`` within ``1.5 D`` of the axis and over the
tip's path (from ``2 D`` below its end to ``2 D`` above its start), growing
by ``grading`` per row beyond.

The cone and its shaft are one :class:`~skfem_npfem.RigidBody`; the
interface (smooth, or Tresca adhesion ``alpha s_u``) acts on the cone's face
and the shaft is smooth, so the body's vertical force over ``pi D^2/4`` is the
tip resistance ``q_c`` (the sleeve friction of a real cone is not modelled).

With ``material=mohr-coulomb`` the soil is an effective-stress clay
(``c``, ``phi``, ``psi``; ``sigma0`` its initial effective stress: a
weightless soil's static pore pressure is nil) and ``drainage`` adds the
pore water: undrained, each cell keeps its volume and the excess pore
pressure is reported (at the shoulder, where a piezocone reads u2); ``su``
is then the clay's undrained strength at the constant mean effective stress
``sigma0`` with the vertical stress intermediate (the plane-strain
``c cos phi + sigma0 sin phi``), against which the cone's resistance matches
a Tresca soil's (docs/validation/cone_penetration.md).  With
``drainage=coupled`` (conductivity ``k``) the water flows while the cone
goes down, and ``dissipation=true`` holds the cone after the push while the
excess pore pressure at u2 dissipates: a CPTu dissipation test against Teh &
Houlsby's (1991) ``T*_50 = 0.245``
(:mod:`~skfem_npfem.scenes.footing.cone_dissipation`).

A Tresca clay may have weight (``rho``) and a strength that grows with depth
(``su_gradient``, ``layers``): the resistance is then read as site
investigation reads it, ``q_net`` and ``N_kt = q_net / s_u(z)`` at the tip's
depth (:mod:`~skfem_npfem.scenes.footing.cone_ground`); ``sensitivity`` and
``rate_parameter`` make it soften and feel the rate
(:mod:`~skfem_npfem.scenes.soil_profile`).

Reference: Teh & Houlsby's (1991) cone factor of a smooth cone in steady
penetration, ``N_c = (q_c - sigma_0)/s_u = 1.25 + 1.84 ln I_r``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ...boundary import wall_x
from ...constants import GRAVITY
from ...laws import teh_houlsby_nc
from ...mesh.sources import AlphaShapeMesher
from ...run.simulation import Simulation
from ...step.model import Model
from ..base import Scene, SceneRun
from ..common import (
    fidelity_from,
    fidelity_params,
    make_writer,
    solver_from,
    solver_params,
)
from ..params import POSITIVE, Param, Values
from ..refinement import INSERT_METRICS, INSERT_PARAMS, insert_metrics, refiner_from
from ..scenery import Scenery, box, number
from ..soil_profile import clay_law
from ..water import is_wet, scene_water, water_params
from .cone_dissipation import (
    DISSIPATION_METRICS,
    DISSIPATION_PARAMS,
    attach_piezocone,
    check_dissipation,
    dissipation_metrics,
    in_push,
)
from .cone_geometry import (
    SHOULDER_PARAM,
    check,
    cone_body,
    cone_height,
    cone_outline,
    sizes,
    soil_points,
)
from .cone_ground import (
    GROUND_METRICS,
    GROUND_PARAMS,
    check_ground,
    cone_soil,
    net_curve,
    start_state,
)
from .penetration_common import (
    ADHESION,
    derive_cone,
    lattice_params,
    penetration_warnings,
    refuse_penetration,
    running_drops,
    steady_factor,
)
from .penetration_soil import (
    WATER_METRICS,
    penetration_parameters,
    pore_metrics,
    soil_params,
)
from .scenery import saved_factor_curve

__all__ = ["INTERFACES", "SCENE", "cone_body"]

#: Cone-soil interfaces.
INTERFACES = ("smooth", "rough", "adhesion")

#: The soil's top surface.
SURFACES = ("surcharge", "rollers")

PARAMS = [
    Param("diameter", 0.0357, "m", "cone diameter D (10 cm^2 cone)", float, **POSITIVE),
    *soil_params(
        1.0e4,
        "c cos phi + sigma0 sin phi (undrained at a constant mean effective "
        "stress sigma0, the vertical stress between the radial and the hoop "
        "ones, as round an expanding cylindrical cavity)",
    ),
    Param(
        "rigidity_index",
        100.0,
        "-",
        "rigidity index I_r = G/s_u",
        float,
        lo=1.0,
        hi=1.0e5,
    ),
    Param(
        "nu",
        0.49,
        "-",
        "Poisson's ratio (tresca: undrained; mohr-coulomb: the skeleton's drained nu')",
        float,
        lo=0.0,
        hi=0.5,
        hi_open=True,
    ),
    Param(
        "sigma0",
        5.0e4,
        "Pa",
        "isotropic initial stress, compression positive (total and, the "
        "scene being weightless, effective: the static pore pressure is nil)",
        float,
        lo=0.0,
    ),
    Param(
        "surface",
        "surcharge",
        "-",
        "the soil's top: surcharge (sigma0 as a pressure on a free surface) or "
        "rollers (held vertically: the soil is closed and the shaft's volume "
        "raises its pressure as the cone goes down)",
        str,
        SURFACES,
    ),
    Param(
        "interface",
        "smooth",
        "-",
        "interface of the cone's face: smooth, rough (adhesion s_u) or adhesion "
        "(alpha s_u); the shaft is smooth",
        str,
        INTERFACES,
    ),
    ADHESION,
    SHOULDER_PARAM,
    Param(
        "penetration",
        None,
        "m",
        "how far the cone is pushed from where it starts (default 6 D: N_c is "
        "steady from about 5 D on)",
        float,
        **POSITIVE,
    ),
    Param(
        "depth",
        None,
        "m",
        "depth of the cone's tip below the soil's surface at the start "
        "(default 10 D, deep enough that the free surface under its surcharge "
        "moves N_c by under 1 %; the cone starts embedded, wished in place)",
        float,
        **POSITIVE,
    ),
    Param(
        "domain_below",
        8.0,
        "-",
        "soil below the tip's final position / D",
        float,
        lo=2.0,
        hi=100.0,
    ),
    Param(
        "domain_radius",
        30.0,
        "-",
        "soil radius / D (its outer wall is a roller: with rollers on top too, "
        "15 D raised N_c by about 8 % at I_r = 100)",
        float,
        lo=3.0,
        hi=100.0,
    ),
    Param(
        "speed",
        0.02,
        "m/s",
        "cone speed (standard 2 cm/s; quasi-static: sets the time unit)",
        float,
        **POSITIVE,
    ),
    Param(
        "dt",
        None,
        "s",
        "time step (default: the cone moves spacing/2 per step; at most one spacing)",
        float,
        **POSITIVE,
    ),
    Param(
        "spacing",
        None,
        "m",
        "particle spacing near the cone (default D/12)",
        float,
        **POSITIVE,
    ),
    *lattice_params("cone"),
    Param(
        "steady_window",
        1.0,
        "-",
        "the steady state: the last steady_window x D of the push (at most "
        "the whole push)",
        float,
        lo=0.05,
        hi=100.0,
    ),
    *GROUND_PARAMS,
    *INSERT_PARAMS,
    *water_params(coupled=True),
    *DISSIPATION_PARAMS,
    *fidelity_params(0.0),
    *solver_params(),
]

METRICS = {
    "cone_factor": "steady N_c = (q_c - sigma_0)/s_u (s_u: su): the median of "
    "the steps' N_c over the last steady_window x D of the push",
    "cone_factor_range": "[min, max] of N_c over that window",
    "cone_factor_mean": "mean of N_c over that window (trapezoidal)",
    "cone_factor_drops": "steps of that window whose N_c is under 0.8 x "
    "cone_factor (a step where the soil round the cone gave way)",
    "load_drops": "steps of the whole push whose N_c is under 0.8 x the median "
    "of the steps over the last D/2 of push up to it (the footing's "
    "load_drops)",
    "cone_factor_reference": "Teh & Houlsby (1991): 1.25 + 1.84 ln I_r",
    "relative_error": "cone_factor / reference - 1",
    "max_body_penetration": "deepest a particle got inside the cone "
    "before being put back on its outline, m (over the run)",
    "curve": "list of [w/D, N_c] per step (w: how far the cone has been pushed)",
    "n_particles": "number of particles",
    "warnings": "what to look at (a particle deeper than half a spacing inside "
    "the cone)",
    **GROUND_METRICS,
    **INSERT_METRICS,
    **WATER_METRICS,
    "shoulder_excess_pore_pressure": "with water only: the mean excess pore "
    "pressure at the end of the particles beside the shaft (r <= R + spacing) "
    "from the shoulder up to max(0.15 D, spacing) above it (the u2 filter of "
    "a piezocone) / s_u",
    **DISSIPATION_METRICS,
}


def build(
    values: Values, out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build the cone-penetration simulation."""
    dt = check(values)
    check_ground(values)
    g = sizes(values)
    su = values["su"]
    G = values["rigidity_index"] * su
    E = 2 * G * (1 + values["nu"])
    soil = cone_soil(values, E)
    cone = cone_body(values)
    x, spacing = soil_points(values, cone)
    particles, loads = start_state(values, x)
    axis = wall_x(2, 0.0, facing=1)
    model = Model(
        dim=2,
        axisymmetric=True,
        materials=[soil],
        # Darcy's law needs gamma_w = rho_w g; a weightless soil's particles
        # have (next to) no mass.
        gravity=GRAVITY
        if values["drainage"] == "coupled" or values["rho"] > 0
        else 0.0,
        mode="static",
        walls=[axis],
        bodies=[cone],
        loads=loads,
        water=scene_water(values),
        solver=solver_from(values),
        strength_law=clay_law(values),
        **fidelity_from(values, 0.0),
    )
    mesher = AlphaShapeMesher(g["h"], values["alpha"], spacing=spacing, walls=[axis])
    sim = Simulation(
        particles,
        model,
        mesher,
        dt,
        writer=make_writer(out, resume),
        progress=progress,
        meta={
            "scene": "cone-penetration",
            "parameters": penetration_parameters(values),
        },
        refiner=refiner_from(values),
    )
    sim.penetration_check.enabled = False  # penetration_warnings says it
    t_push = g["w"] / values["speed"]
    t_end = attach_piezocone(sim, values, t_push, lambda x, w: shoulder_filter(x, g, w))

    def metrics(sim_: Simulation) -> dict[str, Any]:
        curve, net = net_curve(in_push(sim_, t_push), values)
        steady = steady_factor(curve, values["steady_window"])
        factor = None if steady is None else steady.median
        ref = teh_houlsby_nc(values["rigidity_index"])
        pen = [r.extra.get("cone_penetration", 0.0) for r in sim_.records]
        notes = penetration_warnings(
            "cone-penetration", max(pen, default=0.0), g["h"], dt
        )
        return {
            "cone_factor": factor,
            "cone_factor_range": None if steady is None else steady.range,
            "cone_factor_mean": None if steady is None else steady.mean,
            "cone_factor_drops": None if steady is None else steady.drops,
            "load_drops": running_drops(curve),
            "cone_factor_nkt": factor,
            "q_net": net,
            "cone_factor_reference": ref,
            "relative_error": None if factor is None else factor / ref - 1.0,
            "max_body_penetration": max(pen, default=0.0),
            "curve": curve,
            "n_particles": int(particles.n),
            **insert_metrics(sim_),
            "warnings": notes,
            **pore_metrics(
                sim_.particles,
                values,
                shoulder_filter(sim_.particles.x, g, curve[-1][0] if curve else 0.0),
                "shoulder_excess_pore_pressure",
            ),
            **(dissipation_metrics(sim_, values, t_push) if is_wet(values) else {}),
        }

    return SceneRun(sim, {"t_end": t_end}, metrics)


#: Height of the u2 filter behind the shoulder, in D: a standard piezocone's
#: ring filter is about 5 mm tall on a 35.7 mm cone.
U2_FILTER_HEIGHT = 0.15


def shoulder_filter(x: np.ndarray, g: dict[str, float], push: float) -> np.ndarray:
    """The particles of the u2 filter after ``push`` x D.

    A piezocone reads u2 on a ring filter on the shaft just behind the
    cone: the particles beside the shaft (``r <= R + h``) from the shoulder
    up to :data:`U2_FILTER_HEIGHT` x D above it (at least one spacing ``h``,
    so that a coarse lattice has a row there).  The cone's face below the
    shoulder is left out: it reads u1, which dissipates about twice as fast.
    """
    above = x[:, 1] - shoulder_height(g, push)
    height = max(U2_FILTER_HEIGHT * g["D"], g["h"])
    return (above >= 0.0) & (above <= height) & (x[:, 0] <= g["D"] / 2 + g["h"])


def shoulder_height(g: dict[str, float], push: float) -> float:
    """The height of the cone's shoulder after ``push`` x D (``g``: :func:`sizes`)."""
    return g["z_tip"] - push * g["D"] + cone_height(g)


#: The cone's pictures show r <= WINDOW_R D, from WINDOW_Z D below the end of the
#: tip's path to WINDOW_Z D above its start: the cone and its plastic zone
#: (the whole domain, 30 D x 24 D, left them about 10 px wide).
WINDOW_R, WINDOW_Z = 4.0, 3.0


def cone_scenery(p: dict, folder: Path | None = None) -> Scenery:
    """Base, rollers, the axis, the cone and its shaft, the N_c-w/D curve.

    The pictures show a window a few D around the tip's path
    (:data:`WINDOW_R`, :data:`WINDOW_Z`); steps and ``--times`` are in w/D.
    The curve comes from ``folder``'s ``summary.json``, else from the latest
    checkpoint there.
    """
    s = Scenery(scene="cone-penetration")
    default = {q.name: q.default for q in PARAMS}
    names = (
        "diameter",
        "spacing",
        "penetration",
        "depth",
        "domain_below",
        "domain_radius",
        "shoulder_round",
    )
    values = {k: number(p, k, default[k]) for k in names}
    speed = number(p, "speed", default["speed"])
    if None in (
        values["diameter"],
        values["domain_below"],
        values["domain_radius"],
        speed,
    ):
        return s
    g = sizes(values)
    s.floor, s.floor_label = 0.0, "fixed base"
    s.walls.append((g["radius"], -1, "rollers"))
    s.symmetry = 0.0
    s.outline = box(0.0, g["radius"], 0.0, g["top"])
    s.bodies.append((cone_outline(g), np.array([0.0, -speed]), "cone"))
    D = g["D"]
    s.label = lambda t: f"w/D = {speed * t / D:.3g}"
    s.unit = ("wD", "w/D", D / speed)
    s.window = (
        0.0,
        min(WINDOW_R * D, g["radius"]),
        max(g["z_tip"] - g["w"] - WINDOW_Z * D, 0.0),
        min(g["z_tip"] + WINDOW_Z * D, g["top"]),
    )
    s.window_note = (
        f"window: r \u2264 {WINDOW_R:g} D, {WINDOW_Z:g} D around the tip's path"
    )
    s.diameter = D
    su = number(p, "su", 1.0e4)
    s0 = number(p, "sigma0", default["sigma0"])
    ir = number(p, "rigidity_index", default["rigidity_index"])
    if ir is not None:
        s.factor_reference = teh_houlsby_nc(ir)
    if folder is not None and su and s0 is not None:
        s.factor_curve = saved_factor_curve(Path(folder), D, su, s0)
    return s


def derive(values: dict[str, Any]) -> None:
    """The cone's derived defaults (:func:`derive_cone`); a checked dissipation."""
    derive_cone(values)
    check_dissipation(values)


SCENE = Scene(
    name="cone-penetration",
    description=__doc__.strip().splitlines()[0].split(": ", 1)[1],
    params=PARAMS,
    build=build,
    metrics_doc=METRICS,
    ignored=refuse_penetration,
    derive=derive,
    scenery=cone_scenery,
    time_params=("dt", "penetration"),
)
