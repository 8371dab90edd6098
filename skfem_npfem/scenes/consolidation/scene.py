"""Scene ``consolidation``: Terzaghi's column or Mandel's specimen, coupled steps.

``case=terzaghi``: a weightless column of height H between smooth
impermeable walls on a fixed impermeable base, its drained top loaded
suddenly by ``load`` = q0; the degree of consolidation U (settlement over
``q0 H / M``) against Terzaghi's series at ``T_v = c_v t / H^2``,
``c_v = k M / gamma_w``.  ``case=mandel``: the quarter of Mandel's
plane-strain specimen (half-width a, half-height b), symmetry faces
impermeable, a rigid smooth plate on top carrying ``load * a`` (its nodes'
vertical displacements tied, :attr:`~skfem_npfem.Model.tied`), the lateral
face drained and traction free; the centre's pore pressure over its initial
``p0 = load / 2`` against the exact series (Mandel–Cryer effect).

Time stepping: the first step is ``dT`` (a time factor), each next step
``dt_growth`` times the last, at most ``dT_max``, shortened to land on the
report times (0.01, 0.05, 0.1, 0.2, 0.5, 1, 2, ...) and on ``T_end``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial import Delaunay
from skfem import MeshTri

from ...constants import GRAVITY
from ...errors import ParameterError
from ...loads import surface_load
from ...materials import LinearElastic
from ...mesh.sources import AlphaShapeMesher, FixedMesh
from ...particles import Particles
from ...run.simulation import Simulation
from ...step.model import Model
from ...water import Water
from ..base import Scene, SceneRun
from ..common import elastic_params, make_writer, solver_from, solver_params
from ..limits import SPACING, check_size
from ..params import POSITIVE, Param, Values
from ..scenery import Scenery, box, number
from .exact import mandel_pressure, terzaghi_degree

CASES = ("terzaghi", "mandel")

#: Time factors a run lands on (those up to ``T_end``), besides ``T_end``.
REPORT_TIMES = (0.01, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0)

#: Density of the weightless soil, kg/m^3 (the load alone consolidates it).
WEIGHTLESS = 1e-9

PARAMS = [
    Param(
        "case", "terzaghi", "-", "terzaghi (column) or mandel (specimen)", str, CASES
    ),
    *elastic_params(1.0e7),
    Param(
        "k", 1.0e-3, "m/s", "hydraulic conductivity (permeability)", float, **POSITIVE
    ),
    Param("rho_w", 1000.0, "kg/m^3", "density of the pore water", float, **POSITIVE),
    Param(
        "load",
        1.0e4,
        "Pa",
        "q0 on the column's top (terzaghi) or the plate's mean pressure sigma0 "
        "(mandel), applied at once",
        float,
        **POSITIVE,
    ),
    Param(
        "height",
        None,
        "m",
        "column height H (terzaghi, default 1) or half-height b (mandel, default 0.5)",
        float,
        **POSITIVE,
    ),
    Param(
        "width",
        None,
        "m",
        "column width (terzaghi, default 0.2) or half-width a (mandel, default 1)",
        float,
        **POSITIVE,
    ),
    Param("spacing", 0.05, "m", "node (particle) spacing", float, **SPACING),
    Param(
        "mesh",
        "lattice",
        "-",
        "lattice (right triangles) or delaunay (interior nodes moved by up to "
        "0.3 spacing, seeded, and re-triangulated)",
        str,
        ("lattice", "delaunay"),
    ),
    Param("seed", 1, "-", "seed of the delaunay mesh's perturbation", int, lo=0),
    Param(
        "dT",
        1.0e-3,
        "-",
        "first time step as a time factor (c_v dt / H^2 or c dt / a^2)",
        float,
        lo=1e-9,
        hi=10.0,
    ),
    Param(
        "dt_growth",
        1.2,
        "-",
        "ratio of a step to the one before",
        float,
        lo=1.0,
        hi=10.0,
    ),
    Param(
        "dT_max",
        0.02,
        "-",
        "longest time step as a time factor",
        float,
        lo=1e-9,
        hi=10.0,
    ),
    Param("T_end", 1.0, "-", "end of the run as a time factor", float, lo=1e-9, hi=1e3),
    Param(
        "projection",
        1.0,
        "-",
        "pressure-projection factor tau of the excess pore pressure (0: none)",
        float,
        lo=0.0,
        hi=1e3,
    ),
    Param(
        "large_deformation",
        False,
        "-",
        "false: one fixed mesh, small strains; true: remesh every step (alpha "
        "shape) on the moved particles, which carry their pore pressure",
        bool,
    ),
    Param(
        "alpha",
        1.3,
        "-",
        "alpha-shape factor (large_deformation)",
        float,
        lo=1.0,
        hi=10.0,
    ),
    *solver_params(),
]

METRICS = {
    "degree_of_consolidation": "terzaghi: [T_v, U] after every step "
    "(U = settlement / (q0 H / M))",
    "degree_of_consolidation_error": "terzaghi: max |U - U_exact| over the steps",
    "first_step_pressure": "terzaghi: [min, max] of the excess pore pressure / q0 "
    "off the drained top after the first step",
    "centre_pressure": "mandel: [c t / a^2, p / p0] at the centre after every step",
    "centre_pressure_error": "mandel: max |p - p_exact| / p0 at the centre "
    "over the steps",
    "peak_pressure": "mandel: [c t / a^2, p / p0] of the largest centre pressure",
    "peak_pressure_exact": "mandel: [c t / a^2, p / p0] of the exact series' peak",
    "consolidation_coefficient": "c_v = k M / gamma_w (terzaghi) or c (mandel), m^2/s",
    "diffusion_number": "[min, max] of c_v dt / h^2 over the steps",
    "n_particles": "number of particles",
}


def derive(values: dict[str, Any]) -> None:
    """Fill the geometry: H = 1, width 0.2 (terzaghi); a = 1, b = 0.5 (mandel)."""
    terzaghi = values["case"] == "terzaghi"
    if values["height"] is None:
        values["height"] = 1.0 if terzaghi else 0.5
    if values["width"] is None:
        values["width"] = 0.2 if terzaghi else 1.0


def consolidation_mesh(values: Values) -> MeshTri:
    """The lattice or the perturbed Delaunay mesh of the column or the specimen."""
    W, H, h = values["width"], values["height"], values["spacing"]
    nx, ny = max(1, round(W / h)), max(1, round(H / h))
    mesh = MeshTri.init_tensor(np.linspace(0, W, nx + 1), np.linspace(0, H, ny + 1))
    if values["mesh"] == "lattice":
        return mesh
    x = mesh.p.T.copy()
    tol = 1e-9 * max(W, H)
    inner = (
        (x[:, 0] > tol) & (x[:, 0] < W - tol) & (x[:, 1] > tol) & (x[:, 1] < H - tol)
    )
    rng = np.random.default_rng(values["seed"])
    x[inner] += rng.uniform(-0.3, 0.3, (int(inner.sum()), 2)) * np.array(
        [W / nx, H / ny]
    )
    return MeshTri(x.T, Delaunay(x).simplices.T)


def check_values(values: Values) -> None:
    """Refuse a mesh with fewer than two elements across or four along."""
    W, H, h = values["width"], values["height"], values["spacing"]
    if round(H / h) < 4 or round(W / h) < 2:
        raise ParameterError(
            "spacing",
            h,
            f"at most height/4 = {H / 4:g} m and width/2 = {W / 2:g} m",
        )
    check_size((round(W / h) + 1) * (round(H / h) + 1), 2, values)
    if values["dT_max"] < values["dT"]:
        raise ParameterError("dT_max", values["dT_max"], f">= dT = {values['dT']:g}")


def consolidation_coefficient(values: Values) -> float:
    """``c_v = k M / gamma_w``; Mandel's ``c`` is the same for B = 1, nu_u = 1/2."""
    soil = LinearElastic(values["E"], values["nu"], WEIGHTLESS)
    return values["k"] * soil.p_wave_modulus / (values["rho_w"] * GRAVITY)


