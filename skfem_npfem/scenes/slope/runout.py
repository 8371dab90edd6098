"""What the slope's run-out is measured by, and the mechanism picture.

The run-out of the toe, the crest settlement, the travel of the mass centre and
the volume that moved; the deposit's slopes against the friction angle and its
own factor of safety (a second limit analysis of the deposit).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from skfem import MeshTri

from ...boundary import RigidWall, floor
from ...constants import GRAVITY
from ...errors import NpfemError, SolverError, warn_user
from ...limit.loads import gravity_load
from ...limit.safety import strength_reduction
from ...limit.undrained import undrained_materials
from ...mesh.smoothing import nodal_integration
from ...mesh.sources import mesh_particles
from ...run.simulation import Simulation
from ...step.operators import step_strength
from ...strength_laws import SHEAR_FROM_EQUIVALENT
from ..common import (
    solver_from,
)
from .section import (
    _surface_height,
)
from .water import static_pressure

__all__ = [
    "RUNOUT_METRICS",
    "base_metrics",
    "deposit_factor_of_safety",
    "deposit_slopes",
    "intact_blocks",
    "runout_floor",
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


#: The run-out stage's metrics (null without it).
RUNOUT_METRICS = {
    "reduction": "strength reduction factor of the run-out (null without it)",
    "runout": "advance of the toe: farthest x of slope material above the "
    "foundation surface, minus the initial toe x, m (null without run-out)",
    "crest_settlement": "drop of the surface at the initial crest edge, m",
    "retrogression": "how far behind the crest's edge the failure reached: "
    "the crest edge's x less the smallest initial x of the particles that "
    "started behind it and moved more than half a spacing, m (0: none did)",
    "blocks": "with a softening clay (sensitivity > 1): how many intact blocks "
    "the failed mass broke into: groups of moved particles (neighbours within "
    "1.5 spacings) whose softening has taken less than half of its loss "
    "(xi < xi_95 ln(2) / 3), each of at least 0.05 H^2 initial area (null "
    "without softening or run-out)",
    "mass_centre_travel": "distance travelled by the mass centre of the moved "
    "particles (displacement > spacing/2), m",
    "moved_volume": "initial volume of the moved particles, m^2 per m",
    "deposit_profile": "list of [x, surface y] of the final section, one per spacing",
    "deposit_max_slope": "steepest surface slope of the deposit over 3 spacings, deg",
    "mass_change": "relative change of the total mass over the run-out",
    "volume_change": "relative change of the meshed volume over the run-out",
    "at_rest": "the run-out ended by the at-rest rule (not t_end)",
    "deposit_factor_of_safety": "factor of safety of the final deposit with the "
    "run-out's strengths (a second limit analysis; >= 1: statically admissible; "
    "null with a warning when its strength reduction finds none)",
}


def intact_blocks(
    x: np.ndarray,
    area: np.ndarray,
    candidate: np.ndarray,
    h: float,
    min_area: float,
) -> int:
    """How many connected groups of ``candidate`` particles are at least ``min_area``.

    Two candidates are neighbours when they are closer than ``1.5 h`` (one
    lattice spacing and its diagonal); a group's area is the sum of its
    particles' ``area`` (their initial volumes, m^2 per m).
    """
    idx = np.flatnonzero(candidate)
    if idx.size == 0:
        return 0
    pairs = cKDTree(x[idx]).query_pairs(1.5 * h, output_type="ndarray")
    n = idx.size
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    sizes = np.bincount(label, weights=area[idx])
    return int(np.count_nonzero(sizes >= min_area))


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
    # Each particle's initial volume (mass over its material's density).
    volume = p.mass / np.array([m.rho for m in sim.model.materials])[p.material]
    if moved.any():
        w = p.mass[moved]
        travel = float(np.linalg.norm((w[:, None] * p.u[moved]).sum(0) / w.sum()))
        vol = float(np.sum(volume[moved]))
    blocks = None
    law = sim.model.strength_law
    if law is not None and law.sensitivity > 1.0:
        intact = SHEAR_FROM_EQUIVALENT * p.eps_p < law.ductility * math.log(2) / 3
        H = y_crest - y_toe
        blocks = intact_blocks(x0, volume, moved & intact, h, 0.05 * H**2)
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
        "blocks": blocks,
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
    active, t = mesh_particles(sim.mesh_source, p)
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
        "blocks": None,
        "mass_centre_travel": None,
        "moved_volume": None,
        "deposit_profile": None,
        "deposit_max_slope": None,
        "mass_change": None,
        "volume_change": None,
        "at_rest": None,
        "deposit_factor_of_safety": None,
        "n_particles": n_particles,
        "inserted": 0,
        "merged": 0,
        "n_particles_final": n_particles,
        "stage_wall_time": {
            "initial_stress": state.get("t_initial", 0.0),
            "factor_of_safety": state.get("t_fos", 0.0),
            "factor_of_safety_check": state.get("t_fos_check", 0.0),
            "critical_kh": state.get("t_critical_kh", 0.0),
            "runout": float(sum(sum(r.timings.values()) for r in sim.records)),
        },
    }


def runout_floor(values: Mapping[str, Any], run_out: bool) -> list[RigidWall]:
    """The rigid base as a floor beyond the toe of a slope on no foundation layer.

    The parametric slope with ``foundation_depth = 0`` stands on its fixed
    base (``y = 0``); the run-out spreads beyond the toe on that base, a rigid
    wall with ``floor_friction`` (none otherwise: the foundation layer's
    particles carry the run-out).
    """
    if not run_out or values["geometry"] or values["foundation_depth"] > 0.0:
        return []
    return [floor(2, values["floor_friction"])]
