"""Scene ``strip-footing``: rigid strip footing pushed to its collapse load.

Half model (symmetry at ``x = 0``), plane strain, quasi-static steps.  The soil
block is ``domain_width*b`` wide and deep with a mesh graded from ``spacing``
under the footing; base fixed, far side on rollers.  The footing (``width``
``B = 2b``; half-width ``b``) pushes
the surface particles at ``x <= b`` down; it is smooth (horizontal motion free)
or rough (horizontal motion fixed).  The footing pressure is the sum of the
vertical reactions over ``b``.

Settlement steps (:mod:`~skfem_npfem.scenes.footing.plateau`): ``steps`` equal steps
reach ``settlement``; the run then goes on with growing increments until the
load curve is flat (the load changes by at most ``plateau_tol`` while the
settlement doubles) or a cap (``max_settlement``, ``max_steps``) stops it with a
warning.  ``plateau_tol = 0`` runs exactly ``steps`` steps to ``settlement``.
Pseudo-time equals settlement: ``dt`` of a step is its increment (m).

References (weightless soil): Prandtl ``q/c = 2 + pi``; Mohr-Coulomb
``N_c = (N_q - 1) cot(phi)``, ``N_q = exp(pi tan phi) tan^2(45 + phi/2)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ...errors import ParameterError, warn_user
from ...laws import prandtl_nc
from ...materials import DruckerPrager, Material, MohrCoulomb, Tresca
from ...mesh.sources import FixedMesh
from ...particles import Particles
from ...run.simulation import Simulation
from ..base import Scene, SceneRun
from ..common import (
    elastic_params,
    fidelity_params,
    fill_at_rest,
    make_writer,
    solver_params,
)
from ..limit_mode import (
    LIMIT_METRICS,
    analysis_param,
    check_limit_method,
    limit_scene_run,
)
from ..limits import SPACING as SPACING_RANGE
from ..methods import METHOD_METRICS_NO_SPFEM, method_params, with_method
from ..params import ANGLE, POSITIVE, Param, Values
from ..refinement import REFINE_METRICS, REFINE_PARAMS, check_refine, progress_lines
from ..soil_profile import PROFILE_PARAMS, check_layers, has_profile
from ..water import derive_drainage
from .mesh import (
    DEFAULT_DOMAIN,
    DEFAULT_SPACING,
    LIMIT_DOMAIN,
    LIMIT_SPACING,
    resolve_defaults,
    soil_mesh,
    soil_particles,
    unit_weight,
)
from .plateau import PlateauRule
from .scenery import footing_scenery
from .strip_coupled import (
    LOAD_METRICS,
    LOAD_PARAMS,
    footing_model,
    footing_parameters,
    held_load_run,
)
from .strip_limit import HETEROGENEITY_METRICS, footing_limit, heterogeneity_factor
from .strip_water import (
    FOOTING_WATER_PARAMS,
    footing_gamma,
    undrained_strength,
)
from .usage import ignored

MATERIALS = ("tresca", "mohr-coulomb", "drucker-prager")


#: Default minimum settlement in units of ``(c + gamma b) b / E``.
SETTLEMENT_SCALE = 100.0
#: Default ``max_settlement`` in units of ``settlement``.
MAX_SETTLEMENT_FACTOR = 100.0


PARAMS = [
    Param("material", "tresca", "-", "yield criterion", str, MATERIALS),
    *elastic_params(1.0e8),
    Param(
        "c",
        1.0e4,
        "Pa",
        "cohesion (tresca: the undrained strength s_u, > 0; c = 0 needs rho > 0)",
        float,
        lo=0,
    ),
    Param(
        "phi",
        0.0,
        "deg",
        "friction angle (tresca: 0; another value is refused)",
        float,
        **ANGLE,
    ),
    Param(
        "psi", None, "deg", "dilation angle (default: phi, associated)", float, **ANGLE
    ),
    Param(
        "rho",
        0.0,
        "kg/m^3",
        "density of the soil (0: weightless); its unit weight is gamma = rho g",
        float,
        lo=0,
    ),
    Param(
        "gravity",
        9.81,
        "m/s^2",
        "gravitational acceleration (acts when rho > 0)",
        float,
        **POSITIVE,
    ),
    Param(
        "K0",
        None,
        "-",
        "at-rest earth pressure coefficient s_xx / s_yy of the initial "
        "geostatic stress (default Jaky's 1 - sin phi, phi of the soil; no "
        "effect on a weightless soil)",
        float,
        **POSITIVE,
    ),
    Param(
        "interface", "smooth", "-", "footing-soil interface", str, ("smooth", "rough")
    ),
    Param("width", 2.0, "m", "footing width B = 2b", float, **POSITIVE),
    Param(
        "spacing",
        None,
        "m",
        f"element size under the footing (default {DEFAULT_SPACING:g}; "
        f"{LIMIT_SPACING:g} with analysis=limit)",
        float,
        **SPACING_RANGE,
    ),
    Param(
        "grading",
        1.15,
        "-",
        "element growth ratio away from the footing",
        float,
        lo=1.0,
        hi=2.0,
    ),
    Param(
        "domain_width",
        None,
        "-",
        "soil width / B (half of it modelled: the half block is as deep as it "
        f"is wide; default {DEFAULT_DOMAIN:g}, {LIMIT_DOMAIN:g} with "
        "analysis=limit)",
        float,
        lo=2.0,
        hi=50.0,
    ),
    Param(
        "settlement",
        None,
        "m",
        "minimum settlement, reached in `steps` equal steps (default "
        f"{SETTLEMENT_SCALE:g} (c + gamma b) b / E: 0.01 m at the defaults)",
        float,
        **POSITIVE,
    ),
    Param(
        "steps",
        8,
        "-",
        "number of equal settlement steps up to `settlement` (the first stage; "
        "the run then goes on with growing steps until the plateau or a cap, "
        "max_steps counting all steps; exactly `steps` steps with "
        "plateau_tol = 0)",
        int,
        lo=1,
    ),
    Param(
        "plateau_tol",
        None,
        "-",
        "continue until the load changes by at most this fraction while the "
        "settlement doubles; 0: stop after `steps` (default 1e-3; 0 with "
        "large_deformation, whose load keeps rising)",
        float,
        lo=0,
        hi=0.5,
    ),
    Param(
        "growth",
        1.5,
        "-",
        "increment factor per step after `settlement` while the curve is "
        "straight (1: equal steps)",
        float,
        lo=1.0,
        hi=4.0,
    ),
    Param(
        "max_settlement",
        None,
        "m",
        "cap on the settlement without a plateau (default "
        f"{MAX_SETTLEMENT_FACTOR:g} x settlement)",
        float,
        **POSITIVE,
    ),
    Param("max_steps", 100, "-", "cap on the number of steps", int, lo=1),
    Param(
        "large_deformation",
        False,
        "-",
        "move the particles with the soil (updated Lagrangian); false: "
        "small-strain limit analysis",
        bool,
    ),
    *PROFILE_PARAMS,
    *REFINE_PARAMS,
    *FOOTING_WATER_PARAMS,
    *LOAD_PARAMS,
    analysis_param("settlement steps to the load plateau"),
    *method_params(
        ("npfem", "fem-remap"),
        missing="spfem is not available in strip-footing: it is explicit "
        "dynamics and this scene is quasi-static, without inertia",
    ),
    *fidelity_params(0.0),
    *solver_params(),
]

METRICS = {
    "q_ult": "footing pressure at the last step (= collapse load on the plateau), Pa",
    "bearing_factor": "q_ult / c (c > 0), else q_ult / (gamma b) = N_gamma (B = 2b, "
    "gamma = rho g; (rho - rho_w) g under a water table at or above the ground); "
    "q_ult / s_u for an undrained weightless soil with psi = 0",
    "bearing_factor_reference": "Prandtl-Reissner N_c for weightless soil (2 + pi "
    "undrained, s_u = c cos phi + p0 sin phi; else null)",
    "relative_error": "bearing_factor / reference - 1 (weightless soil)",
    "load_curve": "list of [settlement (m), pressure (Pa)] per step",
    "plateau_reached": "true if the run stopped on a detected plateau, false if a "
    "cap stopped it first (then q_ult is a lower estimate, except for fem-remap "
    "with P1 elements and isochoric plastic flow, which locks: its load is "
    "inflated, see warnings); null when plateau_tol = 0",
    "plateau_change": "relative load change over the last doubling of the "
    "settlement (null before the settlement has doubled)",
    "plateau_tolerance": "plateau_tol used (0: detection off)",
    "plateau_settlement": "settlement at which the plateau was detected, m (null: "
    "not reached)",
    "stopped_by": "plateau, max_settlement, max_steps or steps (plateau_tol = 0)",
    "warnings": "list of one-line warnings (a cap stopped the run before the "
    "plateau; fem-remap P1 locking); the CLI prints each on stderr",
    "n_particles": "number of particles",
    **METHOD_METRICS_NO_SPFEM,
    **HETEROGENEITY_METRICS,
    **REFINE_METRICS,
    **LIMIT_METRICS,
    **LOAD_METRICS,
}


def soil_material(values: Mapping[str, Any]) -> tuple[Material, float]:
    """The soil material and its friction angle (0 for Tresca)."""
    name = values["material"]
    c, phi = values["c"], values["phi"]
    psi = phi if values["psi"] is None else values["psi"]
    rho = values["rho"]
    E, nu = values["E"], values["nu"]
    if name == "tresca":
        if c <= 0:
            raise ParameterError(
                "c",
                c,
                "material=tresca needs c > 0 (c = 0 is allowed with "
                "mohr-coulomb or drucker-prager and rho > 0)",
            )
        mat, phi = Tresca(E, nu, rho, c=c), 0.0
    elif name == "mohr-coulomb":
        mat = MohrCoulomb(E, nu, rho, c=c, phi=phi, psi=psi)
    else:
        mat = DruckerPrager(E, nu, rho, c=c, phi=phi, psi=psi)
    if c == 0 and rho == 0:
        raise ParameterError("rho", rho, "must be > 0 when c = 0 (no strength)")
    return mat, phi


def derive(values: dict[str, Any]) -> None:
    """The strip footing's derived defaults, in place.

    ``spacing`` and ``domain_width`` (:func:`resolve_defaults`); Jaky's ``K0``
    and the associated ``psi = phi`` of the soil; the stepping:
    ``settlement`` (``100 (c + gamma b) b / E``), ``plateau_tol``
    (1e-3, 0 with large_deformation) and ``max_settlement`` (100 x
    settlement).
    """
    resolve_defaults(values)
    derive_drainage(values)
    check_layers(values)
    check_refine(values)
    fill_at_rest(values)
    if values["psi"] is None:
        values["psi"] = values["phi"]
    b = values["width"] / 2
    if values["settlement"] is None:
        strength = values["c"] + unit_weight(values) * b
        values["settlement"] = SETTLEMENT_SCALE * strength * b / values["E"]
    if values["plateau_tol"] is None:
        values["plateau_tol"] = 0.0 if values["large_deformation"] else 1e-3
    if values["max_settlement"] is None:
        values["max_settlement"] = MAX_SETTLEMENT_FACTOR * values["settlement"]


def plateau_rule(values: Mapping[str, Any]) -> PlateauRule:
    """The stepping and stop rule from the resolved parameters (:func:`derive`)."""
    return PlateauRule(
        settlement=values["settlement"],
        steps=values["steps"],
        tol=values["plateau_tol"],
        growth=values["growth"],
        max_settlement=values["max_settlement"],
        max_steps=values["max_steps"],
    )


def build(
    values: Values, out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build the strip-footing simulation (or its limit analysis)."""
    check_limit_method(values)
    mesh = soil_mesh(values)
    mat, phi = soil_material(values)
    rule = plateau_rule(values)
    particles, foot = soil_particles(values, mesh, phi)
    if values["load"] is not None:  # loaded fast, then held
        writer = make_writer(out, resume)
        return held_load_run(values, mesh, mat, particles, foot, writer, progress)
    b, c, gamma = values["width"] / 2, values["c"], footing_gamma(values)
    model = footing_model(values, mat)
    sim = Simulation(
        particles,
        model,
        FixedMesh(mesh.t),
        rule.first_increment,
        writer=make_writer(out, resume),
        progress=progress,
        meta={"scene": "strip-footing", "parameters": footing_parameters(values)},
    )

    def record(sim_: Simulation, p: Particles, res) -> bool:
        # Stored on the step record so that it survives checkpoints (--resume).
        rec = res.record
        rec.extra["settlement"] = float(-p.u[foot, 1].mean())
        rec.extra["pressure"] = -float(res.solution.reaction[foot, 1].sum()) / b
        sim_.dt = rule.next_increment(load_curve(sim_), rec.dt)
        return False

    def finished(sim_: Simulation) -> bool:
        # Also checked before the first step of a resumed run, so resuming a
        # finished run takes no further step.  The reason names the stop in
        # the progress report ("stopped: plateau").
        reason = rule.stop_reason(load_curve(sim_))
        finished.label = (reason or "").replace("_", " ")
        return reason is not None

    ref = prandtl_nc(phi) if gamma == 0 and c > 0 and not has_profile(values) else None
    if (s_u := undrained_strength(values, phi)) is not None:  # Tresca of s_u
        c, ref = s_u, prandtl_nc(0.0)
    if values["analysis"] == "limit":
        report = progress_lines(sim.progress)
        return limit_scene_run(
            sim,
            lambda: footing_limit(values, mesh, mat, particles, foot, ref, phi, report),
        )
    sim.callbacks.append(record)

    def metrics(sim_: Simulation) -> dict[str, Any]:
        curve = load_curve(sim_)
        q = curve[-1][1] if curve else float("nan")
        factor = q / c if c > 0 else q / (gamma * b)
        plateau = rule.outcome(curve, "strip-footing", locking_note(values, phi))
        for msg in plateau["warnings"]:
            warn_user(msg)
        return {
            "q_ult": q,
            "bearing_factor": factor,
            "bearing_factor_reference": ref,
            "relative_error": None if ref is None else factor / ref - 1.0,
            "heterogeneity_factor": heterogeneity_factor(values, q),
            "load_curve": curve,
            **plateau,
            "n_particles": int(particles.n),
        }

    return with_method(
        values, SceneRun(sim, {"steps": rule.step_cap, "stop": finished}, metrics)
    )


