"""Scene ``column-collapse``: 2D (plane-strain) granular column collapse.

A cohesionless column of width ``L0`` and height ``H0 = aspect * L0`` stands on a
rough floor and is released at ``t = 0``.  With ``symmetric=true`` (default) the
half column ``0 <= x <= L0`` leans against a smooth wall at ``x = 0`` (the
symmetry plane, as in the channel experiments of Lube et al. 2005); otherwise a
free-standing column ``-L0 <= x <= L0`` collapses to both sides.

The particles start on a regular lattice of the given spacing (the remesher
breaks the lattice ties), with masses ``rho V_i`` from the initial mesh (kept
fixed: mass is conserved exactly), a geostatic stress ``s_yy = -rho g (H0 - y)``,
``s_xx = s_zz = K0 s_yy``, and floor contact forces equal to the weight of the
column over each base particle's tributary width (the floor friction is lagged:
without them the first step would be frictionless).  Every step the particles are
re-triangulated (Delaunay plus alpha shape); the floor is a rigid wall with
lagged Coulomb friction, the symmetry wall is frictionless.  The material is
Mohr-Coulomb (exact in plane strain) or Drucker-Prager (plane-strain match),
with ``psi < phi`` through frozen friction and a tension cut-off.

The run stops at ``t_end`` or earlier, once the kinetic energy has fallen below
``rest_fraction`` times its maximum (after ``min_time``).

Run-out convention: ``runout`` (``L_inf``) is the *99 % mass front*: the
position below which 99 % of the particle mass lies, measured from the wall
(``x = 0``) when symmetric, and half the distance between the 0.5 % and 99.5 %
mass quantiles otherwise.  It converges under refinement (3.38 +- 0.03 L0 at
a = 2 for 12 to 22 particles across L0, docs/validation.md), whereas the edge
of the meshed main body flickers as thin tail elements are dropped and rebuilt;
that edge is still reported as ``runout_main_body``, and the farthest grain as
``runout_tip``.  The front has stopped (``collapse_time``) once the run-out
stays within one spacing of its final value.
Lube et al. (2005) found ``(L_inf - L0) / L0 = 1.2 a`` for ``a <~ 1.8`` and
``1.9 a^(2/3)`` for ``a >~ 2.8`` (``a`` = aspect ratio).

Time integration: keep ``theta2 = 1``.  ``theta2`` sets the restitution of
impacts, ``e = 1/theta2 - 1``: ``theta2 = 1/2`` makes the impact on the floor
perfectly elastic and the collapse gains volume and then blows up.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from ...boundary import floor, wall_x
from ...constants import GRAVITY
from ...errors import ParameterError, warn_user
from ...laws import lube2005_runout as lube_runout
from ...materials import DruckerPrager, MohrCoulomb
from ...mesh.smoothing import nodal_integration
from ...mesh.sources import AlphaShapeMesher, main_body
from ...particles import Particles
from ...run.rest import AtRest
from ...run.simulation import Simulation
from ...step.model import Model
from ...step.records import Step
from ..base import Scene, SceneRun
from ..common import (
    check_soil,
    fidelity_from,
    make_writer,
    solver_from,
)
from ..limits import check_size
from ..methods import with_method
from ..params import Values
from ..refinement import insert_metrics, refiner_from, strategies
from ..scenery import Scenery, box, number, time_label
from ..shaking import model_kh
from ..water import scene_water
from ..wet_soil import recorded_parameters, wet_column
from .geometry import fill_column_defaults
from .params import (
    COLLAPSE_STABILISATION,
    COLLAPSE_VOLUME_CORRECTION,
    MAX_STIFFNESS_RATIO,
    MAX_STRENGTH_RATIO,
    METRICS,
    PARAMS,
    VOLUME_CORRECTION_STRAIN,
)
from .runout import (
    collapse_time,
    detached_fraction,
    detached_warnings,
    front,
    mass_front,
    picture_front,
    rest_warnings,
)


def lattice(x0: float, x1: float, height: float, spacing: float) -> np.ndarray:
    """Regular lattice over ``[x0, x1] x [0, height]`` with about ``spacing``."""
    nx = max(1, round((x1 - x0) / spacing))
    ny = max(1, round(height / spacing))
    X, Y = np.meshgrid(
        np.linspace(x0, x1, nx + 1), np.linspace(0.0, height, ny + 1), indexing="ij"
    )
    return np.column_stack([X.ravel(), Y.ravel()])


def graded_lattice(
    x0: float, x1: float, height: float, h: float, band: float, symmetric: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The lattice of :func:`lattice`, every other point kept in the core.

    Points within ``band`` of the top, the free side(s) (``x1``; ``x0`` too
    unless ``symmetric``) and the floor keep the spacing ``h``; the others
    only where both lattice indices are even (spacing ``2 h``).  Returns the
    points and the spacing of each.
    """
    x = lattice(x0, x1, height, h)
    i = np.rint((x[:, 0] - x0) / h).astype(int)
    j = np.rint(x[:, 1] / h).astype(int)
    fine = (x[:, 1] > height - band) | (x[:, 1] < band) | (x[:, 0] > x1 - band)
    if not symmetric:
        fine |= x[:, 0] < x0 + band
    keep = fine | ((i % 2 == 0) & (j % 2 == 0))
    return x[keep], np.where(fine[keep], h, 2.0 * h)


