"""Scene ``elastic-column``: soil column under self-weight (oedometric).

Fixed base, smooth (roller) sides, gravity along ``-e_d``.  Analytic answers:
``s_vv = -rho g (H - z)``, ``s_hh = nu/(1-nu) s_vv``, top settlement
``rho g H^2 / (2 M)`` with the constrained modulus ``M``; after a sudden
gravity switch-on the top oscillates with the first oedometric period
``T = 4 H / c_p``, ``c_p = sqrt(M / rho)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from skfem import MeshTet, MeshTri

from ...constants import GRAVITY
from ...errors import ParameterError
from ...materials import LinearElastic
from ...mesh.smoothing import nodal_integration
from ...mesh.sources import FixedMesh
from ...particles import Particles
from ...run.simulation import Simulation
from ...step.model import Model
from ...water import Water
from ..base import Scene, SceneRun
from ..common import (
    elastic_params,
    fidelity_from,
    fidelity_params,
    make_writer,
    solver_from,
    solver_params,
)
from ..limits import SPACING, check_size
from ..methods import METHOD_METRICS, method_params, with_method
from ..params import POSITIVE, Param, Values
from ..scenery import Scenery, box, number
from ..water import WATER_PARAMS, derive_drainage, scene_water
from ..wet_soil import (
    effective_vertical_stress,
    recorded_parameters,
    warn_dry_water,
)

PARAMS = [
    Param("dim", 2, "-", "spatial dimension (2: plane strain, 3: 3D)", int, (2, 3)),
    *elastic_params(1.0e7),
    Param(
        "rho", 2000.0, "kg/m^3", "density (saturated, with water)", float, **POSITIVE
    ),
    Param("gravity", GRAVITY, "m/s^2", "gravitational acceleration", float, lo=0),
    Param("height", 4.0, "m", "column height H", float, **POSITIVE),
    Param("width", 1.0, "m", "column width (and depth in 3D)", float, **POSITIVE),
    Param("spacing", 0.125, "m", "particle (node) spacing", float, **SPACING),
    Param("mode", "static", "-", "static or dynamic", str, ("static", "dynamic")),
    Param("dt", 0.01, "s", "time step", float, **POSITIVE),
    Param(
        "steps",
        1,
        "-",
        "number of steps of dt, run exactly (mode=dynamic: time steps to t = "
        "steps x dt; mode=static: load steps under the full weight, the first "
        "already in equilibrium)",
        int,
        lo=1,
    ),
    Param(
        "theta1", 1.0, "-", "time-integration parameter theta1", float, lo=0.5, hi=1.0
    ),
    Param(
        "theta2", 1.0, "-", "time-integration parameter theta2", float, lo=0.5, hi=1.0
    ),
    *WATER_PARAMS,
    *method_params(spfem="mode=dynamic only"),
    *fidelity_params(0.0),
    *solver_params(),
]

METRICS = {
    "sigma_v_rel_l2": "relative L2 error of the vertical (effective) stress vs "
    "-rho g (H - z) (with water: the buoyant rho - rho_w below the water table; "
    "undrained: vs 0, relative to the drained stress: the mixture keeps its "
    "volume between the walls, so the skeleton carries nothing new)",
    "sigma_h_rel_l2": "relative L2 error of the horizontal stress vs nu/(1-nu) s_v",
    "pore_pressure_rel_l2": "relative L2 error of the pore pressure vs rho_w g "
    "(water_level - z) below the table (wet runs only)",
    "excess_pore_pressure_rel_l2": "relative L2 error of the excess pore pressure "
    "vs the drained effective vertical stress it carries instead (undrained only)",
    "settlement": "mean top settlement at the end, m (positive down)",
    "settlement_exact": "rho g H^2 / (2 M), m (with water: the integral of "
    "-s'_v / M over the height)",
    "base_sigma_v": "mean vertical stress of the base particles, Pa",
    "period": "oscillation period of the top (dynamic, >= 1 period run), s",
    "period_exact": "first oedometric period 4 H / c_p, s",
    "n_particles": "number of particles",
    **METHOD_METRICS,
}


def column_mesh(dim: int, width: float, height: float, spacing: float):
    """Structured P1 mesh of the column (width^(d-1) x height)."""
    nx = max(1, round(width / spacing))
    nz = max(1, round(height / spacing))
    xs = np.linspace(0.0, width, nx + 1)
    zs = np.linspace(0.0, height, nz + 1)
    if dim == 2:
        return MeshTri.init_tensor(xs, zs)
    return MeshTet.init_tensor(xs, xs, zs)


#: Largest elastic strain scale ``rho g H / M`` of a run (a settlement of 30 H).
#: Beyond it one step's increment is huge: its round-off spin rotates the
#: stress (sigma_v error 0.4 % at 58, 1.3 % at 117, 6 % at 290, 27 % at 5.8e3),
#: and from ~1e16 on ``x = x0 + u`` loses ``x0`` to round-off, so the depth of
#: the analytic reference is lost (the 58 % reported at E = 1e-300).
MAX_ELASTIC_STRAIN = 60.0


def check_values(values: Mapping[str, Any]) -> None:
    """Refuse a column too coarse, too big or too soft for its own weight."""
    dim, H, W, h = values["dim"], values["height"], values["width"], values["spacing"]
    if h > H / 4:
        raise ParameterError(
            "spacing",
            h,
            f"at most height/4 = {H / 4:g} m (4 elements over the height give "
            "a stress error of 8 %, one element 69 %)",
        )
    nx, nz = max(1, round(W / h)), max(1, round(H / h))
    check_size((nx + 1) ** (dim - 1) * (nz + 1), dim, values)
    mat = LinearElastic(values["E"], values["nu"], values["rho"])
    strain = mat.rho * values["gravity"] * H / mat.p_wave_modulus
    if strain > MAX_ELASTIC_STRAIN:
        least = values["E"] * strain / MAX_ELASTIC_STRAIN
        raise ParameterError(
            "E",
            values["E"],
            f"at least {least:.3g} Pa for this column: its elastic strain "
            f"rho g H / M = {strain:.3g} is beyond {MAX_ELASTIC_STRAIN:g} (a "
            "settlement of 30 H), where the stresses are no longer right",
        )


def build(
    values: Values, out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build the elastic column simulation."""
    check_values(values)
    dim, H, W = values["dim"], values["height"], values["width"]
    mesh = column_mesh(dim, W, H, values["spacing"])
    mat = LinearElastic(values["E"], values["nu"], values["rho"])
    ni = nodal_integration(mesh)
    x = mesh.p.T.copy()
    fixed = np.zeros_like(x, dtype=bool)
    fixed[np.isclose(x[:, -1], 0.0)] = True
    for k in range(dim - 1):  # smooth side walls: rollers
        fixed[np.isclose(x[:, k], 0.0) | np.isclose(x[:, k], W), k] = True
    particles = Particles.create(x, mat.rho * ni.volumes, fixed=fixed)
    water = scene_water(values)
    if water is not None:  # stress-free skeleton, its pore water at rest
        particles = particles.replace(
            pore_pressure=water.static_pressure(x, values["gravity"]),
            excess_pore_pressure=np.zeros(particles.n),
        )
    model = Model(
        dim=dim,
        materials=[mat],
        gravity=values["gravity"],
        mode=values["mode"],
        theta1=values["theta1"],
        theta2=values["theta2"],
        solver=solver_from(values),
        water=water,
        **fidelity_from(values, 0.0),
    )
    sim = Simulation(
        particles,
        model,
        FixedMesh(mesh.t),
        values["dt"],
        writer=make_writer(out, resume),
        progress=progress,
        meta={"scene": "elastic-column", "parameters": recorded_parameters(values)},
    )
    top = np.isclose(x[:, -1], H)

    def record_top(sim_, p, step) -> bool:
        # Stored on the step record so that it survives checkpoints (--resume).
        step.record.extra["settlement_top"] = float(-p.u[top, -1].mean())
        return False

    sim.callbacks.append(record_top)

    def metrics(sim_: Simulation) -> dict[str, float]:
        return column_metrics(sim_, values, mat, top, water)

    return with_method(values, SceneRun(sim, {"steps": values["steps"]}, metrics))


