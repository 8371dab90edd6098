"""Scene ``footing-penetration``: a rigid strip footing pushed deep into clay.

Half model (symmetry at ``x = 0``), plane strain, quasi-static steps with
remeshing: a rigid :class:`~skfem_npfem.RigidBody` of width ``B`` (the
footing) moves down at ``speed`` into a weightless Tresca layer
``domain_width*B`` wide and ``domain_depth*B`` deep (base fixed, far side on
rollers) until its penetration ``w`` reaches ``penetration``.  The particles
start on a graded lattice: ``spacing`` within ``B`` of the footing's edge and
down to ``penetration + B``, growing by ``grading`` per row beyond.  The
interface is smooth, fully rough (Tresca adhesion ``s_u``) or adhesive
(``alpha s_u``); the soil separates freely from the footing.

The footing pressure ``q`` is the vertical force of the soil on the footing
over its width.  References: Prandtl's ``q/s_u = 2 + pi`` once the soil
yields under a surface footing (smooth or rough: the same in weightless
Tresca soil); past it the pressure rises as the footing is embedded and the
soil heaves beside it.

``material=mohr-coulomb`` makes the soil an effective-stress clay (``c``,
``phi``, ``psi``) and ``drainage`` adds pore water; undrained, its ``su`` is
the plane-strain ``c cos phi`` of the stress-free soil (a uniform initial
stress would need a surcharge beside the footing, which this scene does
not carry).  With ``drainage=coupled`` (conductivity ``k``) the water
flows by Darcy's law while the footing goes down: the footing is
impermeable (the soil touching it), the soil's free surface beside it
drained, the base and the rollers impermeable; the normalised velocity
``V = v B / c_v`` (``c_v = k M / gamma_w``, ``M`` the skeleton's constrained
modulus) sets how far the response is from drained (small ``V``) to
undrained (large ``V``): docs/validation/penetration_backbone.md.

``su_gradient`` or ``layers`` make the strength grow with depth, and
``sensitivity``, ``ductility``, ``rate_parameter``, ``reference_rate`` (with
``softening_length`` as the regularisation) make it soften as the clay is
remoulded and rise with the shear rate (:mod:`~skfem_npfem.scenes.soil_profile`;
N-PFEM only).

``method`` runs the same scene with N-PFEM (default) or FEM-remap (P1 or P2
elements, Gauss-point state remapped after each remesh; the footing enters
its steps through the same stage functions); docs/validation/penetration_methods.md
compares the three curves.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ...boundary import RigidBody
from ...constants import GRAVITY
from ...errors import ParameterError
from ...laws import prandtl_nc
from ...mesh.sources import AlphaShapeMesher
from ...run.refining import initial_rows
from ...run.simulation import Simulation
from ...step.model import Model
from ..base import Scene, SceneRun
from ..common import (
    fidelity_from,
    fidelity_params,
    make_writer,
    solver_from,
    solver_params,
    window_mean,
)
from ..limits import check_size
from ..methods import METHOD_METRICS_NO_SPFEM, method_params, with_method
from ..params import POSITIVE, Param, Values
from ..refinement import INSERT_METRICS, INSERT_PARAMS, insert_metrics, refiner_from
from ..scenery import Scenery, box, number
from ..soil_profile import CLAY_PARAMS, clay_law, profile_params, with_profile
from ..water import is_wet, scene_water, water_params
from .cone_ground import check_ground
from .penetration_common import (
    ADHESION,
    axis_count,
    derive_footing,
    interface_adhesion,
    lattice_params,
    locking_warnings,
    penetration_warnings,
    refuse_penetration,
    running_drops,
    step_dt,
)
from .penetration_ground import (
    NET_METRICS,
    WEIGHT,
    footing_soil,
    geometry,
    net_curve,
    penetration_curve,
    soil,
)
from .penetration_soil import (
    WATER_METRICS,
    penetration_parameters,
    pore_metrics,
    soil_params,
    with_pore_pressure,
)

__all__ = ["INTERFACES", "RIGID_ENOUGH", "SCENE", "consolidation_coefficient"]

#: Footing-soil interfaces.
INTERFACES = ("smooth", "rough", "adhesion")

#: Smallest E_u/s_u at which ``bearing_factor`` (w/B = 0.1) is compared with
#: 2 + pi.  The soil reaches Prandtl's load at a settlement of about
#: 15 s_u/E_u B (measured at B/20: w/B = 0.15 at E_u/s_u = 100, under 0.06
#: at 1000); from 300 on that is at most half of w/B = 0.1, so the window
#: lies on the plastic branch the reference describes.
RIGID_ENOUGH = 300.0


PARAMS = [
    Param("width", 1.0, "m", "footing width B", float, **POSITIVE),
    Param(
        "domain_width",
        10.0,
        "-",
        "soil width / B (half of it modelled)",
        float,
        lo=3.0,
        hi=50.0,
    ),
    Param("domain_depth", 5.0, "-", "soil depth / B", float, lo=1.5, hi=50.0),
    Param(
        "E",
        1.0e5,
        "Pa",
        "Young's modulus (tresca: undrained E_u; mohr-coulomb: the skeleton's E')",
        float,
        **POSITIVE,
    ),
    Param(
        "nu",
        0.495,
        "-",
        "Poisson's ratio (tresca: undrained; mohr-coulomb: the skeleton's drained nu')",
        float,
        lo=0.0,
        hi=0.5,
        hi_open=True,
    ),
    *soil_params(
        1.0e3, "c cos phi (plane strain; the weightless soil starts stress-free)"
    ),
    Param("interface", "smooth", "-", "footing-soil interface", str, INTERFACES),
    ADHESION,
    Param(
        "penetration",
        None,
        "m",
        "final penetration w (default: B)",
        float,
        **POSITIVE,
    ),
    Param(
        "speed",
        1.0,
        "m/s",
        "footing speed (quasi-static: sets the time unit)",
        float,
        **POSITIVE,
    ),
    Param(
        "dt",
        None,
        "s",
        "time step (default: the footing moves spacing/4 per step; at most "
        "one spacing)",
        float,
        **POSITIVE,
    ),
    Param("spacing", 0.05, "m", "particle spacing near the footing", float, **POSITIVE),
    *lattice_params("footing"),
    Param(
        "seal_cavities",
        True,
        "-",
        "true: a hole the alpha test would open inside the soil, reaching the "
        "outside only through supported particles (the symmetry axis, the "
        "fixed base and side) or not at all, stays meshed; false: such holes "
        "open (the soil stretched along the axis under the footing opens "
        "them past w = B/2, and the load falls for a step where one does)",
        bool,
    ),
    *method_params(
        ("npfem", "fem-remap"),
        missing="spfem is not available in footing-penetration: it is explicit "
        "dynamics and this scene is quasi-static, without inertia (and SPFEM "
        "has no rigid-body contact); docs/validation/penetration_methods.md "
        "compares npfem and fem-remap here",
    ),
    WEIGHT,
    *profile_params("su"),
    *CLAY_PARAMS,
    *INSERT_PARAMS,
    *water_params(coupled=True),
    *fidelity_params(0.0),
    *solver_params(),
]

METRICS = {
    "bearing_factor": "q/s_u at w/B = 0.1 (s_u: material=mohr-coulomb's "
    "plane-strain undrained strength c cos phi of the stress-free soil): the "
    "curve's mean over one spacing of "
    "penetration centred there (w/B = 0.1 +- spacing/(2B); it averages the "
    "saw-tooth of soil nodes passing the footing's edge); null if not reached",
    "bearing_factor_range": "[min, max] of q/s_u over that window",
    "bearing_factor_reference": "Prandtl's 2 + pi",
    "relative_error": "bearing_factor / (2 + pi) - 1 when E_u/s_u >= 300; null "
    "below (at the default 100 the soil still settles elastically at w/B = 0.1 "
    "and reaches 2 + pi near w/B = 0.15: the reference does not apply there)",
    "final_bearing_factor": "q/s_u at the final penetration",
    "load_drops": "steps whose q/s_u is under 0.8 x the median of the steps "
    "over the last B/2 of penetration up to it (a step where the soil under "
    "the footing gave way; the cone's load_drops)",
    "max_body_penetration": "deepest a particle got inside the footing before "
    "being put back on its outline, m (over the run)",
    "max_heave": "largest upward displacement of the soil surface / B",
    "warnings": "what to look at: a particle deeper than half a spacing inside "
    "the footing; method=fem-remap with P1 elements (they lock)",
    "curve": "list of [w/B, q/s_u] per step",
    **NET_METRICS,
    **INSERT_METRICS,
    **WATER_METRICS,
    "consolidation_coefficient": "drainage=coupled: c_v = k M / gamma_w "
    "(M = E (1 - nu)/((1 + nu)(1 - 2 nu)), the skeleton's constrained "
    "modulus), m^2/s",
    "normalised_velocity": "drainage=coupled: V = speed B / c_v (drained for "
    "small V, undrained for large V)",
    "n_particles": "number of particles",
    **METHOD_METRICS_NO_SPFEM,
}


def consolidation_coefficient(values: Mapping[str, Any]) -> float:
    """``c_v = k M / gamma_w`` of the skeleton (``E``, ``nu``), m^2/s.

    Examples
    --------
    >>> v = {"E": 1.3e5, "nu": 0.3, "k": 1e-3, "rho_w": 1000.0}
    >>> round(consolidation_coefficient(v) * 9.81, 9)
    0.175
    """
    E, nu = values["E"], values["nu"]
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    return values["k"] * M / (values["rho_w"] * GRAVITY)


def check(values: Mapping[str, Any]) -> float:
    """Refuse bad combinations before anything is built; return ``dt``."""
    B, half, depth, w = geometry(values)
    h = values["spacing"]
    if h > B / 4:
        raise ParameterError("spacing", h, f"at most B/4 = {B / 4:g} m")
    if w > depth - 2 * h:
        raise ParameterError(
            "penetration",
            w,
            f"less than the soil depth minus two spacings ({depth - 2 * h:g} m): "
            "the footing would hit the fixed base",
        )
    if is_wet(values) and values["method"] != "npfem":
        raise ParameterError(
            "method",
            values["method"],
            "npfem with pore water (drainage other than dry)",
        )
    dt = step_dt(values, h, 0.25, "footing")
    nx = axis_count(B / 2 + B, h, half, values["grading"])
    ny = axis_count(w + B, h, depth, values["grading"])
    check_size(nx * ny, 2, values, advice="use a larger spacing or grading")
    return dt


def footing_body(values: Mapping[str, Any]) -> RigidBody:
    """The footing at time 0: resting on the surface, moving down at ``speed``."""
    B, _, depth, w = geometry(values)
    height = w + B
    return RigidBody(
        [
            [-B / 2, depth],
            [B / 2, depth],
            [B / 2, depth + height],
            [-B / 2, depth + height],
        ],
        velocity=[0.0, -values["speed"]],
        adhesion=interface_adhesion(values),
        name="footing",
        reference=[0.0, depth],
    )


def build(
    values: Values, out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build the footing-penetration simulation."""
    dt = check(values)
    check_ground(values)
    locking = locking_warnings(values)  # before the run, and in the metrics
    B, _, _, w = geometry(values)
    su = values["su"]
    particles, spacing, _ = soil(values)
    particles = with_pore_pressure(particles, values)
    depth = geometry(values)[2] - particles.x[:, 1]
    particles = with_profile(values, particles, depth, su, name="su")
    body = footing_body(values)
    model = Model(
        dim=2,
        materials=[footing_soil(values)],
        # Darcy's law needs gamma_w = rho_w g; a weightless soil's particles
        # have (next to) no mass.
        gravity=GRAVITY
        if values["drainage"] == "coupled" or values["rho"] > 0
        else 0.0,
        mode="static",
        bodies=[body],
        water=scene_water(values),
        solver=solver_from(values),
        strength_law=clay_law(values),
        **fidelity_from(values, 0.0),
    )
    seal = values["seal_cavities"]
    h = values["spacing"]
    mesher = AlphaShapeMesher(h, values["alpha"], spacing=spacing, seal_cavities=seal)
    sim = Simulation(
        particles,
        model,
        mesher,
        dt,
        writer=make_writer(out, resume),
        progress=progress,
        meta={
            "scene": "footing-penetration",
            "parameters": penetration_parameters(values),
        },
        refiner=refiner_from(values),
    )
    t_end = w / values["speed"]
    sim.penetration_check.enabled = False  # penetration_warnings says it
    surface = particles.x[:, 1] >= particles.x[:, 1].max() - 1e-9

    def metrics(sim_: Simulation) -> dict[str, Any]:
        curve = penetration_curve(sim_.records, B, su)
        factor, spread = window_mean(curve, 0.1, 0.5 * values["spacing"] / B)
        ref = prandtl_nc(0.0)
        compared = factor is not None and values["E"] >= RIGID_ENOUGH * su
        pen = [r.extra.get("footing_penetration", 0.0) for r in sim_.records]
        rows, ids = initial_rows(sim_.particles, surface.size)  # refined: by id
        heave = float(sim_.particles.u[rows[surface[ids]], 1].max()) / B
        notes = (
            penetration_warnings(
                "footing-penetration", max(pen, default=0.0), values["spacing"], dt
            )
            + locking
        )
        out = {
            "bearing_factor": factor,
            "bearing_factor_range": spread,
            "bearing_factor_reference": ref,
            "relative_error": factor / ref - 1.0 if compared else None,
            "final_bearing_factor": curve[-1][1] if curve else None,
            "load_drops": running_drops(curve),
            "max_body_penetration": max(pen, default=0.0),
            "max_heave": heave,
            "warnings": notes,
            "curve": curve,
            "net_curve": net_curve(curve, values),
            "n_particles": int(particles.n),
            **insert_metrics(sim_),
        }
        if values["drainage"] == "coupled":
            cv = consolidation_coefficient(values)
            out["consolidation_coefficient"] = cv
            out["normalised_velocity"] = values["speed"] * B / cv
        return {**out, **pore_metrics(sim_.particles, values)}

    return with_method(values, SceneRun(sim, {"t_end": t_end}, metrics))