def initial_particles(
    x: np.ndarray,
    mesher: AlphaShapeMesher,
    *,
    rho: float,
    gravity: float,
    height: float,
    K0: float,
    n_walls: int,
    floor_id: int = 0,
) -> Particles:
    """Particles at rest with geostatic stress, mesh masses and floor forces.

    Masses are ``rho V_i`` from the initial alpha-shape mesh; the floor force of
    each base particle (``y = 0``) is the weight of the column over its tributary
    width (half the distance to its neighbours), the lagged normal force of the
    first step's Coulomb friction.
    """
    active, _ = mesher(x)
    if active.size != x.shape[0]:
        raise ParameterError("spacing", mesher.h, "all lattice particles meshed")
    ni = nodal_integration(mesher.last.mesh())
    volumes = np.zeros(x.shape[0])
    volumes[active] = ni.volumes
    stress = np.zeros((x.shape[0], 4))
    stress[:, 1] = -rho * gravity * (height - x[:, 1])
    stress[:, 0] = stress[:, 2] = K0 * stress[:, 1]
    p = Particles.create(x, rho * volumes, stress=stress, n_walls=n_walls)
    base = np.flatnonzero(np.isclose(x[:, 1], 0.0, atol=1e-9 * height))
    xb = x[base, 0]
    order = np.argsort(xb)
    xs = xb[order]
    width = np.diff(np.concatenate([xs[:1], 0.5 * (xs[1:] + xs[:-1]), xs[-1:]]))
    wall_force = np.zeros((x.shape[0], n_walls))
    wall_force[base[order], floor_id] = rho * gravity * height * width
    return p.replace(wall_force=wall_force)


def _check(values: Mapping[str, Any]) -> float:
    """Refuse inconsistent values; return the particle spacing h."""
    L0, H0 = values["half_width"], values["aspect"] * values["half_width"]
    h = values["spacing"] if values["spacing"] is not None else L0 / 22.0
    if h > L0 / 2 or h > H0 / 2:
        if values["spacing"] is None:  # the user set aspect, not the spacing
            raise ParameterError(
                "aspect",
                values["aspect"],
                f"at least {2 * h / L0:.3g} with the default spacing L0/22 (the "
                "column must be 2 spacings high), or set a smaller spacing",
            )
        raise ParameterError(
            "spacing", h, f"at most min(L0, H0)/2 = {min(L0, H0) / 2:g} m"
        )
    # Up-front size check (scenes/limits.py), before anything is built.
    width = L0 if values["symmetric"] else 2 * L0
    n = (max(1, round(width / h)) + 1) * (max(1, round(H0 / h)) + 1)
    blame = "spacing" if values["spacing"] is not None else "aspect"
    check_size(n, 2, values, blame, "use a larger spacing or a smaller column")
    c = values["c"]
    weight = values["rho"] * values["gravity"] * H0
    if c > MAX_STRENGTH_RATIO * weight:
        raise ParameterError(
            "c",
            c,
            f"at most {MAX_STRENGTH_RATIO:g} rho g H0 = "
            f"{MAX_STRENGTH_RATIO * weight:.3g} Pa: a column that strong stands "
            "still, and the solver tolerance no longer resolves its weight",
        )
    if values["E"] > MAX_STIFFNESS_RATIO * weight:
        raise ParameterError(
            "E",
            values["E"],
            f"at most {MAX_STIFFNESS_RATIO:g} rho g H0 = "
            f"{MAX_STIFFNESS_RATIO * weight:.3g} Pa: the elastic strains fall "
            "below the solver tolerance (the flow is rate-independent long "
            "before: E = 10 GPa and 10 MPa give the same run-out)",
        )
    check_soil(values)
    if values["theta2"] < 1.0:
        warn_user(
            f"theta2={values['theta2']:g}: impacts on the floor have restitution "
            f"{1 / values['theta2'] - 1:.2f}; theta2 = 1/2 makes them elastic and the "
            "collapse unstable (keep theta2 = 1)",
        )
    return h


