"""Scene ``slope``: a slope's factor of safety, its mechanism, and the run-out.

Plane strain.  The parametric section is a slope of ``height`` H and ``angle``
(degrees from horizontal, 90: a vertical cut) facing +x, with a crest
``crest_length`` long and a toe plain ``toe_length`` long on a foundation layer
``foundation_depth`` deep; or, with ``geometry=FILE``, the regions and
materials of a cross-section file (JSON, format in
:mod:`skfem_npfem.mesh.regions`, an example in
``docs/examples/two_layer_slope.json``).  Particles fill the section at
``spacing``.  The base is fixed and the sides are on rollers.

Stages, in one run:

1. **initial stresses** -- ``initial_stress=gravity``: gravity switched on in
   one elastic static step (equilibrium by construction; its residual is
   reported), or ``k0``: ``s_v = -rho g * depth`` below the surface,
   ``s_h = K0 s_v`` (not in equilibrium under a slope: the residual says how
   far);
2. **factor of safety** by strength reduction (``c/F``, ``tan(phi)/F``) with
   the collapse mechanism (with an output folder: ``mechanism.npz`` and
   ``mechanism.png``), from limit analysis on the particles' mesh
   (:func:`~skfem_npfem.step.limit.strength_reduction`;
   ``analysis=limit`` runs this stage only);
3. **failure and run-out**, with ``runout=true``: the strengths divided by
   ``reduction`` (default: ``margin`` times the factor of safety, or 1 when
   the factor of safety is below 1: such a slope fails as it is) and the
   PFEM loop run until the slide is at rest (kinetic energy below
   ``rest_fraction`` of its peak) or ``t_end``.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np
from skfem import MeshTri

from ..boundary import Contacts
from ..constants import GRAVITY
from ..materials import LinearElastic, Material, MohrCoulomb, Tresca
from ..mesh.regions import (
    CrossSection,
    Region,
    check_regions,
    fill_regions,
    read_cross_section,
)
from ..mesh.smoothing import nodal_integration
from ..mesh.sources import AlphaShapeMesher, FixedMesh
from ..particles import Particles
from ..run.simulation import AtRest, Simulation
from ..step.conic import solve_step
from ..step.limit import reduced_strength, strength_reduction
from ..step.model import Model
from ..step.program import ConeInput
from .base import Param, Scene, SceneRun
from .common import (
    check_size,
    elastic_params,
    fidelity_from,
    fidelity_params,
    make_writer,
    solver_from,
    solver_params,
)
from .limit_mode import LIMIT_METRICS, analysis_param, limit_metrics
from .scenery import Scenery, number

MATERIALS = ("mohr-coulomb", "tresca")
_POSITIVE = {"lo": 0, "lo_open": True}

PARAMS = [
    Param("height", 10.0, "m", "slope height H", float, **_POSITIVE),
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
    Param("foundation_depth", 5.0, "m", "foundation layer below the toe", float, lo=0),
    Param("crest_length", None, "m", "crest plateau (default 1.5 H)", float, lo=0),
    Param("toe_length", None, "m", "toe plain (default 2.5 H)", float, lo=0),
    Param(
        "geometry",
        None,
        "-",
        "cross-section file (JSON regions and materials) instead of the "
        "parametric slope",
        str,
    ),
    Param("spacing", None, "m", "particle spacing (default H/10)", float, **_POSITIVE),
    Param("material", "mohr-coulomb", "-", "yield criterion", str, MATERIALS),
    *elastic_params(2.0e7),
    Param("c", 1.0e4, "Pa", "cohesion", float, lo=0),
    Param(
        "phi",
        20.0,
        "deg",
        "friction angle (tresca: 0)",
        float,
        lo=0,
        hi=90,
        hi_open=True,
    ),
    Param(
        "psi",
        0.0,
        "deg",
        "dilation angle of the run-out (limit analysis is associated)",
        float,
        lo=0,
        hi=90,
        hi_open=True,
    ),
    Param("rho", 2000.0, "kg/m^3", "density", float, **_POSITIVE),
    Param(
        "initial_stress",
        "gravity",
        "-",
        "gravity (elastic step) or k0",
        str,
        ("gravity", "k0"),
    ),
    Param(
        "K0", None, "-", "at-rest coefficient (default 1 - sin phi)", float, **_POSITIVE
    ),
    analysis_param("initial stresses, factor of safety, and run-out if asked"),
    Param("runout", False, "-", "run the failure and run-out stage", bool),
    Param(
        "reduction",
        None,
        "-",
        "strength reduction factor of the run-out (default margin x factor of safety)",
        float,
        **_POSITIVE,
    ),
    Param("margin", 1.5, "-", "reduction / factor of safety by default", float, lo=1.0),
    Param(
        "dt",
        None,
        "s",
        "initial time step (default 0.02 sqrt(H/g))",
        float,
        **_POSITIVE,
    ),
    Param(
        "t_end", None, "s", "end time cap (default 15 sqrt(H/g))", float, **_POSITIVE
    ),
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
        **_POSITIVE,
    ),
    *fidelity_params(0.0),
    *solver_params(),
]

METRICS = {
    "factor_of_safety": "strength reduction factor at which the slope just "
    "carries its weight (limit analysis)",
    "fos_iterates": "list of [F, gravity multiplier] of every cone program",
    "initial_equilibrium_residual": "|G s - f| / |f| on the free dofs of the "
    "initial stresses (null with analysis=limit)",
    "reduction": "strength reduction factor of the run-out (null without it)",
    "runout": "advance of the toe: farthest x of slope material above the "
    "foundation surface, minus the initial toe x, m (null without run-out)",
    "crest_settlement": "drop of the surface at the initial crest edge, m",
    "mass_centre_travel": "distance travelled by the mass centre of the moved "
    "particles (displacement > spacing/2), m",
    "moved_volume": "initial volume of the moved particles, m^2 per m",
    "deposit_profile": "list of [x, surface y] of the final section, one per spacing",
    "deposit_max_slope": "steepest surface slope of the deposit over 3 spacings, deg",
    "mass_change": "relative change of the total mass over the run-out",
    "volume_change": "relative change of the meshed volume over the run-out",
    "at_rest": "the run-out ended by the at-rest rule (not t_end)",
    "deposit_factor_of_safety": "factor of safety of the final deposit with the "
    "run-out's strengths (a second limit analysis; >= 1: statically admissible)",
    "n_particles": "number of particles",
    "stage_wall_time": "seconds per stage: initial_stress, factor_of_safety (all "
    "its cone programs), runout (the steps)",
    **LIMIT_METRICS,
    "collapse_multiplier": "gravity multiplier of the unreduced strengths (the "
    "first program; capped at 1e3: a cohesionless slope that stands carries "
    "any multiple of its weight)",
}


# -- geometry -------------------------------------------------------------------
def parametric_section(values: dict[str, Any]) -> CrossSection:
    """The slope of the parameters as a one-region cross-section."""
    H, D = values["height"], values["foundation_depth"]
    crest = values["crest_length"]
    toe = values["toe_length"]
    crest = 1.5 * H if crest is None else crest
    toe = 2.5 * H if toe is None else toe
    run = 0.0 if values["angle"] >= 90 else H / math.tan(math.radians(values["angle"]))
    x_crest, x_toe = crest, crest + run
    W = x_toe + toe
    pts = [(0, 0), (W, 0)]
    if D > 0:
        pts.append((W, D))
    pts += [(x_toe, D), (x_crest, D + H), (0, D + H)]
    poly = np.array(pts, dtype=float)
    props = {
        "c": values["c"],
        "phi": 0.0 if values["material"] == "tresca" else values["phi"],
        "rho": values["rho"],
    }
    return CrossSection([Region("soil", _dedupe(poly))], {"soil": props})


def _dedupe(poly: np.ndarray) -> np.ndarray:
    """Drop repeated consecutive vertices (a zero-length crest or toe)."""
    keep = np.linalg.norm(poly - np.roll(poly, 1, axis=0), axis=1) > 1e-12
    return poly[keep]


def section_of(values: dict[str, Any]) -> tuple[CrossSection, float]:
    """The cross-section (file or parametric) and the spacing."""
    if values["geometry"]:
        sec = read_cross_section(values["geometry"])
        heights = [float(np.ptp(r.polygon[:, 1])) for r in sec.regions]
        default_h = max(heights) / 20
    else:
        sec = parametric_section(values)
        default_h = values["height"] / 10
    h = values["spacing"] if values["spacing"] is not None else default_h
    values["spacing"] = h
    area = sum(abs(_area(r.polygon)) for r in sec.regions)
    check_size(area / h**2, 2, values, advice="use a larger spacing")
    check_regions(sec.regions, h)
    return sec, h


def _area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def section_materials(
    sec: CrossSection, values: dict[str, Any], flow: bool = False
) -> list[Material]:
    """One material per name of the section (scene values as defaults)."""
    mats = []
    for props in sec.materials.values():
        c = props.get("c", values["c"])
        phi = props.get("phi", values["phi"])
        rho = props.get("rho", values["rho"])
        E, nu = props.get("E", values["E"]), props.get("nu", values["nu"])
        psi = min(props.get("psi", values["psi"]), phi) if flow else phi
        if values["material"] == "tresca" and not values["geometry"]:
            mats.append(Tresca(E, nu, rho, c=c))
        else:
            mats.append(
                MohrCoulomb(E, nu, rho, c=c, phi=phi, psi=psi, tension_cutoff=flow)
            )
    return mats


def supports(x: np.ndarray, sec: CrossSection) -> np.ndarray:
    """Fixed dofs: the base (lowest y) and the sides (smallest/largest x)."""
    lo, hi = x.min(axis=0), x.max(axis=0)
    tol = 1e-9 * max(float(np.ptp(x)), 1.0)
    fixed = np.zeros_like(x, dtype=bool)
    base = np.abs(x[:, 1] - lo[1]) < tol
    fixed[base, 1] = True
    if sec.supports["base"] == "fixed":
        fixed[base, 0] = True
    if sec.supports["sides"] == "rollers":
        fixed[(np.abs(x[:, 0] - lo[0]) < tol) | (np.abs(x[:, 0] - hi[0]) < tol), 0] = (
            True
        )
    return fixed


# -- stages ---------------------------------------------------------------------
def initial_stress(
    values: dict[str, Any],
    mesh: MeshTri,
    mats: list[Material],
    material: np.ndarray,
    fixed: np.ndarray,
) -> tuple[np.ndarray, float]:
    """Stage 1: the initial stresses (full Voigt) and their equilibrium residual."""
    ni = nodal_integration(mesh, (0, 1, 3))
    x = mesh.p.T
    rho = np.array([m.rho for m in mats])[material]
    force = np.zeros_like(x)
    force[:, 1] = -rho * GRAVITY * ni.volumes
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
            contacts=Contacts(
                np.zeros(0, int), np.zeros((0, 2)), np.zeros(0), np.zeros(0)
            ),
        )
        sigma = solve_step(data, solver_from(values)).sigma
    else:
        surface = _surface_height(x, x[:, 0])
        phi = np.array([getattr(m, "phi", 0.0) for m in mats])[material]
        K0 = values["K0"]
        k0 = 1 - np.sin(np.radians(phi)) if K0 is None else np.full(len(x), K0)
        sigma = np.zeros((x.shape[0], 4))
        sigma[:, 1] = -rho * GRAVITY * (surface - x[:, 1])
        sigma[:, 0] = sigma[:, 2] = k0 * sigma[:, 1]
    free = ~fixed.reshape(-1)
    resid = ni.G @ sigma[:, [0, 1, 3]].reshape(-1) - force.reshape(-1)
    norm = float(np.linalg.norm(force.reshape(-1)[free]))
    return sigma, float(np.linalg.norm(resid[free]) / norm)


def _surface_height(x: np.ndarray, at: np.ndarray, width: float = 0.0) -> np.ndarray:
    """Highest particle y near each of ``at`` (NaN where there is none).

    The particles are binned in columns ``width`` wide (default: half the
    median gap between distinct x); a query takes the highest particle of its
    column and the two neighbouring ones (within ``width`` to ``2 width``).
    """
    if width <= 0:
        gaps = np.diff(np.unique(np.round(x[:, 0], 9)))
        width = 0.5 * float(np.median(gaps)) if gaps.size else 1.0
    x0 = min(float(x[:, 0].min()), float(np.min(at))) - 2 * width
    b = np.floor((x[:, 0] - x0) / width).astype(int)
    qb = np.floor((np.asarray(at) - x0) / width).astype(int)
    top = np.full(max(int(b.max()), int(qb.max())) + 2, -np.inf)
    np.maximum.at(top, b, x[:, 1])
    out = np.maximum(np.maximum(top[qb - 1], top[qb]), top[qb + 1])
    return np.where(np.isfinite(out), out, np.nan)


def factor_of_safety(values, mesh, mats, material, fixed):
    """Stage 2: strength reduction on the initial mesh (its limit analysis)."""
    ni = nodal_integration(mesh, (0, 1, 3))
    rho = np.array([m.rho for m in mats])[material]
    load = np.zeros((mesh.p.shape[1], 2))
    load[:, 1] = -rho * GRAVITY * ni.volumes
    return strength_reduction(
        ni, mats, material, load, fixed=fixed, options=solver_from(values)
    ), ni


# -- build ----------------------------------------------------------------------
def build(
    values: dict[str, Any], out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build the slope's staged run (or its limit analysis only)."""
    sec, h = section_of(values)
    pts, tri, region = fill_regions(sec.regions, h)
    names = list(sec.materials)
    material = np.array([names.index(sec.regions[r].material) for r in region])
    mesh = MeshTri(np.ascontiguousarray(pts.T), np.ascontiguousarray(tri))
    fixed = supports(pts, sec)
    mats = section_materials(sec, values)
    H = float(np.ptp(pts[:, 1]))
    if values["dt"] is None:
        values["dt"] = 0.02 * math.sqrt(H / GRAVITY)
    if values["t_end"] is None:
        values["t_end"] = 15 * math.sqrt(H / GRAVITY)
    limit_only = values["analysis"] == "limit"
    state: dict[str, Any] = {}
    if limit_only:
        sigma, resid = np.zeros((len(pts), 4)), None
    else:
        t0 = time.perf_counter()
        sigma, resid = initial_stress(values, mesh, mats, material, fixed)
        state["t_initial"] = time.perf_counter() - t0
    ni = nodal_integration(mesh, (0, 1, 3))
    masses = np.array([m.rho for m in mats])[material] * ni.volumes

    def fos() -> dict[str, Any]:
        if "fos" not in state:
            t0 = time.perf_counter()
            res, ni_ = factor_of_safety(values, mesh, mats, material, fixed)
            state["t_fos"] = time.perf_counter() - t0
            state["fos"] = res
            state["fos_metrics"] = {
                "factor_of_safety": res.factor_of_safety,
                "fos_iterates": [list(map(float, it)) for it in res.iterates],
                **limit_metrics(res.limit, ni_.volumes, res.programs, state["t_fos"]),
                # The gravity multiplier of the slope as it is (F = 1).
                "collapse_multiplier": res.multiplier_unreduced,
            }
            if out is not None:
                save_mechanism(Path(out), pts, tri, res, ni_.volumes)
        return state["fos_metrics"]

    run_out = values["runout"] and not limit_only
    flow_mats = section_materials(sec, values, flow=True)
    particles = Particles.create(
        pts, masses, stress=sigma, fixed=fixed, material=material
    )
    if run_out:
        # Stage 3 needs the factor of safety first: reduce, then flow to rest.
        fos()
        F = fos()["factor_of_safety"]
        # A slope that fails as it is (F < 1) runs out with its own strength.
        red = values["reduction"] or (values["margin"] * F if F >= 1 else 1.0)
        state["reduction"] = red
        flow_mats = [reduced_strength_flow(m, red) for m in flow_mats]
    model = Model(
        dim=2,
        materials=flow_mats,
        gravity=GRAVITY,
        mode="dynamic",
        solver=solver_from(values),
        **fidelity_from(values, 0.0),
    )
    source = AlphaShapeMesher(h, values["alpha"]) if run_out else FixedMesh(mesh.t)
    sim = Simulation(
        particles,
        model,
        source,
        values["dt"],
        adaptive=True,
        max_displacement=values["max_displacement"],
        writer=make_writer(out, resume),
        progress=progress,
        meta={"scene": "slope", "parameters": values},
    )
    x_toe, y_toe, x_crest, y_crest = _toe_and_crest(sec, values)

    def metrics(sim_: Simulation) -> dict[str, Any]:
        m = {
            **fos(),
            "initial_equilibrium_residual": resid,
            "reduction": None,
            "runout": None,
            "crest_settlement": None,
            "mass_centre_travel": None,
            "moved_volume": None,
            "deposit_profile": None,
            "deposit_max_slope": None,
            "mass_change": None,
            "volume_change": None,
            "at_rest": None,
            "deposit_factor_of_safety": None,
            "n_particles": len(pts),
            "stage_wall_time": {
                "initial_stress": state.get("t_initial", 0.0),
                "factor_of_safety": state.get("t_fos", 0.0),
                "runout": float(sum(sum(r.timings.values()) for r in sim_.records)),
            },
        }
        if run_out:
            m.update(
                runout_metrics(sim_, state, values, h, x_toe, y_toe, x_crest, y_crest)
            )
        return m

    if not run_out:
        return SceneRun(sim, {"steps": 0}, metrics)
    stop = AtRest(values["rest_fraction"], 2 * math.sqrt(H / GRAVITY))
    state["stop"] = stop
    return SceneRun(sim, {"t_end": values["t_end"], "stop": stop}, metrics)