def build(
    values: Values, out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build the consolidation simulation (see the module notes)."""
    check_values(values)
    mesh = consolidation_mesh(values)
    W, H = values["width"], values["height"]
    x = mesh.p.T.copy()
    tol = 1e-9 * max(W, H)
    left, right = x[:, 0] < tol, x[:, 0] > W - tol
    base, top = x[:, 1] < tol, x[:, 1] > H - tol
    mandel = values["case"] == "mandel"
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = base
    fixed[:, 0] = left if mandel else left | right | base
    soil = LinearElastic(values["E"], values["nu"], WEIGHTLESS)
    water = Water(
        "coupled",
        None,
        rho_w=values["rho_w"],
        projection=values["projection"],
        permeability=values["k"],
    )
    loads = surface_load(x, top, values["load"])
    large = values["large_deformation"]
    model = Model(
        dim=2,
        materials=[soil],
        mode="static",
        gravity=GRAVITY,
        loads=loads,
        water=water,
        update_geometry=large,
        solver=solver_from(values),
        tied=[(np.flatnonzero(top), 1)] if mandel else None,
    )
    particles = Particles.from_mesh(mesh, soil, fixed=fixed)
    source = (
        AlphaShapeMesher(values["spacing"], values["alpha"])
        if large
        else FixedMesh(mesh.t)
    )
    length = W if mandel else H
    seconds = length**2 / consolidation_coefficient(values)  # one time factor
    sim = Simulation(
        particles,
        model,
        source,
        values["dT"] * seconds,
        writer=make_writer(out, resume),
        progress=progress,
        meta={"scene": "consolidation", "parameters": dict(values)},
    )
    sim.dt_max = values["dT_max"] * seconds
    centre = int(np.argmin(np.hypot(x[:, 0], x[:, 1])))
    sim.callbacks.append(_stepping(values, seconds, loads, top, centre))
    t_end = values["T_end"] * seconds

    def metrics(sim_: Simulation) -> dict[str, Any]:
        return scene_metrics(sim_, values, seconds)

    return SceneRun(sim, {"t_end": t_end}, metrics)


def _stepping(values: Values, seconds: float, loads, top, centre):
    """The callback that records U or p_c and sets the next (growing) step."""
    marks = [
        T * seconds for T in (*REPORT_TIMES, values["T_end"]) if T <= values["T_end"]
    ]
    mandel = values["case"] == "mandel"

    def callback(sim: Simulation, p: Particles, step) -> bool:
        extra = step.record.extra
        if mandel:
            extra["centre_pressure"] = float(p.excess_pore_pressure[centre])
        else:
            fy = loads[:, 1]
            extra["settlement"] = float(-np.sum(fy * p.u[:, 1]) / np.sum(fy))
            if sim.step == 1:
                below = ~top
                extra["first_step_pressure"] = [
                    float(p.excess_pore_pressure[below].min()),
                    float(p.excess_pore_pressure[below].max()),
                ]
        sim.dt = growing_step(
            step.record.dt, values["dt_growth"], sim.dt_max, sim.time, marks, seconds
        )
        return False

    return callback


def growing_step(
    last: float,
    growth: float,
    longest: float,
    now: float,
    marks: list[float],
    unit: float,
) -> float:
    """The next time step: ``growth`` times the ``last``, at most ``longest``.

    Shortened to land on the next of the ``marks`` (times, s) after ``now``,
    or to half the way there when a full step would leave a sliver under
    half a step before it; ``unit`` (s) scales the tolerance.

    Examples
    --------
    >>> growing_step(1.0, 2.0, 10.0, 0.0, [5.0], 1.0)
    2.0
    >>> growing_step(1.0, 2.0, 10.0, 0.0, [2.5], 1.0)
    1.25
    """
    dt = min(last * growth, longest)
    ahead = [m - now for m in marks if m - now > 1e-9 * unit]
    if ahead and ahead[0] < dt * (1 + 1e-9):
        dt = ahead[0]
    elif ahead and ahead[0] < 1.5 * dt:  # no sliver before the mark
        dt = 0.5 * ahead[0]
    return dt


def scene_metrics(sim: Simulation, values: Values, seconds: float) -> dict[str, Any]:
    """The documented metrics of a finished run (:data:`METRICS`)."""
    recs = sim.records
    T = np.array([r.time / seconds for r in recs])
    numbers = [
        r.extra["diffusion_number"] for r in recs if "diffusion_number" in r.extra
    ]
    out: dict[str, Any] = {
        "consolidation_coefficient": consolidation_coefficient(values),
        "diffusion_number": [min(numbers), max(numbers)] if numbers else None,
        "n_particles": int(sim.particles.n),
    }
    if values["case"] == "terzaghi":
        soil = LinearElastic(values["E"], values["nu"], WEIGHTLESS)
        scale = values["load"] * values["height"] / soil.p_wave_modulus
        U = np.array([r.extra.get("settlement", np.nan) for r in recs]) / scale
        first = recs[0].extra.get("first_step_pressure") if recs else None
        out["degree_of_consolidation"] = [
            [float(a), float(b)] for a, b in zip(T, U, strict=True)
        ]
        out["degree_of_consolidation_error"] = (
            float(np.max(np.abs(U - terzaghi_degree(T)))) if T.size else None
        )
        out["first_step_pressure"] = (
            None if first is None else [v / values["load"] for v in first]
        )
        return out
    p0 = values["load"] / 2
    pc = np.array([r.extra.get("centre_pressure", np.nan) for r in recs]) / p0
    exact = mandel_pressure(0.0, T, values["nu"])[:, 0] if T.size else T
    out["centre_pressure"] = [[float(a), float(b)] for a, b in zip(T, pc, strict=True)]
    out["centre_pressure_error"] = float(np.max(np.abs(pc - exact))) if T.size else None
    i = int(np.argmax(pc)) if T.size else 0
    out["peak_pressure"] = [float(T[i]), float(pc[i])] if T.size else None
    fine = np.linspace(1e-3, 0.5, 5000)
    pe = mandel_pressure(0.0, fine, values["nu"])[:, 0]
    out["peak_pressure_exact"] = [float(fine[pe.argmax()]), float(pe.max())]
    return out


def consolidation_scenery(p: dict, folder: Path | None = None) -> Scenery:
    """The specimen's outline, its base and the smooth walls."""
    s = Scenery(scene="consolidation")
    H, W = number(p, "height"), number(p, "width")
    if H is None or W is None:
        return s
    s.floor, s.floor_label = 0.0, "fixed impermeable base"
    s.walls += [(0.0, 1, "smooth impermeable walls")]
    if p.get("case", "terzaghi") == "terzaghi":
        s.walls += [(W, -1, "")]
    s.outline = box(0.0, W, 0.0, H)
    return s


SCENE = Scene(
    name="consolidation",
    description=__doc__.strip().splitlines()[0].split(": ", 1)[1],
    params=PARAMS,
    build=build,
    metrics_doc=METRICS,
    scenery=consolidation_scenery,
    derive=derive,
    time_params=("dT_max", "T_end"),
)