def _volume_correction(values: Mapping[str, Any]) -> float:
    """The default kappa: COLLAPSE_VOLUME_CORRECTION where its premise holds."""
    h0 = values["aspect"] * values["half_width"]
    strain = values["rho"] * values["gravity"] * h0 / values["E"]
    if values["psi"] == 0.0 and strain <= VOLUME_CORRECTION_STRAIN:
        return COLLAPSE_VOLUME_CORRECTION
    return 0.0


def _model(values: Mapping[str, Any]) -> Model:
    """Walls (rough floor, smooth symmetry wall) and the Mohr-Coulomb/DP soil."""
    phi = values["phi"]
    floor_phi = phi if values["floor_friction"] is None else values["floor_friction"]
    walls = [floor(2, floor_phi)]
    if values["symmetric"]:
        walls.append(wall_x(2, 0.0, facing=1, friction_angle=0.0))
    cls = MohrCoulomb if values["material"] == "mohr-coulomb" else DruckerPrager
    mat = cls(
        values["E"],
        values["nu"],
        values["rho"],
        c=values["c"],
        phi=phi,
        psi=values["psi"],
        tension_cutoff=True,
    )
    return Model(
        dim=2,
        materials=[mat],
        gravity=values["gravity"],
        mode="dynamic",
        theta1=values["theta1"],
        theta2=values["theta2"],
        walls=walls,
        kh=model_kh(values),
        solver=solver_from(values),
        water=scene_water(values),
        **fidelity_from(values, COLLAPSE_STABILISATION, _volume_correction(values)),
    )


def _front_recorder(h: float, symmetric: bool):
    """Callback storing the run-out measures on each step record."""

    def record_front(sim_: Simulation, p: Particles, step: Step) -> bool:
        body = np.zeros(p.n, bool)
        body[step.active[main_body(p.x[step.active], 3.0 * h)]] = True
        edge, top = front(p.x, body, symmetric)
        tip, _ = front(p.x, np.ones(p.n, bool), symmetric)
        step.record.extra.update(
            runout=mass_front(p.x, p.mass, symmetric),
            runout_main_body=edge,
            runout_tip=tip,
            max_height=top,
            detached_mass_fraction=detached_fraction(p.mass, body),
        )
        return False

    return record_front


def _metrics(values: Mapping[str, Any], h: float, stop: AtRest | None):
    """The summary metrics of a finished run (see METRICS)."""
    L0, a = values["half_width"], values["aspect"]
    H0 = a * L0
    t_scale = math.sqrt(H0 / values["gravity"])

    def metrics(sim_: Simulation) -> dict[str, Any]:
        recs = sim_.records
        last = recs[-1].extra if recs else {}
        times = np.array([r.time for r in recs])
        runouts = np.array([r.extra.get("runout", np.nan) for r in recs])
        runout = float(runouts[-1]) if recs else L0
        top = float(last.get("max_height", H0))
        at_rest = bool(stop is not None and stop(sim_))
        # Before rest (stopped by t_end) the front may still move: unknown.
        t_c = collapse_time(times, runouts, h) if at_rest else float("nan")
        summ = sim_.summary()
        main = float(last.get("runout_main_body", L0))
        detached = float(last.get("detached_mass_fraction", 0.0))
        notes = detached_warnings("column-collapse", detached, runout, main, L0)
        added = insert_metrics(sim_)
        for msg in notes:
            warn_user(msg)
        return {
            "runout": runout,
            "normalised_runout": (runout - L0) / L0,
            "runout_main_body": main,
            "normalised_runout_main_body": (main - L0) / L0,
            "detached_mass_fraction": detached,
            "runout_tip": float(last.get("runout_tip", L0)),
            "reference_runout_lube": lube_runout(a),
            "final_height": top / L0,
            "height_ratio": top / H0,
            "collapse_time": t_c,
            "collapse_time_normalised": t_c / t_scale,
            "at_rest": at_rest,
            "warnings": [*rest_warnings(sim_, values, stop), *notes],
            "volume_change": summ["volume_change"],
            "mass_change": summ["mass_change"],
            "max_kinetic_energy": summ["max_kinetic_energy"],
            "final_kinetic_energy": float(recs[-1].kinetic_energy) if recs else 0.0,
            "n_inactive_final": int(recs[-1].n_inactive) if recs else 0,
            "n_particles": int(sim_.particles.n),
            "inserted": added["inserted"],
            "merged": added["merged"],
        }

    return metrics