def save_mechanism(folder: Path, pts, tri, res, volumes) -> None:
    """``mechanism.npz`` and, with matplotlib, ``mechanism.png`` in ``folder``."""
    lim = res.limit
    np.savez(
        folder / "mechanism.npz",
        x=pts,
        triangles=tri,
        velocity=lim.velocity,
        dissipation=lim.dissipation,
        plastic=lim.plastic,
    )
    try:
        from ..viz.figures import mechanism_figure
    except ImportError:  # pragma: no cover - the viz extra is not installed
        return
    title = f"collapse mechanism at F = {res.factor_of_safety:.3f}"
    fig = mechanism_figure(pts, tri, lim.velocity, lim.dissipation, volumes, title)
    fig.savefig(folder / "mechanism.png")


def reduced_strength_flow(material: Material, factor: float) -> Material:
    """``c/F``, ``tan(phi)/F`` keeping the material's (non-associated) ``psi``."""
    out = reduced_strength(material, factor)
    out.psi = min(material.psi, out.phi)
    out.tension_cutoff = getattr(material, "tension_cutoff", False)
    return out


def _toe_and_crest(sec: CrossSection, values: dict[str, Any]):
    """Toe and crest points of the section (parametric: exact; file: estimated)."""
    if not values["geometry"]:
        H, D = values["height"], values["foundation_depth"]
        crest = 1.5 * H if values["crest_length"] is None else values["crest_length"]
        run = (
            0.0
            if values["angle"] >= 90
            else H / math.tan(math.radians(values["angle"]))
        )
        return crest + run, D, crest, D + H
    allp = np.concatenate([r.polygon for r in sec.regions])
    top = allp[:, 1].max()
    crest_pts = allp[np.isclose(allp[:, 1], top)]
    x_crest = float(crest_pts[:, 0].max())
    right = allp[allp[:, 0] > x_crest + 1e-9]
    if right.size == 0:
        return x_crest, top, x_crest, top
    y_toe = float(right[:, 1].max()) if right.size else top
    low = right[np.isclose(right[:, 1], right[:, 1].max())]
    return float(low[:, 0].min()), y_toe, x_crest, float(top)


