"""The slope scene's stages: particles, initial stresses, factor of safety, run-out.

:mod:`.scene` builds the run from them.

Stage 1 (:func:`initial_stress`) switches gravity on in one elastic static
step or sets ``K0`` stresses; stage 2 (:func:`factor_of_safety`,
:func:`fos_metrics`) is strength reduction by limit analysis on the initial
mesh; stage 3's model (:func:`flow_model`) flows with the strengths reduced
by the run-out's factor (:func:`reduced_strength_flow`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from skfem import MeshTri

from ...boundary import Contacts
from ...constants import GRAVITY
from ...errors import NpfemError
from ...limit.safety import SafetyResult, reduced_strength, strength_reduction
from ...limit.undrained import undrained_materials
from ...materials import LinearElastic, Material
from ...mesh.regions import CrossSection, check_regions, mesh_regions
from ...mesh.smoothing import nodal_integration
from ...step.conic import solve_step
from ...step.model import Model
from ...step.program import ConeInput
from ...water import Water, water_force
from ..common import fidelity_from, solver_from
from ..limit_mode import limit_metrics
from ..refinement import adapt, strategies
from ..shaking import model_kh, static_kh
from ..soil_profile import clay_law
from .body import SlopeBody, body_from, slope_body
from .runout import runout_floor, save_mechanism
from .section import (
    _surface_height,
    section_materials,
    section_of,
    section_warnings,
)
from .seismic import loaded_limits, slope_loads
from .surcharge import surcharge_load
from .water import (
    slope_water,
    static_pressure,
    surface_pressure,
    undrained_metrics,
)

__all__ = [
    "factor_of_safety",
    "flow_model",
    "fos_metrics",
    "initial_stress",
    "reduced_strength_flow",
    "spacing_check",
]

#: Change of F between the spacing and twice it above which F is reported as
#: not converged (the two-layer example changes by about 1 % there).
FOS_CHANGE_TOLERANCE = 0.05


def initial_stress(
    values: Mapping[str, Any],
    mesh: MeshTri,
    mats: list[Material],
    material: np.ndarray,
    fixed: np.ndarray,
    water: Water | None = None,
    loads: np.ndarray | None = None,
    stiffness: np.ndarray | None = None,
) -> tuple[np.ndarray, float]:
    """Stage 1: the initial (effective) stresses and their equilibrium residual.

    With water the stresses are effective ones: the gravity step is loaded
    with the saturated weight and the static pore pressure's force
    (buoyancy, and the free water's pressure on a submerged surface), and
    ``k0`` takes ``s'_v = -(rho g (z_s - z) + p_s - p)`` with ``p`` the static
    pore pressure and ``p_s`` its value at the surface above (free water),
    ``s'_h = K0 s'_v``.

    Parameters
    ----------
    values : mapping
        The scene's parameter values (``initial_stress``: gravity or k0, ``K0``).
    mesh : MeshTri
        The particles' mesh.
    mats : list of Material
        The section's materials (their ``E``, ``nu``, ``rho``, ``phi``).
    material : ndarray (n,) int
        Material index per particle.
    fixed : ndarray (n, 2) bool
        Supports.
    water : Water, optional
        The pore water (None: dry).
    loads : ndarray (n, 2), optional
        Dead loads beside the weight (a surcharge), N: in the gravity step
        (``k0`` ignores them).
    stiffness : ndarray (n,), optional
        The particles' stiffness factors in the gravity step (a profile).

    Returns
    -------
    sigma : ndarray (n, 4)
        Initial (effective) stresses, Pa.
    residual : float
        ``|G s - f| / |f|`` on the free dofs.
    """
    ni = nodal_integration(mesh, (0, 1, 3))
    x = mesh.p.T
    rho = np.array([m.rho for m in mats])[material]
    force = np.zeros_like(x)
    force[:, 1] = -rho * GRAVITY * ni.volumes
    p = static_pressure(water, x, mesh.t, material)
    if p is not None:
        force = force + water_force(ni, x, p)
    if loads is not None:
        force = force + loads
    if values["initial_stress"] == "gravity":
        elastic = [LinearElastic(m.E, m.nu, m.rho) for m in mats]
        data = ConeInput(
            operator=ni,
            materials=elastic,
            material=material,
            sigma_n=np.zeros((x.shape[0], 4)),
            force=force,
            fixed=fixed,
            du_prescribed=np.zeros_like(x),
            contacts=Contacts.empty(2),
            stiffness=stiffness,
        )
        sigma = solve_step(data, solver_from(values)).sigma
    else:
        surface = _surface_height(x, x[:, 0])
        phi = np.array([getattr(m, "phi", 0.0) for m in mats])[material]
        K0 = values["K0"]
        k0 = 1 - np.sin(np.radians(phi)) if K0 is None else np.full(len(x), K0)
        sigma = np.zeros((x.shape[0], 4))
        sigma[:, 1] = -rho * GRAVITY * (surface - x[:, 1])
        if p is not None:
            top = np.column_stack([x[:, 0], surface])
            sigma[:, 1] += p - surface_pressure(water, x, mesh.t, material, top)
        sigma[:, 0] = sigma[:, 2] = k0 * sigma[:, 1]
    free = ~fixed.reshape(-1)
    resid = ni.G @ sigma[:, [0, 1, 3]].reshape(-1) - force.reshape(-1)
    norm = float(np.linalg.norm(force.reshape(-1)[free]))
    return sigma, float(np.linalg.norm(resid[free]) / norm)


def factor_of_safety(
    values: Mapping[str, Any],
    mesh: MeshTri,
    mats: list[Material],
    material: np.ndarray,
    fixed: np.ndarray,
    water: Water | None = None,
    stress: np.ndarray | None = None,
    sec: CrossSection | None = None,
    strength: np.ndarray | None = None,
) -> tuple[SafetyResult, Any, list[Material]]:
    """Stage 2: strength reduction on the initial mesh (its limit analysis).

    With water the load is the saturated weight plus the static pore
    pressure's force (:func:`~skfem_npfem.limit.loads.gravity_load`);
    undrained, the materials are the undrained strengths of the initial
    effective stresses (:func:`~skfem_npfem.limit.undrained_materials`).

    Parameters
    ----------
    values, mesh, mats, material, fixed, water
        As in :func:`initial_stress`.
    stress : ndarray (n, 4), optional
        Initial effective stresses of an undrained analysis (default: those
        of :func:`initial_stress`).
    sec : CrossSection, optional
        The section, whose crest carries the surcharge (default: none).
    strength : ndarray (n,), optional
        The particles' strength factors (a profile; default: uniform).

    Returns
    -------
    result : SafetyResult
        Factor of safety, iterates and the last limit analysis.
    ni : NodalIntegration
        The mesh's strain operator (its cell volumes).
    mats : list of Material
        The (unreduced) materials of the analysis.
    """
    ni = nodal_integration(mesh, (0, 1, 3))
    load, shaking = slope_loads(ni, mats, material, mesh, water)
    if static_kh(values):
        load = load + static_kh(values) * shaking
    strip = None if sec is None else surcharge_load(mesh.p.T, sec, values)
    if strip is not None:
        load = load + strip
    if water is not None and water.undrained:
        if stress is None:
            stress = initial_stress(values, mesh, mats, material, fixed, water)[0]
        mats = undrained_materials(mats, material, stress)
    return (
        strength_reduction(
            ni,
            mats,
            material,
            load,
            fixed=fixed,
            options=solver_from(values),
            strength=strength,
        ),
        ni,
        mats,
    )


def fos_metrics(
    values: Mapping[str, Any],
    body: SlopeBody,
    state: dict[str, Any],
    out: Path | None,
    report: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Stage 2 once: the factor of safety's metrics, kept in ``state``.

    The first call runs the strength reduction; later calls return the same
    metrics.  With an output folder the mechanism is saved there (once): the
    scene passes it only when the run owns the folder, after every check.

    Parameters
    ----------
    values : mapping
        The scene's parameter values.
    body : SlopeBody
        The slope's particles and mesh.
    state : dict
        The run's shared state: gets ``fos``, ``fos_metrics`` and ``t_fos``.
    out : Path or None
        Output folder of ``mechanism.npz``.
    report : callable, optional
        Progress lines of the refinement cycles (``refine=strain``).

    Returns
    -------
    dict
        ``factor_of_safety``, ``fos_iterates``, the limit metrics and
        ``collapse_multiplier``.
    """
    if "fos" not in state:
        t0 = time.perf_counter()

        spent = []  # every cycle's strength reduction

        def solve(b: SlopeBody) -> tuple[Any, float, np.ndarray]:
            out = factor_of_safety(
                values,
                b.mesh,
                b.mats,
                b.material,
                b.fixed,
                slope_water(values, b.sec),
                state.get("initial_stress"),
                b.sec,
                b.strength,
            )
            spent.append(out[0])
            return out, out[0].factor_of_safety, out[0].limit.dissipation

        history, sec = None, body.sec
        if "strain" not in strategies(values):
            res, ni_, mats = solve(body)[0]
        else:
            run = adapt(
                values,
                body,
                solve,
                lambda b: (b.pts, b.tri),
                lambda p: body_from(values, sec, *mesh_regions(p, sec.regions, body.h)),
                report,
            )
            (res, ni_, mats), body, history = run.result, run.body, run.history
        state["fos_body"] = body
        state["t_fos"] = time.perf_counter() - t0
        state["fos"] = res
        state["fos_metrics"] = {
            "factor_of_safety": res.factor_of_safety,
            "fos_iterates": [list(map(float, it)) for it in res.iterates],
            **limit_metrics(
                res.limit,
                ni_.volumes,
                sum(r.programs for r in spent),
                state["t_fos"],
                iterations=sum(r.iterations for r in spent),
                statuses=[s for r in spent for s in r.statuses],
                what="the factor of safety",
            ),
            # The gravity multiplier of the slope as it is (F = 1).
            "collapse_multiplier": res.multiplier_unreduced,
            **spacing_check(values, res.factor_of_safety, state),
            **undrained_metrics(mats),
            "critical_kh": None,
            "surcharge_collapse": None,
            "refine_history": history,
        }
        # Gravity alone (no k_h, no surcharge) brings the slope down: neither
        # limit exists, and its program is infeasible (which a fine lattice's
        # solver may report as a numerical error rather than as infeasible).
        alone = not static_kh(values) and not values["surcharge"]
        falls = alone and res.multiplier_unreduced < 1.0
        if values["analysis"] == "limit" and not falls:
            t0 = time.perf_counter()
            loaded = loaded_limits(values, body, mats)
            fm = state["fos_metrics"]
            fm["warnings"] = [*fm.get("warnings", []), *loaded.pop("notes")]
            fm.update(loaded)
            state["t_critical_kh"] = time.perf_counter() - t0
        state["fos_volumes"] = ni_.volumes
    body = state["fos_body"]
    if out is not None and not state.get("mechanism_saved"):
        # Written once the run owns its folder (never while the scene is built).
        Path(out).mkdir(parents=True, exist_ok=True)
        save_mechanism(
            Path(out), body.pts, body.tri, state["fos"], state["fos_volumes"]
        )
        state["mechanism_saved"] = True
    return state["fos_metrics"]


def spacing_check(
    values: Mapping[str, Any], F: float, state: dict[str, Any]
) -> dict[str, Any]:
    """A convergence hint of the factor of safety: F again at twice the spacing.

    Twice the spacing has a quarter of the particles, so the hint costs about
    a quarter of the factor of safety.  When F changes by more than
    :data:`FOS_CHANGE_TOLERANCE` of itself, a warning says so (F is not
    converged at this spacing: refine it).  A section that cannot be filled
    at twice the spacing, or whose program fails there, gives no hint; nor
    does an adaptive run (``refine``: its ``refine_history`` is the check).

    Parameters
    ----------
    values : mapping
        The scene's parameter values (``spacing``).
    F : float
        The factor of safety at the spacing.
    state : dict
        The run's shared state: gets ``t_fos_check``.

    Returns
    -------
    dict
        ``factor_of_safety_coarse`` (F at twice the spacing, or None),
        ``fos_spacing_change`` (``(F - F_coarse) / F``, or None) and
        ``warnings``.
    """
    t0 = time.perf_counter()
    coarse = {**values, "spacing": 2 * values["spacing"], "refine": "none"}
    try:
        if "strain" in strategies(values):  # its cycles are the convergence check
            raise ValueError("refined")
        check_regions(section_of(coarse)[0].regions, coarse["spacing"])
        body = slope_body(coarse)
        res, _, _ = factor_of_safety(
            coarse,
            body.mesh,
            body.mats,
            body.material,
            body.fixed,
            slope_water(coarse, body.sec),
            sec=body.sec,
            strength=body.strength,
        )
        F2: float | None = float(res.factor_of_safety)
    except (NpfemError, ValueError):
        F2 = None
    state["t_fos_check"] = time.perf_counter() - t0
    h = values["spacing"]
    notes = (
        []
        if values["geometry"] is None
        else section_warnings(section_of(values)[0], h, values)
    )
    change = None if F2 is None or F == 0 else (F - F2) / F
    if change is not None and abs(change) > FOS_CHANGE_TOLERANCE:
        msg = (
            f"slope: the factor of safety is not converged: F = {F:.4g} at spacing "
            f"{h:.4g} m, {F2:.4g} at {2 * h:.4g} m ({100 * change:+.1f} %); refine "
            f"the spacing (spacing={h / 2:.4g}) to see where F goes"
        )
        warnings.warn(msg, stacklevel=2)
        notes.append(msg)
    return {
        "factor_of_safety_coarse": F2,
        "fos_spacing_change": change,
        "warnings": notes,
    }


def flow_model(
    values: Mapping[str, Any],
    body: SlopeBody,
    state: dict[str, Any],
    run_out: bool,
    report: Callable[[str], None] | None = None,
) -> Model:
    """The dynamic model of stage 3, with the run-out's reduced strengths.

    With ``run_out`` the factor of safety comes first (:func:`fos_metrics`,
    ``report`` getting its refinement cycles' progress lines): the strengths
    are divided by ``reduction`` (default ``margin`` times the factor of
    safety, or 1 when it is below 1: such a slope fails as it is), which goes
    into ``state["reduction"]``.

    Parameters
    ----------
    values : mapping
        The scene's parameter values.
    body : SlopeBody
        The slope's section and particles.
    state : dict
        The run's shared state.
    run_out : bool
        Whether stage 3 runs.
    report : callable, optional
        Gets one progress line per refinement cycle of the factor of safety.

    Returns
    -------
    Model
    """
    flow_mats = section_materials(body.sec, values, flow=True)
    if run_out:
        # Stage 3 needs the factor of safety first: reduce, then flow to rest.
        F = fos_metrics(values, body, state, None, report)["factor_of_safety"]
        # A slope that fails as it is (F < 1) runs out with its own strength.
        red = values["reduction"] or (values["margin"] * F if F >= 1 else 1.0)
        state["reduction"] = red
        flow_mats = [reduced_strength_flow(m, red) for m in flow_mats]
    return Model(
        dim=2,
        materials=flow_mats,
        water=slope_water(values, body.sec),
        gravity=GRAVITY,
        mode="dynamic",
        kh=model_kh(values),
        walls=runout_floor(values, run_out),
        loads=surcharge_load(body.pts, body.sec, values),
        solver=solver_from(values),
        strength_law=clay_law(values),
        **fidelity_from(values, 0.0),
    )


def reduced_strength_flow(material: Material, factor: float) -> Material:
    """``c/F``, ``tan(phi)/F`` keeping the material's (non-associated) ``psi``."""
    out = reduced_strength(material, factor)
    out.psi = min(material.psi, out.phi)
    out.tension_cutoff = getattr(material, "tension_cutoff", False)
    return out