def column_metrics(
    sim_: Simulation,
    values: Values,
    mat: LinearElastic,
    top: np.ndarray,
    water: Water | None,
) -> dict[str, float]:
    """The column's metrics against the exact oedometric column at rest."""
    dim, H = values["dim"], values["height"]
    p = sim_.particles
    z0 = p.x[:, -1] - p.u[:, -1]
    g = values["gravity"]
    sv_ex = effective_vertical_stress(z0, H, mat.rho, g, water)
    undrained = water is not None and water.undrained
    if undrained:
        # The mixture keeps its volume and the walls hold it sideways:
        # nothing moves, and the excess pore pressure carries what the
        # skeleton would carry drained.
        drained_sv, sv_ex = sv_ex, np.zeros_like(sv_ex)
    nu = mat.nu
    sv = p.stress[:, dim - 1] if dim == 2 else p.stress[:, 2]
    sh = p.stress[:, 0]
    M = mat.p_wave_modulus
    base = np.isclose(z0, 0.0)
    t_exact = 4 * H / np.sqrt(M / mat.rho)
    scale = drained_sv if undrained else sv_ex
    out = {
        "sigma_v_rel_l2": _rel(sv, sv_ex, scale),
        # nu = 0: the exact s_h is 0; normalise by |s_v| instead of NaN.
        "sigma_h_rel_l2": _rel(sh, nu / (1 - nu) * sv_ex, scale),
        "settlement": float(-p.u[top, -1].mean()),
        "settlement_exact": 0.0
        if undrained
        else exact_settlement(H, mat.rho, g, M, water),
        "base_sigma_v": float(sv[base].mean()),
        "period": oscillation_period(
            [
                (r.time, r.extra["settlement_top"])
                for r in sim_.records
                if "settlement_top" in r.extra
            ]
        ),
        "period_exact": float(t_exact),
        "n_particles": int(p.n),
        **pore_metrics(p, water, g),
    }
    if undrained:
        out["excess_pore_pressure_rel_l2"] = _rel(p.excess_pore_pressure, -drained_sv)
    return out