def runout_metrics(sim, state, values, h, x_toe, y_toe, x_crest, y_crest) -> dict:
    """The run-out stage's metrics from the particles at the end of the run."""
    p = sim.particles
    x0 = p.x - p.u
    moved = np.linalg.norm(p.u, axis=1) > 0.5 * h
    above = x0[:, 1] > y_toe + 0.25 * h
    final = p.x
    runout = float(final[above, 0].max() - x_toe) if above.any() else 0.0
    crest_now = _surface_height(final, np.array([x_crest]), h)[0]
    travel = 0.0
    vol = 0.0
    if moved.any():
        w = p.mass[moved]
        travel = float(np.linalg.norm((w[:, None] * p.u[moved]).sum(0) / w.sum()))
        rho = np.array([m.rho for m in sim.model.materials])[p.material[moved]]
        vol = float(np.sum(w / rho))
    xs = np.arange(final[:, 0].min(), final[:, 0].max() + 1e-9, h)
    ys = _surface_height(final, xs, 0.75 * h)
    slope = deposit_slopes(xs, ys, final[moved, 0], h)
    summ = sim.summary()
    stop = state.get("stop")
    deposit_fos = deposit_factor_of_safety(sim, values)
    return {
        "reduction": state.get("reduction"),
        "runout": max(runout, 0.0),
        "crest_settlement": float(y_crest - crest_now),
        "mass_centre_travel": travel,
        "moved_volume": vol,
        "deposit_profile": [[float(a), float(b)] for a, b in zip(xs, ys, strict=True)],
        "deposit_max_slope": float(np.max(slope, initial=0.0)),
        "mass_change": summ["mass_change"],
        "volume_change": summ["volume_change"],
        "at_rest": bool(stop is not None and stop(sim)),
        "deposit_factor_of_safety": deposit_fos,
    }


