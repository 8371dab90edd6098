"""Strip footing loaded fast, then held: the settlement of a consolidating soil.

With ``load`` (Pa) the footing is rigid and smooth (rough: its horizontal
motion fixed) and force controlled: the vertical displacements of its nodes
are one tied unknown (:attr:`~skfem_npfem.Model.tied`) carrying the mean
pressure ``load`` over its width (:func:`~skfem_npfem.surface_load`).  The
whole load is applied in the first step.  With ``drainage=coupled`` it is then
held for ``hold`` (a time factor ``c_v t / B^2``, ``c_v = k M / gamma_w``, M
the skeleton's P-wave modulus) while the excess pore pressure drains through
the soil surface beside the footing; the footing's own facets are impermeable
(its nodes are tied along their normal), and so are the symmetry face, the
far side (rollers) and the fixed base.  The time steps grow geometrically:
the first is ``dT``, each next ``dt_growth`` times the last, at most
``dT_max``, landing on the report times of the consolidation scene.  With
another drainage the run is the one step: ``undrained`` gives the immediate
settlement, ``dry`` the drained one.

The settlement is that of the footing; the degree of consolidation is
``U = (s - s_immediate) / (s_final - s_immediate)``.  Without ``load`` a
coupled footing takes its settlement steps at 1 m/s: their pseudo-time is
the time of Darcy's flow, in seconds.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from skfem import MeshTri

from ...errors import ParameterError
from ...loads import surface_load
from ...materials import Material
from ...mesh.sources import FixedMesh
from ...particles import Particles
from ...run.simulation import Simulation
from ...step.model import Model
from ..base import SceneRun
from ..common import fidelity_from, solver_from
from ..consolidation.scene import REPORT_TIMES, growing_step
from ..params import POSITIVE, Param
from ..water import scene_water
from ..wet_soil import recorded_parameters
from .strip_water import soil_gravity

__all__ = [
    "LOAD_METRICS",
    "LOAD_PARAMS",
    "consolidation_coefficient",
    "footing_model",
    "footing_parameters",
    "held_load_run",
]

_IF_HELD = "with load and drainage=coupled: "

#: The parameters of the footing loaded fast, then held.
LOAD_PARAMS = [
    Param(
        "load",
        None,
        "Pa",
        "footing pressure applied at once in the first step and held (a rigid "
        "force-controlled footing; drainage=coupled consolidates under it, "
        "another drainage takes that one step); default none: settlement steps",
        float,
        **POSITIVE,
    ),
    Param(
        "hold",
        30.0,
        "-",
        _IF_HELD + "how long the load is held, as a time factor c_v t / B^2 "
        "(c_v = k M / gamma_w, M the P-wave modulus E (1 - nu) / ((1 + nu) "
        "(1 - 2 nu)))",
        float,
        lo=1e-9,
        hi=1e4,
    ),
    Param(
        "dT",
        1.0e-4,
        "-",
        _IF_HELD + "first time step (the loading step) as a time factor c_v dt / B^2",
        float,
        lo=1e-9,
        hi=10.0,
    ),
    Param(
        "dt_growth",
        1.3,
        "-",
        _IF_HELD + "ratio of a time step to the one before",
        float,
        lo=1.0,
        hi=10.0,
    ),
    Param(
        "dT_max",
        1.0,
        "-",
        _IF_HELD + "longest time step as a time factor c_v dt / B^2",
        float,
        lo=1e-9,
        hi=100.0,
    ),
]

#: The metrics of a run with ``load`` (the settlement-step metrics are null).
LOAD_METRICS = {
    "settlement_immediate": "load: the footing's settlement after the first "
    "step (the loading), m",
    "settlement_final": "load: the footing's settlement after the last step, m",
    "settlement_time": "load: list of [t (s), settlement (m)] per step",
    "time_50": "load, coupled: time to 50 % consolidation, U = (s - "
    "s_immediate) / (s_final - s_immediate) = 0.5, s (linear between steps)",
    "time_90": "load, coupled: time to U = 0.9, s",
    "time_factor_50": "load, coupled: c_v time_50 / B^2",
    "time_factor_90": "load, coupled: c_v time_90 / B^2",
    "consolidation_coefficient": "load, coupled: c_v = k M / gamma_w, m^2/s",
    "diffusion_number": "load, coupled: [min, max] of c_v dt / h^2 over the steps",
}

#: The held-load parameters at their defaults, which a run without ``load``
#: leaves out of its record (its checkpoints stay those of before).
_UNLOADED = {p.name: p.default for p in LOAD_PARAMS} | {"k": None}


def footing_parameters(values: Mapping[str, Any]) -> dict[str, Any]:
    """The parameters a strip-footing run records.

    :func:`~skfem_npfem.scenes.wet_soil.recorded_parameters` without the
    held-load parameters and ``k`` at their defaults.
    """
    return {
        key: v
        for key, v in recorded_parameters(values).items()
        if key not in _UNLOADED or _UNLOADED[key] != v
    }


def footing_model(values: Mapping[str, Any], mat: Material, **extra) -> Model:
    """The footing's static model; ``extra`` (loads, tied dofs) passed on.

    A coupled soil gets the gravity of ``values`` even when weightless
    (Darcy's law needs ``gamma_w = rho_w g``).

    Raises
    ------
    ParameterError
        A ``water_level`` with a weightless coupled soil (its skeleton would
        float).
    """
    coupled = values["drainage"] == "coupled"
    if coupled and values["rho"] == 0 and values["water_level"] is not None:
        raise ParameterError(
            "water_level",
            values["water_level"],
            "none with drainage=coupled and a weightless soil (rho = 0): the "
            "excess pore pressure alone drains",
        )
    return Model(
        dim=2,
        materials=[mat],
        gravity=values["gravity"] if coupled else soil_gravity(values),
        mode="static",
        objective_rotation=values["large_deformation"],
        update_geometry=values["large_deformation"],
        solver=solver_from(values),
        water=scene_water(values),
        **fidelity_from(values, 0.0),
        **extra,
    )


def consolidation_coefficient(values: Mapping[str, Any], mat: Material) -> float:
    """``c_v = k M / gamma_w`` of the skeleton ``mat``, m^2/s."""
    E, nu = mat.E, mat.nu
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    return values["k"] * M / (values["rho_w"] * values["gravity"])


def _check(values: Mapping[str, Any]) -> None:
    if values["analysis"] == "limit":
        raise ParameterError(
            "analysis", "limit", "incremental with load (the held load takes steps)"
        )
    if values["method"] != "npfem":
        raise ParameterError("method", values["method"], "npfem with load")
    if values["dT_max"] < values["dT"]:
        raise ParameterError("dT_max", values["dT_max"], f">= dT = {values['dT']:g}")


def held_load_run(
    values: Mapping[str, Any],
    mesh: MeshTri,
    mat: Material,
    particles: Particles,
    foot: np.ndarray,
    writer=None,
    progress=None,
) -> SceneRun:
    """The footing loaded by ``load`` in one step, then held (coupled).

    ``particles`` and ``foot`` are those of the settlement-controlled footing
    (:func:`~.mesh.soil_particles`): the footing's vertical dofs are freed
    and tied, and its prescribed speed removed.
    """
    _check(values)
    foot_ids = np.flatnonzero(foot)
    fixed = np.array(particles.fixed, bool, copy=True)
    fixed[foot_ids, 1] = False
    particles = particles.replace(
        fixed=fixed, v_prescribed=np.zeros_like(particles.v_prescribed)
    )
    loads = surface_load(particles.x, foot, values["load"])
    model = footing_model(values, mat, loads=loads, tied=[(foot_ids, 1)])
    coupled = values["drainage"] == "coupled"
    B = values["width"]
    seconds = B**2 / consolidation_coefficient(values, mat) if coupled else 1.0
    sim = Simulation(
        particles,
        model,
        FixedMesh(mesh.t),
        values["dT"] * seconds,
        writer=writer,
        progress=progress,
        meta={"scene": "strip-footing", "parameters": footing_parameters(values)},
    )
    sim.dt_max = values["dT_max"] * seconds if coupled else sim.dt
    hold = values["hold"]
    marks = [T * seconds for T in (*REPORT_TIMES, hold) if T <= hold]

    def record(sim_: Simulation, p: Particles, step) -> bool:
        step.record.extra["settlement"] = float(-p.u[foot_ids, 1].mean())
        sim_.dt = growing_step(
            step.record.dt, values["dt_growth"], sim_.dt_max, sim_.time, marks, 1.0
        )
        return False

    sim.callbacks.append(record)
    run = {"t_end": hold * seconds} if coupled else {"steps": 1}
    return SceneRun(
        sim, run, lambda s: held_metrics(s, seconds if coupled else None, B)
    )


def held_metrics(
    sim: Simulation, seconds: float | None, width: float
) -> dict[str, Any]:
    """The :data:`LOAD_METRICS` of a finished run (``seconds``: B^2 / c_v; B)."""
    recs = [r for r in sim.records if "settlement" in r.extra]
    t = np.array([r.time for r in recs])
    s = np.array([r.extra["settlement"] for r in recs])
    out: dict[str, Any] = {key: None for key in LOAD_METRICS}
    out["n_particles"] = int(sim.particles.n)
    if not recs:
        return out
    out["settlement_immediate"] = float(s[0])
    out["settlement_final"] = float(s[-1])
    out["settlement_time"] = [[float(a), float(b)] for a, b in zip(t, s, strict=True)]
    if seconds is None or len(recs) < 2 or s[-1] == s[0]:
        return out
    U = (s - s[0]) / (s[-1] - s[0])
    for share in (50, 90):
        i = int(np.argmax(U >= share / 100))
        f = (share / 100 - U[i - 1]) / (U[i] - U[i - 1])
        time = float(t[i - 1] + f * (t[i] - t[i - 1]))
        out[f"time_{share}"] = time
        out[f"time_factor_{share}"] = time / seconds
    out["consolidation_coefficient"] = width**2 / seconds
    numbers = [
        r.extra["diffusion_number"] for r in recs if "diffusion_number" in r.extra
    ]
    out["diffusion_number"] = [min(numbers), max(numbers)] if numbers else None
    return out