def pore_metrics(p: Particles, water: Water | None, g: float) -> dict[str, float]:
    """``pore_pressure_rel_l2`` of a wet column (a dry one reports none)."""
    if water is None:
        return {}
    exact = water.static_pressure(p.x - p.u, g)
    return {"pore_pressure_rel_l2": _rel(p.pore_pressure, exact)}


def exact_settlement(
    H: float, rho: float, g: float, M: float, water: Water | None
) -> float:
    """Top settlement ``integral_0^H -s'_v / M dz`` of the column at rest, m.

    Dry: ``rho g H^2 / (2 M)``.  The effective stress is linear in ``z`` but
    for a kink at the water table, so the trapezoidal rule on ``0``, the
    table and ``H`` is exact.
    """
    if water is None or water.table is None:
        return rho * g * H**2 / (2 * M)
    level = float(np.clip(water.table.elevation(np.zeros((1, 2)))[0], 0.0, H))
    z = np.unique([0.0, level, H])
    sv = effective_vertical_stress(z, H, rho, g, water)
    return float(-np.sum(0.5 * (sv[1:] + sv[:-1]) * np.diff(z)) / M)


def derive(values: dict[str, Any]) -> None:
    """The column's derived defaults, in place: ``drainage`` from ``water_level``."""
    derive_drainage(values)


def _rel(a: np.ndarray, b: np.ndarray, scale: np.ndarray | None = None) -> float:
    """``|a - b| / |b|``; if ``b`` is zero, ``|a - b| / |scale|`` (NaN without)."""
    nb = float(np.linalg.norm(b))
    if nb == 0 and scale is not None:
        nb = float(np.linalg.norm(scale))
    return float(np.linalg.norm(a - b) / nb) if nb > 0 else float("nan")


def oscillation_period(history: list[tuple[float, float]]) -> float:
    """Period of a signal from its crossings of the mean (NaN if < 1 period).

    Crossings are located by linear interpolation; the period is twice the mean
    spacing of consecutive crossings.
    """
    if len(history) < 4:
        return float("nan")
    t = np.array([0.0] + [h[0] for h in history])
    w = np.array([0.0] + [h[1] for h in history])
    s = w - 0.5 * (w.max() + w.min())
    idx = np.flatnonzero(np.sign(s[:-1]) * np.sign(s[1:]) < 0)
    if idx.size < 3:
        return float("nan")
    tc = t[idx] - s[idx] * (t[idx + 1] - t[idx]) / (s[idx + 1] - s[idx])
    return float(2.0 * np.mean(np.diff(tc)))


def column_scenery(p: dict, folder: Path | None = None) -> Scenery:
    """The column's scenery: fixed base, roller side walls, static label."""
    s = Scenery(scene="elastic-column")
    H, W = number(p, "height"), number(p, "width")
    if H is None or W is None:
        return s
    s.floor, s.floor_label = 0.0, "fixed base"
    s.walls += [(0.0, 1, "smooth side walls (rollers)"), (W, -1, "")]
    s.outline = box(0.0, W, 0.0, H)
    if p.get("mode") == "static":
        s.label = lambda t: f"static load step (pseudo-time {t:.3g})"
    return s


SCENE = Scene(
    name="elastic-column",
    description=__doc__.strip().splitlines()[0].split(": ", 1)[1],
    params=PARAMS,
    build=build,
    metrics_doc=METRICS,
    scenery=column_scenery,
    derive=derive,
    ignored=warn_dry_water,
    time_params=None,  # a run counts its steps
)