def deposit_slopes(
    xs: np.ndarray, ys: np.ndarray, moved_x: np.ndarray, h: float, window: int = 5
) -> np.ndarray:
    """Surface slopes (deg) of least-squares lines over ``window`` columns.

    Only windows over moved material count (the deposit, not the ground it
    came to rest on), and not the windows over the front: the front of a
    deposit ends in a step a few particles high at any spacing, a particle
    size rather than a slope.  A line through ``window`` columns averages out
    the one-particle steps of the highest-particle profile.
    """
    ok = np.isfinite(ys)
    xs, ys = xs[ok], ys[ok]
    if xs.size < window or moved_x.size == 0:
        return np.zeros(0)
    idx = np.arange(xs.size - window + 1)[:, None] + np.arange(window)
    X, Y = xs[idx], ys[idx]
    Xc = X - X.mean(axis=1, keepdims=True)
    b = np.sum(Xc * (Y - Y.mean(axis=1, keepdims=True)), axis=1) / np.sum(Xc**2, axis=1)
    lo, hi = X[:, 0] - 0.5 * h, X[:, -1] + 0.5 * h
    mx = np.sort(moved_x)
    has = (np.searchsorted(mx, hi) - np.searchsorted(mx, lo)) > 0
    has &= hi < mx[-1]  # not over the front (a few particles thick)
    return np.degrees(np.arctan(np.abs(b[has])))