def penetration_scenery(p: dict, folder: Path | None = None) -> Scenery:
    """Base, rollers, symmetry axis, the footing where it is, the load curve."""
    s = Scenery(scene="footing-penetration")
    B = number(p, "width")
    dw, dd = number(p, "domain_width"), number(p, "domain_depth")
    speed = number(p, "speed", 1.0)
    if B is None or dw is None or dd is None:
        return s
    half, depth = dw * B / 2, dd * B
    w = number(p, "penetration") or B
    s.floor, s.floor_label = 0.0, "fixed base"
    s.walls.append((half, -1, "rollers"))
    s.symmetry = 0.0
    s.outline = box(0.0, half, 0.0, depth)
    s.half_width = B / 2
    height = w + B
    s.bodies.append(
        (
            np.array(
                [
                    [0, depth],
                    [B / 2, depth],
                    [B / 2, depth + height],
                    [0, depth + height],
                ],
                float,
            ),
            np.array([0.0, -speed]),
            "footing",
        )
    )
    s.label = lambda t: f"w/B = {speed * t / B:.3g}"
    s.unit = ("wB", "w/B", B / speed)
    su = number(p, "su")
    if su:
        s.q_reference = prandtl_nc(0.0) * su
    if folder is not None:
        s.load_curve = _saved_curve(Path(folder), B, su or 1.0)
    return s


def _saved_curve(folder: Path, B: float, su: float) -> np.ndarray | None:
    """``[w, q]`` rows of a finished run's summary (None without one)."""
    try:
        data = json.loads((folder / "summary.json").read_text())
        c = np.array(data["metrics"]["curve"], dtype=float).reshape(-1, 2)
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return np.stack([c[:, 0] * B, c[:, 1] * su], axis=1)


SCENE = Scene(
    name="footing-penetration",
    description=__doc__.strip().splitlines()[0].split(": ", 1)[1],
    params=PARAMS,
    build=build,
    metrics_doc=METRICS,
    ignored=refuse_penetration,
    derive=derive_footing,
    scenery=penetration_scenery,
    time_params=("dt", "penetration"),
)