def locking_note(values: Mapping[str, Any], phi: float) -> str:
    """Why the run's load is inflated by volumetric locking ("" if it is not).

    Constant-strain triangles (fem-remap, P1) carry about one incompressibility
    constraint per element under isochoric plastic flow (Tresca, or a dilation
    angle psi = 0), about as many as free degrees of freedom: the load keeps
    rising far above the collapse load (docs/baselines.md).  N-PFEM (nodal
    integration) and P2 elements do not lock.
    """
    if values["method"] != "fem-remap" or (values["element"] or "p1") != "p1":
        return ""
    psi = phi if values["psi"] is None else values["psi"]
    if values["material"] == "tresca":
        flow = "isochoric plastic flow (tresca)"
    elif psi == 0.0:
        flow = "isochoric plastic flow (psi = 0)"
    else:
        return ""
    return f"fem-remap with P1 elements under {flow}"


def load_curve(sim: Simulation) -> list[list[float]]:
    """``[settlement, pressure]`` of every recorded step."""
    return [
        [r.extra["settlement"], r.extra["pressure"]]
        for r in sim.records
        if "pressure" in r.extra
    ]


SCENE = Scene(
    name="strip-footing",
    description=__doc__.strip().splitlines()[0].split(": ", 1)[1],
    params=PARAMS,
    build=build,
    metrics_doc=METRICS,
    scenery=footing_scenery,
    derive=derive,
    ignored=ignored,
    time_params=None,  # a run counts its steps
)