def deposit_factor_of_safety(sim: Simulation, values: dict[str, Any]) -> float:
    """Factor of safety of the final deposit with the run-out's strengths.

    A second limit analysis, on the alpha-shape mesh of the particles at the
    end of the run (supports as at the start); at least 1 when the deposit is
    statically admissible.
    """
    p = sim.particles
    active, t = sim.mesh_source(p.x)
    mesh = MeshTri(np.ascontiguousarray(p.x[active].T), np.ascontiguousarray(t))
    ni = nodal_integration(mesh, (0, 1, 3))
    material = np.asarray(p.material)[active]
    rho = np.array([m.rho for m in sim.model.materials])[material]
    load = np.zeros((active.size, 2))
    load[:, 1] = -rho * GRAVITY * ni.volumes
    fixed = np.asarray(p.fixed, bool)[active]
    res = strength_reduction(
        ni,
        sim.model.materials,
        material,
        load,
        fixed=fixed,
        options=solver_from(values),
    )
    return float(res.factor_of_safety)


def slope_scenery(p: dict, folder: Path | None = None) -> Scenery:
    """The slope's scenery: the fixed base."""
    s = Scenery(scene="slope")
    if number(p, "height") is None:
        return s
    s.floor, s.floor_label = 0.0, "fixed base"
    return s


SCENE = Scene(
    name="slope",
    description=__doc__.strip().splitlines()[0].split(": ", 1)[1],
    params=PARAMS,
    build=build,
    metrics_doc=METRICS,
    scenery=slope_scenery,
)
