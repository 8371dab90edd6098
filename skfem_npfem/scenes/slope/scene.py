"""Scene ``slope``: a slope's factor of safety, its mechanism, and the run-out.

Plane strain.  The parametric section is a slope of ``height`` H and ``angle``
(degrees from horizontal, 90: a vertical cut) facing +x, with a crest
``crest_length`` long and a toe plain ``toe_length`` long on a foundation layer
``foundation_depth`` deep; or, with ``geometry=FILE``, the regions and
materials of a cross-section file (JSON, format in
:mod:`skfem_npfem.mesh.section_file`, an example in
``docs/examples/two_layer_slope.json``).  Particles fill the section at
``spacing``.  The base is fixed and the sides are on rollers.

Stages, in one run:

1. **initial stresses** -- ``initial_stress=gravity``: gravity switched on in
   one elastic static step (equilibrium by construction; its residual is
   reported), or ``k0``: ``s_v = -rho g * depth`` below the surface,
   ``s_h = K0 s_v`` (not in equilibrium under a slope: the residual says how
   far);
2. **factor of safety** by strength reduction (``c/F``, ``tan(phi)/F``) with
   the collapse mechanism (with an output folder: ``mechanism.npz``, drawn by
   ``skfem-npfem plot`` as ``plots/mechanism.png``), from limit analysis on
   the particles' mesh (:func:`~skfem_npfem.limit.safety.strength_reduction`;
   ``analysis=limit`` runs this stage only);
3. **failure and run-out**, with ``runout=true``: the strengths divided by
   ``reduction`` (default: ``margin`` times the factor of safety, or 1 when
   the factor of safety is below 1: such a slope fails as it is) and the
   PFEM loop run until the slide is at rest (kinetic energy below
   ``rest_fraction`` of its peak) or ``t_end``; or, with ``push_depth > 0``,
   **a footing pushed** down on the crest instead: the surcharge's strip as a
   rigid footing, quasi-static steps with the strengths unreduced, its
   pressure-settlement curve against its limit analysis (:mod:`.push`).

With water (``rho`` saturated, ``c``, ``phi`` effective) the factor of safety
adds the pore pressure's force (``drained``) or uses the undrained strengths
of the initial effective stresses (``undrained``; :mod:`.water`).

On the parametric section ``su_gradient`` or ``layers`` make ``c`` grow with
the depth below the slope's surface (:mod:`.profile`), and ``sensitivity``,
``ductility``, ``rate_parameter`` soften the run-out's clay as it is
remoulded (a sensitive clay; ``retrogression`` says how far behind the crest
the failure reached).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from ...constants import GRAVITY
from ...errors import NpfemError
from ...mesh.regions import fill_regions
from ...mesh.smoothing import nodal_integration
from ...mesh.sources import FixedMesh
from ...particles import Particles
from ...run.rest import AtRest
from ...run.simulation import Simulation
from ..base import Scene, SceneRun
from ..common import (
    elastic_params,
    fidelity_params,
    make_writer,
    solver_params,
)
from ..limit_mode import LIMIT_METRICS, analysis_param
from ..params import ANGLE, POSITIVE, Param, Values
from ..refinement import (
    INSERT_METRICS,
    REFINE_METRICS,
    SLOPE_REFINE_PARAMS,
    insert_metrics,
    progress_lines,
    refiner_from,
)
from ..scenery import Scenery, number, section_lines
from ..soil_profile import CLAY_PARAMS, PROFILE_PARAMS
from ..water import WATER_PARAMS
from ..wet_soil import recorded_parameters
from .body import run_out_mesher, slope_body
from .checks import ignored
from .push import (
    PUSH_METRICS,
    PUSH_PARAMS,
    push_metrics,
    push_model,
    push_time,
    pushing,
)
from .runout import RUNOUT_METRICS, base_metrics, runout_metrics
from .section import check_section, section_of, toe_and_crest
from .seismic import KH_PARAM, SEISMIC_METRICS
from .stages import (
    flow_model,
    fos_metrics,
    initial_stress,
)
from .surcharge import (
    SURCHARGE_METRICS,
    SURCHARGE_PARAMS,
    surcharge_load,
)
from .water import (
    derive_slope_drainage,
    slope_water,
    wet_particles,
)

MATERIALS = ("mohr-coulomb", "tresca")

FOUNDATION_NOTE = (
    "foundation layer below the toe (0: the slope stands on the rigid base, "
    "which carries the run-out beyond the toe as a floor)"
)
FLOOR_NOTE = (
    "friction angle of the rigid floor that carries the run-out when "
    "foundation_depth = 0 (lagged Coulomb friction)"
)
PARAMS = [
    Param("height", 10.0, "m", "slope height H", float, **POSITIVE),
    Param(
        "angle",
        45.0,
        "deg",
        "slope angle from horizontal (90: vertical cut)",
        float,
        lo=0,
        hi=90,
        lo_open=True,
    ),
    Param("foundation_depth", 5.0, "m", FOUNDATION_NOTE, float, lo=0),
    Param("crest_length", None, "m", "crest plateau (default 1.5 H)", float, lo=0),
    Param("toe_length", None, "m", "toe plain (default 2.5 H)", float, lo=0),
    Param("floor_friction", 30.0, "deg", FLOOR_NOTE, float, lo=0, hi=89),
    Param(
        "geometry",
        None,
        "-",
        "cross-section file (JSON regions and materials) instead of the "
        "parametric slope",
        str,
        note="the path of a JSON cross-section file",
    ),
    Param("spacing", None, "m", "particle spacing (default H/10)", float, **POSITIVE),
    Param("material", "mohr-coulomb", "-", "yield criterion", str, MATERIALS),
    *elastic_params(2.0e7),
    Param("c", 1.0e4, "Pa", "cohesion", float, lo=0),
    Param(
        "phi",
        20.0,
        "deg",
        "friction angle (tresca: 0; another value is refused)",
        float,
        **ANGLE,
    ),
    Param(
        "psi",
        0.0,
        "deg",
        "dilation angle of the run-out (limit analysis is associated)",
        float,
        **ANGLE,
    ),
    Param("rho", 2000.0, "kg/m^3", "density (saturated with water)", float, **POSITIVE),
    KH_PARAM,
    *SURCHARGE_PARAMS,
    *PUSH_PARAMS,
    *PROFILE_PARAMS,
    *CLAY_PARAMS,
    *WATER_PARAMS,
    Param(
        "initial_stress",
        "gravity",
        "-",
        "gravity (elastic step) or k0",
        str,
        ("gravity", "k0"),
    ),
    Param(
        "K0", None, "-", "at-rest coefficient (default 1 - sin phi)", float, **POSITIVE
    ),
    analysis_param("initial stresses, factor of safety, and run-out if asked"),
    Param("runout", False, "-", "run the failure and run-out stage", bool),
    Param(
        "reduction",
        None,
        "-",
        "strength reduction factor of the run-out (default margin x factor of safety)",
        float,
        **POSITIVE,
    ),
    Param("margin", 1.5, "-", "reduction / factor of safety by default", float, lo=1.0),
    Param(
        "dt",
        None,
        "s",
        "initial time step (default 0.02 sqrt(H/g))",
        float,
        **POSITIVE,
    ),
    Param("t_end", None, "s", "end time cap (default 15 sqrt(H/g))", float, **POSITIVE),
    Param(
        "rest_fraction",
        1e-3,
        "-",
        "at rest: kinetic energy below this fraction of its peak",
        float,
        lo=0,
        hi=1,
        lo_open=True,
        hi_open=True,
    ),
    Param("alpha", 1.3, "-", "alpha-shape parameter of the remeshing", float, lo=1.0),
    Param(
        "max_displacement",
        0.5,
        "-",
        "largest step displacement / spacing",
        float,
        **POSITIVE,
    ),
    *SLOPE_REFINE_PARAMS,
    *fidelity_params(0.0),
    *solver_params(),
]

METRICS = {
    "factor_of_safety": "strength reduction factor at which the slope just "
    "carries its weight (limit analysis)",
    "fos_iterates": "list of [F, gravity multiplier] of every cone program",
    "factor_of_safety_coarse": "the factor of safety again at twice the spacing "
    "(a convergence hint; null when the section cannot be filled there, and with "
    "refine=strain: see refine_history)",
    "fos_spacing_change": "(F - F at twice the spacing) / F: above 0.05 in size a "
    "warning says F is not converged (refine the spacing)",
    "warnings": "list of one-line warnings: implausible material values of a "
    "section file or of the parameters (a unit mistake), regions thinner than "
    "4 spacings, a factor of safety that changes by more than 5 % at twice the "
    "spacing, a deposit whose factor of safety was not found",
    "initial_equilibrium_residual": "|G s - f| / |f| on the free dofs of the "
    "initial stresses (null with analysis=limit)",
    **RUNOUT_METRICS,
    "n_particles": "particles of the run-out at its start (without it: of the "
    "factor of safety's last lattice)",
    "stage_wall_time": "seconds per stage: initial_stress, factor_of_safety (all "
    "its cone programs), factor_of_safety_check (at twice the spacing), "
    "critical_kh (its program), runout (the steps of the run-out or the push)",
    **LIMIT_METRICS,
    "collapse_multiplier": "gravity multiplier of the unreduced strengths (the "
    "first program; capped at 1e3: a cohesionless slope that stands carries "
    "any multiple of its weight)",
    **SEISMIC_METRICS,
    **SURCHARGE_METRICS,
    **PUSH_METRICS,
    **REFINE_METRICS,
    **INSERT_METRICS,
    "undrained_strength_min": "drainage=undrained: the smallest strength s_u = "
    "c' cos phi' + s'_0 sin phi' (initial effective stress) used for F, Pa",
    "undrained_strength_max": "drainage=undrained only: the largest one, Pa",
}


# -- build ----------------------------------------------------------------------
def resolve_values(values: dict[str, Any]) -> None:
    """The slope's derived defaults, in place: ``spacing``, ``dt``, ``t_end``.

    The parametric slope's ``crest_length`` (1.5 H) and ``toe_length`` (2.5 H)
    are filled first.
    ``drainage`` follows ``water_level`` (or a section file's water line).
    The spacing defaults to H/10 (a section file: its tallest region / 20);
    ``dt`` to ``0.02 sqrt(H/g)`` and ``t_end`` to ``15 sqrt(H/g)`` with the
    height H of the section filled at that spacing.  A section too large for
    the machine, or with regions too thin for the spacing, is refused here.

    Parameters
    ----------
    values : dict
        The checked parameter values (defaults and overrides).
    """
    derive_slope_drainage(values)
    if not values["geometry"]:
        H = values["height"]
        if values["crest_length"] is None:
            values["crest_length"] = 1.5 * H
        if values["toe_length"] is None:
            values["toe_length"] = 2.5 * H
    sec, default_h = section_of(values)
    h = values["spacing"] if values["spacing"] is not None else default_h
    values["spacing"] = h
    check_section(sec, h, values)
    if values["dt"] is None or values["t_end"] is None:
        H = float(np.ptp(fill_regions(sec.regions, h)[0][:, 1]))
        if values["dt"] is None:
            values["dt"] = 0.02 * math.sqrt(H / GRAVITY)
        if values["t_end"] is None:
            values["t_end"] = 15 * math.sqrt(H / GRAVITY)


def stage_one(
    values: Values, body: Any, water: Any, state: dict[str, Any]
) -> tuple[np.ndarray, float | None]:
    """Stage 1's stresses and residual (zero and None with ``analysis=limit``).

    Its wall time and the stresses go into ``state``.
    """
    if values["analysis"] == "limit":
        return np.zeros((len(body.pts), 4)), None
    t0 = time.perf_counter()
    sigma, resid = initial_stress(
        values,
        body.mesh,
        body.mats,
        body.material,
        body.fixed,
        water,
        surcharge_load(body.pts, body.sec, values),
        body.stiffness,
    )
    state["t_initial"] = time.perf_counter() - t0
    state["initial_stress"] = sigma
    return sigma, resid


def build(
    values: Values, out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build the slope's staged run (or its limit analysis only).

    Parameters
    ----------
    values : Values
        The scene's resolved parameter values (:func:`resolve_values`).
    out : Path, optional
        Output folder.
    progress : callable, optional
        Progress reporter of the run.
    resume : bool
        Resume from the folder's checkpoint.

    Returns
    -------
    SceneRun
        No steps without the run-out (its metrics run stage 2 when asked);
        with it, steps until at rest or ``t_end``.
    """
    body = slope_body(values)
    pts, material, fixed = body.pts, body.material, body.fixed
    H = float(np.ptp(pts[:, 1]))
    limit_only = values["analysis"] == "limit"
    water = slope_water(values, body.sec)
    state: dict[str, Any] = {}
    sigma, resid = stage_one(values, body, water, state)
    ni = nodal_integration(body.mesh, (0, 1, 3))
    masses = np.array([m.rho for m in body.mats])[material] * ni.volumes
    run_out = values["runout"] and not limit_only
    push = pushing(values)
    if push:
        model = push_model(values, body)
    else:
        # The run's progress (None: on, as the Simulation takes it) also
        # reports the cycles of an adaptive factor of safety made first.
        lines = progress_lines(True if progress is None else bool(progress))
        model = flow_model(values, body, state, run_out, lines)
    particles = Particles.create(
        pts,
        masses,
        stress=sigma,
        fixed=fixed,
        material=material,
        n_walls=len(model.walls),
    ).replace(strength=body.strength, stiffness=body.stiffness)
    particles = wet_particles(particles, water, body.mesh.t)
    moving = run_out or push
    source = run_out_mesher(body, values["alpha"]) if moving else FixedMesh(body.mesh.t)
    dt, t_push = push_time(values) if push else (values["dt"], 0.0)
    sim = Simulation(
        particles,
        model,
        source,
        dt,
        adaptive=True,
        # The push moves its footing a quarter spacing per step.
        max_displacement=None if push else values["max_displacement"],
        writer=make_writer(out, resume),
        progress=progress,
        refiner=refiner_from(values, "surface") if run_out else None,
        meta={"scene": "slope", "parameters": recorded_parameters(values)},
    )
    toe_crest = toe_and_crest(body.sec, values)

    def metrics(sim_: Simulation) -> dict[str, Any]:
        fos = fos_metrics(values, body, state, out, progress_lines(sim_.progress))
        # The run-out's lattice, else the last lattice of refine=strain.
        n = len(pts) if run_out else len(state["fos_body"].pts)
        m = base_metrics(fos, resid, n, state, sim_) | dict.fromkeys(PUSH_METRICS)
        if push:
            late = push_metrics(sim_, values, body)
            m["warnings"] = [*m.get("warnings", []), *late.pop("notes")]
            m.update(late)
        if run_out:
            late = runout_metrics(sim_, state, values, body.h, *toe_crest)
            m["warnings"] = [*m.get("warnings", []), *late.pop("notes")]
            m.update(late | insert_metrics(sim_))
        return m

    derived = {}
    phis = {getattr(m, "phi", 0.0) for m in body.mats}
    if values["initial_stress"] == "k0" and not limit_only and len(phis) == 1:
        derived["K0"] = float(1 - np.sin(np.radians(phis.pop())))  # as used
    if push:
        return SceneRun(sim, {"t_end": t_push}, metrics, derived=derived)
    if not run_out:
        return SceneRun(sim, {"steps": 0}, metrics, derived=derived)
    stop = AtRest(values["rest_fraction"], 2 * math.sqrt(H / GRAVITY))
    state["stop"] = stop
    return SceneRun(
        sim,
        {"t_end": values["t_end"], "stop": stop},
        metrics,
        derived=derived | {"reduction": state["reduction"]},
    )


def slope_scenery(p: dict, folder: Path | None = None) -> Scenery:
    """The slope's scenery: base, side rollers, outline and layer boundaries.

    The section is the run's (its ``geometry`` file, else the parametric
    slope); a file that cannot be read any more leaves the fixed base alone.
    """
    s = Scenery(scene="slope")
    if number(p, "height") is None:
        return s
    s.floor, s.floor_label = 0.0, "fixed base"
    values = {q.name: q.default for q in PARAMS} | dict(p)
    try:
        sec, _ = section_of(values)
    except (NpfemError, OSError, ValueError, KeyError, TypeError):
        return s
    polygons = [r.polygon for r in sec.regions]
    pts = np.concatenate(polygons)
    s.outline, between = section_lines(polygons)
    s.boundaries = between if len(between) else None
    s.floor = float(pts[:, 1].min())
    if sec.supports.get("base") != "fixed":
        s.floor_label = f"base ({sec.supports.get('base')})"
    if sec.supports.get("sides") == "rollers":
        s.walls += [
            (float(pts[:, 0].min()), 1, "side rollers"),
            (float(pts[:, 0].max()), -1, ""),
        ]
    return s


SCENE = Scene(
    name="slope",
    description=__doc__.strip().splitlines()[0].split(": ", 1)[1],
    params=PARAMS,
    build=build,
    metrics_doc=METRICS,
    scenery=slope_scenery,
    derive=resolve_values,
    ignored=ignored,
)