def build(
    values: Values, out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build the column-collapse simulation."""
    h = _check(values)
    L0, H0 = values["half_width"], values["aspect"] * values["half_width"]
    symmetric = values["symmetric"]
    model = _model(values)
    x0 = 0.0 if symmetric else -L0
    x, graded = lattice(x0, L0, H0, h), None
    if "surface" in strategies(values):  # surface or surface+strain
        band = values["refine_band"] * h
        x, graded = graded_lattice(x0, L0, H0, h, band, symmetric)
    mesher = AlphaShapeMesher(h, values["alpha"], walls=model.walls, spacing=graded)
    particles = initial_particles(
        x,
        mesher,
        rho=values["rho"],
        gravity=values["gravity"],
        height=H0,
        K0=values["K0"],
        n_walls=len(model.walls),
    )
    particles = wet_column(particles, model, values, H0)
    sim = collapse_simulation(particles, model, mesher, values, out, progress, resume)
    sim.refiner = refiner_from(values)
    sim.callbacks.append(_front_recorder(h, symmetric))
    run_kwargs, stop = run_control(values, H0)
    srun = SceneRun(sim, run_kwargs, _metrics(values, h, stop), derived={"spacing": h})
    return with_method(values, srun)


def collapse_simulation(
    particles: Particles,
    model: Model,
    mesher: AlphaShapeMesher,
    values: Mapping[str, Any],
    out: Path | None,
    progress=None,
    resume: bool = False,
) -> Simulation:
    """The adaptive, checkpointed simulation of a collapse (every geometry)."""
    return Simulation(
        particles,
        model,
        mesher,
        values["dt"],
        adaptive=True,
        max_displacement=values["max_displacement"],
        writer=make_writer(out, resume),
        output_every=values["output_every"],
        checkpoint_dir=out,
        checkpoint_every=values["checkpoint_every"] if out is not None else 0,
        progress=progress,
        meta={"scene": "column-collapse", "parameters": recorded_parameters(values)},
    )


def run_control(
    values: Mapping[str, Any], H0: float
) -> tuple[dict[str, Any], AtRest | None]:
    """``run`` keywords (``t_end``, the at-rest stop) of a column of height H0."""
    run_kwargs: dict[str, Any] = {"t_end": values["t_end"]}
    stop = None
    if values["rest_fraction"] > 0:
        min_time = values["min_time"]
        if min_time is None:
            min_time = 2 * math.sqrt(H0 / values["gravity"])
        stop = run_kwargs["stop"] = AtRest(values["rest_fraction"], min_time)
    return run_kwargs, stop


def collapse_scenery(p: dict, folder: Path | None = None) -> Scenery:
    """The plane-strain collapse's scenery: rough floor, symmetry wall, Lube 2005."""
    s = Scenery(scene="column-collapse")
    a = number(p, "aspect")
    L0 = number(p, "half_width")
    if a is None or L0 is None:
        return s
    H0, g = a * L0, number(p, "gravity", GRAVITY) or GRAVITY
    s.symmetric = bool(p.get("symmetric", True))
    s.floor, s.floor_label = 0.0, "rough floor"
    s.outline = box(0.0 if s.symmetric else -L0, L0, 0.0, H0)
    if s.symmetric:
        s.walls.append((0.0, 1, "smooth wall (symmetry plane)"))
    s.runout_reference = L0 * (1.0 + lube_runout(a))
    s.runout_label = "Lube et al. 2005: L\u221e"
    s.front = partial(picture_front, symmetric=s.symmetric)
    s.tau = math.sqrt(H0 / g)
    s.label = time_label(s.tau)
    return s


SCENE = Scene(
    name="column-collapse",
    description=__doc__.strip().splitlines()[0].split(": ", 1)[1],
    params=PARAMS,
    build=build,
    metrics_doc=METRICS,
    scenery=collapse_scenery,
    derive=fill_column_defaults,
)
