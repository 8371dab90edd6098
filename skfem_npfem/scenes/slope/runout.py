"""What the slope's run-out is measured by, and the mechanism picture.

The run-out of the toe, the crest settlement, the travel of the mass centre and
the volume that moved; the deposit's slopes against the friction angle and its
own factor of safety (a second limit analysis of the deposit).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from skfem import MeshTri

from ...constants import GRAVITY
from ...errors import NpfemError, SolverError, warn_user
from ...limit.loads import gravity_load
from ...limit.safety import strength_reduction
from ...limit.undrained import undrained_materials
from ...mesh.smoothing import nodal_integration
from ...run.simulation import Simulation
from ...step.operators import step_strength
from ..common import (
    solver_from,
)
from .section import (
    _surface_height,
)
from .water import static_pressure

__all__ = [
    "base_metrics",
    "deposit_factor_of_safety",
    "deposit_slopes",
    "runout_metrics",
    "save_mechanism",
]


def save_mechanism(folder: Path, pts, tri, res, volumes) -> None:
    """``mechanism.npz`` in ``folder``: the mechanism's data.

    ``skfem-npfem plot`` draws it as ``plots/mechanism.png``
    (:func:`skfem_npfem.viz.mechanism.plot_mechanism`).
    """
    lim = res.limit
    np.savez(
        folder / "mechanism.npz",
        x=pts,
        triangles=tri,
        velocity=lim.velocity,
        dissipation=lim.dissipation,
        plastic=lim.plastic,
        volumes=volumes,
        factor_of_safety=res.factor_of_safety,
    )


def runout_metrics(sim, state, values, h, x_toe, y_toe, x_crest, y_crest) -> dict:
    """The run-out stage's metrics from the particles at the end of the run.

    ``notes`` lists what went wrong in the deposit's factor of safety (which
    is then None; the other metrics stand).
    """
    p = sim.particles
    x0 = p.x - p.u
    moved = np.linalg.norm(p.u, axis=1) > 0.5 * h
    above = x0[:, 1] > y_toe + 0.25 * h
    behind = moved & (x0[:, 0] < x_crest)  # crest soil that took part
    retro = float(x_crest - x0[behind, 0].min()) if behind.any() else 0.0
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
    notes = []
    try:
        deposit_fos = deposit_factor_of_safety(sim, values)
    except (NpfemError, SolverError) as err:
        # A second analysis after the run: its failure must not cost the run.
        deposit_fos = None
        notes.append(
            f"slope: the deposit's factor of safety was not found ({err}); the "
            "run-out's results stand"
        )
        warn_user(notes[0])
    return {
        "notes": notes,
        "reduction": state.get("reduction"),
        "runout": max(runout, 0.0),
        "crest_settlement": float(y_crest - crest_now),
        "retrogression": retro,
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


def deposit_factor_of_safety(sim: Simulation, values: Mapping[str, Any]) -> float:
    """Factor of safety of the final deposit with the run-out's strengths.

    A second limit analysis, on the alpha-shape mesh of the particles at the
    end of the run (supports as at the start; each particle's strength as its
    last step had it: a profile's, softened); at least 1 when the deposit is
    statically admissible.  With water, as the slope's: the static pore
    pressure's force (drained) or the undrained strengths of the particles'
    effective stresses at the end (undrained).
    """
    p = sim.particles
    active, t = sim.mesh_source(p.x)
    mesh = MeshTri(np.ascontiguousarray(p.x[active].T), np.ascontiguousarray(t))
    ni = nodal_integration(mesh, (0, 1, 3))
    material = np.asarray(p.material)[active]
    rho = np.array([m.rho for m in sim.model.materials])[material]
    water, x = sim.model.water, p.x[active]
    pore = static_pressure(water, x, t, material)
    load = gravity_load(ni, rho, GRAVITY, x=x, pore_pressure=pore)
    fixed = np.asarray(p.fixed, bool)[active]
    mats = sim.model.materials
    if water is not None and water.undrained:
        mats = undrained_materials(mats, material, np.asarray(p.stress)[active])
    res = strength_reduction(
        ni,
        mats,
        material,
        load,
        fixed=fixed,
        options=solver_from(values),
        strength=step_strength(sim.model, p, active),
    )
    return float(res.factor_of_safety)


def base_metrics(
    fos: dict[str, Any],
    resid: float | None,
    n_particles: int,
    state: dict[str, Any],
    sim: Simulation,
) -> dict[str, Any]:
    """The slope's metrics before the run-out's: those left null without it.

    Parameters
    ----------
    fos : dict
        The factor of safety's metrics (:func:`fos_metrics`).
    resid : float or None
        Equilibrium residual of the initial stresses (None: limit only).
    n_particles : int
        Number of particles.
    state : dict
        The run's shared state (stage times).
    sim : Simulation
        The run (its step timings).

    Returns
    -------
    dict
    """
    return {
        **fos,
        "initial_equilibrium_residual": resid,
        "reduction": None,
        "runout": None,
        "crest_settlement": None,
        "retrogression": None,
        "mass_centre_travel": None,
        "moved_volume": None,
        "deposit_profile": None,
        "deposit_max_slope": None,
        "mass_change": None,
        "volume_change": None,
        "at_rest": None,
        "deposit_factor_of_safety": None,
        "n_particles": n_particles,
        "stage_wall_time": {
            "initial_stress": state.get("t_initial", 0.0),
            "factor_of_safety": state.get("t_fos", 0.0),
            "factor_of_safety_check": state.get("t_fos_check", 0.0),
            "critical_kh": state.get("t_critical_kh", 0.0),
            "runout": float(sum(sum(r.timings.values()) for r in sim.records)),
        },
    }
