"""Runs of the column-collapse scene for the axisymmetric and 3D geometries.

:func:`build_geometry` turns resolved scene values
(:mod:`.geometry`) into a :class:`~skfem_npfem.scenes.base.SceneRun`
with the same time loop as the plane-strain scene: adaptive time step (halved
on a solver failure), VTU output and checkpoints, and the stop at rest.  A
callback records per step the run-out and the height of the main body on the
step record, :func:`~.methods.with_method` the stress roughness
(:mod:`skfem_npfem.metrics`); the metrics are computed from those
records.

:data:`COLUMN_COLLAPSE` is the scene registered as ``column-collapse``: the
plane-strain scene of :mod:`.plane_strain` extended by the ``geometry``
parameters; plane strain runs the plane-strain build unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ...constants import GRAVITY
from ...errors import warn_user
from ...laws import lajeunesse2004_runout, lube2004_runout
from ...laws import lube2005_runout as lube_runout
from ...mesh.sources import main_body
from ...run.rest import AtRest
from ...run.simulation import Simulation
from ...step.records import Step
from ..base import Scene, SceneRun
from ..common import fidelity_from, solver_from
from ..methods import with_method
from ..params import Values
from ..scenery import Scenery, box, number, time_label
from ..water import scene_water
from ..wet_soil import wet_column
from .box_column import box_column
from .cylinder import ColumnSetup, cylinder_column, mass_quantile, radial_front
from .geometry import (
    CYLINDRICAL,
    GEOMETRY_PARAMS,
    QUARTER_FIXED,
    GeometryScene,
    metrics_doc,
)
from .params import COLLAPSE_VOLUME_CORRECTION, VOLUME_CORRECTION_STRAIN
from .plane_strain import SCENE as PLANE_STRAIN
from .plane_strain import collapse_scenery, collapse_simulation, run_control
from .runout import (
    collapse_time,
    detached_fraction,
    detached_warnings,
    picture_front,
    rest_warnings,
)

__all__ = [
    "COLUMN_COLLAPSE",
    "bare_method",
    "build_geometry",
    "with_geometries",
]

#: What the masses and volumes of each geometry are of (summary ``mass_basis``).
MASS_BASIS = {
    "axisymmetric": "full ring (2 pi r weight): volumes m^3, masses kg, energies J",
    "quarter-cylinder": "the quarter x, y >= 0 (x 4 for the whole column)",
    "box": "the slab 0 <= y <= depth (per depth: divide by depth)",
}


#: Defaults of N-PFEM's stress stabilisation and volume correction for the
#: cylindrical geometries: ``(beta, stabilisation_mode, kappa)``, chosen from
#: measurements on the seed column (docs/seed_column.md, "Smooth and
#: volume-keeping by default" and "The 3D default to rest").  The 3D quarter
#: goes with the alpha-shape factor 2.0
#: (:data:`~skfem_npfem.scenes.collapse.cylinder.GEOMETRY_ALPHA`).  The reference
#: paper's bare method is ``--set stabilisation=0 --set volume_correction=0``.
CYLINDER_FIDELITY = {
    "axisymmetric": (100.0, "full", COLLAPSE_VOLUME_CORRECTION),
    "quarter-cylinder": (1000.0, "vertical", 0.15),
}


def bare_method(geometry: str) -> dict[str, Any]:
    """Scene overrides that run a column with the reference paper's bare method.

    The cylindrical geometries ran it before they defaulted to
    :data:`CYLINDER_FIDELITY`: no stabilisation, no volume correction, the
    alpha factor 1.3, and in 3D the buried slivers dropped by the alpha shape.
    Studies and benchmarks measured then pin these, so that a rerun repeats
    their committed numbers; in 3D they include
    :data:`~.geometry.QUARTER_FIXED` (the uniform lattice, tol 1e-8 and the
    paper's fixed 2 ms, which the bare method ran with).  Plane strain has its
    own defaults: empty.

    Parameters
    ----------
    geometry : str
        ``"plane-strain"``, ``"axisymmetric"``, ``"quarter-cylinder"`` or ``"box"``.

    Returns
    -------
    dict
        ``--set`` overrides of the ``column-collapse`` scene.
    """
    if geometry not in CYLINDER_FIDELITY:
        return {}
    bare: dict[str, Any] = {
        "stabilisation": 0.0,
        "volume_correction": 0.0,
        "alpha": 1.3,
    }
    if geometry == "quarter-cylinder":
        bare["buried_slivers"] = "drop"
        bare.update(QUARTER_FIXED)
    return bare


def column_setup(values: Mapping[str, Any]) -> ColumnSetup:
    """Particles, model and remesher of a resolved axisymmetric or 3D column.

    The node-mass rule, the stabilisation and the volume correction
    (``nodal_mass``, ``stabilisation``, ``stabilisation_mode``,
    ``volume_correction``) are those of the plane-strain scene with the
    defaults of :data:`CYLINDER_FIDELITY` for the cylindrical geometries (the
    volume correction where its premise holds: ``psi = 0`` and a stiff soil,
    as in plane strain); the box keeps the stabilisation off.  In
    axisymmetry the residual carries the hoop terms.
    """
    setup = _column_setup(values)
    geo = values["geometry"]
    if geo != "axisymmetric":
        setup.mesher.keep_buried_slivers = values["buried_slivers"] == "keep"
    if geo in CYLINDER_FIDELITY:
        beta, mode, kappa = CYLINDER_FIDELITY[geo]
        strain = values["rho"] * values["gravity"] * values["height"] / values["E"]
        if values["psi"] != 0.0 or strain > VOLUME_CORRECTION_STRAIN:
            kappa = 0.0
        fidelity = fidelity_from(values, beta, kappa, mode)
    else:
        fidelity = fidelity_from(values, 0.0)
    model = replace(setup.model, water=scene_water(values), **fidelity)
    height = values["height"] if geo in CYLINDRICAL else setup.particles.x[:, -1].max()
    particles = wet_column(setup.particles, model, values, height)
    return replace(setup, model=model, particles=particles)


def _column_setup(values: Mapping[str, Any]) -> ColumnSetup:
    geo = values["geometry"]
    soil = {
        k: values[k]
        for k in (
            "rho", "E", "nu", "phi", "psi", "c", "dt", "theta1", "theta2", "K0",
            "gravity", "alpha",
        )
    }  # fmt: skip
    kw = {
        "floor_friction": values["floor_friction"],
        "match": values["dp_match"] or "compression",
        "solver": replace(solver_from(values), strength_floor=values["strength_floor"]),
    }
    if geo in CYLINDRICAL:
        soil.update(radius=values["radius"], height=values["height"])
        if values["refine"] == "surface":
            kw["band"] = values["refine_band"]
        return cylinder_column(
            geo, values["spacing"], material=values["material"], **kw, **soil
        )
    L0 = values["half_width"]
    return box_column(
        soil,
        length=L0,
        height=values["aspect"] * L0,
        depth=values["depth"],
        spacing=values["spacing"],
        symmetric=values["symmetric"],
        **kw,
    )


def _front(geo: str, x: np.ndarray, mass: np.ndarray, symmetric: bool) -> float:
    """Run-out: radial 99 % mass front, or along x as in plane strain (box)."""
    if geo in CYLINDRICAL:
        return radial_front(x, mass)
    if symmetric:
        return mass_quantile(x[:, 0], mass, 0.99)
    lo, hi = (mass_quantile(x[:, 0], mass, q) for q in (0.005, 0.995))
    return 0.5 * (hi - lo)


def _recorder(values: Mapping[str, Any], h: float):
    """Callback storing the run-out and the height of the main body on each record.

    (The stress roughness is recorded by :func:`~.methods.with_method`, as for
    every method and geometry.)
    """
    geo, symmetric = values["geometry"], values["symmetric"]

    def record(sim_: Simulation, p, step: Step) -> bool:
        body = np.zeros(p.n, bool)
        body[step.active[main_body(p.x[step.active], 3.0 * h)]] = True
        extra = step.record.extra
        extra["max_height"] = float(p.x[body, -1].max()) if body.any() else math.nan
        extra["detached_mass_fraction"] = detached_fraction(p.mass, body)
        run = _front(geo, p.x, p.mass, symmetric)
        if geo in CYLINDRICAL:
            extra["runout_radius"] = run
            return False
        xb = p.x[body, 0]
        extra["runout"] = run
        extra["runout_main_body"] = float(
            xb.max() if symmetric else 0.5 * (xb.max() - xb.min())
        )
        extra["runout_tip"] = float(
            p.x[:, 0].max() if symmetric else 0.5 * np.ptp(p.x[:, 0])
        )
        return False

    return record


def _metrics(values: Mapping[str, Any], h: float, stop: AtRest | None):
    """The summary metrics of a finished run (GEOMETRY_METRICS and the shared)."""
    geo = values["geometry"]
    cyl = geo in CYLINDRICAL
    L0 = values["radius"] if cyl else values["half_width"]
    H0 = values["height"] if cyl else values["aspect"] * values["half_width"]
    key = "runout_radius" if cyl else "runout"

    def metrics(sim_: Simulation) -> dict[str, Any]:
        recs = sim_.records
        last = recs[-1].extra if recs else {}
        times = np.array([r.time for r in recs])
        runs = np.array([r.extra.get(key, np.nan) for r in recs])
        run = float(runs[-1]) if recs else L0
        top = float(last.get("max_height") or H0)
        at_rest = bool(stop is not None and stop(sim_))
        # Before rest (stopped by t_end) the front may still move: unknown.
        t_c = collapse_time(times, runs, h) if at_rest else math.nan
        summ = sim_.summary()
        detached = float(last.get("detached_mass_fraction", 0.0))
        main = None if cyl else float(last.get("runout_main_body", L0))
        notes = detached_warnings("column-collapse", detached, run, main, L0)
        for msg in notes:
            warn_user(msg)
        out: dict[str, Any] = {key: run, "normalised_runout": (run - L0) / L0}
        if cyl:
            out["reference_runout_lube2004"] = lube2004_runout(H0 / L0)
            out["reference_runout_lajeunesse2004"] = lajeunesse2004_runout(H0 / L0)
        else:
            out["runout_main_body"] = main
            out["normalised_runout_main_body"] = (main - L0) / L0
            out["runout_tip"] = float(last.get("runout_tip", L0))
            out["reference_runout_lube"] = lube_runout(values["aspect"])
        out |= {
            "final_height": top / L0,
            "height_ratio": top / H0,
            "collapse_time": t_c,
            "collapse_time_normalised": t_c / math.sqrt(H0 / values["gravity"]),
            "at_rest": at_rest,
            "warnings": [*rest_warnings(sim_, values, stop), *notes],
            "volume_change": summ["volume_change"],
            "mass_change": summ["mass_change"],
            "max_kinetic_energy": summ["max_kinetic_energy"],
            "final_kinetic_energy": float(recs[-1].kinetic_energy) if recs else 0.0,
            "n_inactive_final": int(recs[-1].n_inactive) if recs else 0,
            "n_particles": int(sim_.particles.n),
            "mass_basis": MASS_BASIS[geo],
            "detached_mass_fraction": detached,
        }
        return out

    return metrics


def build_geometry(
    values: Values, out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build an axisymmetric or 3D column-collapse run (resolved values)."""
    setup = column_setup(values)
    sim = collapse_simulation(
        setup.particles, setup.model, setup.mesher, values, out, progress, resume
    )
    h = setup.spacing
    sim.callbacks.append(_recorder(values, h))
    H0 = (
        values["height"]
        if values["geometry"] in CYLINDRICAL
        else (values["aspect"] * values["half_width"])
    )
    run_kwargs, stop = run_control(values, H0)
    # The method option (npfem only here) adds the stress roughness per step
    # and its metrics, as for plane strain.
    return with_method(values, SceneRun(sim, run_kwargs, _metrics(values, h, stop)))


#: What the plane-strain parameters mean for the other geometries (appended to
#: their help).
GEOMETRY_NOTES = {
    "aspect": "cylindrical: h0/r0, unless radius and height are both given",
    "half_width": "plane-strain and box only",
    "symmetric": "plane-strain and box only",
    "spacing": "cylindrical: default r0/18; box: L0/22",
    "material": "3D: drucker-prager only; cylindrical and box default drucker-prager",
    "dt": "axisymmetric: default 2 ms; quarter-cylinder: default up to 6 ms "
    "with max_displacement 1 (a dt given alone is fixed)",
    "accuracy": "quarter-cylinder: default fast, unless tol is given",
    "stabilisation": "axisymmetric: default 100; quarter-cylinder: default 1000; "
    "the paper's bare method: 0",
    "stabilisation_mode": "quarter-cylinder: default vertical",
    "volume_correction": "axisymmetric: default 0.05, quarter-cylinder: 0.15, "
    "where psi = 0 and rho g h0 / E <= 0.01",
    "alpha": "quarter-cylinder: default 2.0",
    "max_displacement": "not in axisymmetry; quarter-cylinder: default 1 unless "
    "dt is given",
    "refine": "quarter-cylinder: default surface; "
    "axisymmetric and quarter-cylinder: the graded lattice, the fine "
    "band along the top, the floor and the free side (the axis and the symmetry "
    "planes are no free surface), no strain; not box",
    "refine_ratio": "plane-strain only",
    "refine_share": "plane-strain only",
    "refine_merge": "plane-strain only",
}


def _annotated(param):
    note = GEOMETRY_NOTES.get(param.name)
    return param if note is None else replace(param, help=f"{param.help} ({note})")


def with_geometries(plane: Scene) -> GeometryScene:
    """The plane-strain column-collapse scene extended by ``geometry``."""

    def build(
        values: Values,
        out: Path | None = None,
        progress=None,
        resume: bool = False,
    ) -> SceneRun:
        if values["geometry"] == "plane-strain":
            return plane.build(values, out=out, progress=progress, resume=resume)
        return build_geometry(values, out, progress, resume)

    names = frozenset(p.name for p in plane.params)
    return GeometryScene(
        name=plane.name,
        description=plane.description.replace(
            "2D (plane-strain) granular column collapse",
            "Granular column collapse: plane strain, axisymmetric or 3D",
        ),
        params=[*GEOMETRY_PARAMS, *map(_annotated, plane.params)],
        build=build,
        metrics_doc=metrics_doc(plane.metrics_doc),
        plane_names=names,
        scenery=geometry_scenery,
    )


#: What the stress fields of an axisymmetric result are (the VTU slots
#: xx, yy, zz, xy hold rr, zz, theta-theta, rz).
AXISYMMETRIC_FIELDS = {
    "stress_xx": "radial stress \u03c3_rr (tension +)",
    "stress_yy": "vertical stress \u03c3_zz (tension +)",
    "stress_zz": "hoop stress \u03c3_\u03b8\u03b8 (tension +)",
    "stress_xy": "shear stress \u03c3_rz",
}


def geometry_scenery(p: dict, folder: Path | None = None) -> Scenery:
    """The collapse's scenery for its geometry (3D geometries: plane-strain's)."""
    if p.get("geometry") == "quarter-cylinder":
        s = collapse_scenery(p, folder)
        # Look at the two symmetry planes (x = 0, y = 0), where the interior
        # of the column is, and the free surface above them.
        s.view, s.floor = (-1.0, -1.4, 0.9), 0.0
        s.field_names = {"stress_zz": "vertical stress sigma_zz (tension +)"}
        r0, h0 = number(p, "radius"), number(p, "height")
        if r0 and h0:
            g = number(p, "gravity", GRAVITY) or GRAVITY
            s.tau = math.sqrt(h0 / g)
            s.label = time_label(s.tau, "h0")
        return s
    if p.get("geometry") != "axisymmetric":
        return collapse_scenery(p, folder)
    s = Scenery(scene="column-collapse")
    r0, h0 = number(p, "radius"), number(p, "height")
    if r0 is None or h0 is None:
        return s
    g = number(p, "gravity", GRAVITY) or GRAVITY
    s.floor, s.floor_label = 0.0, "rough floor"
    s.outline = box(0.0, r0, 0.0, h0)
    # The axis is no wall: the section turns about it (u_r = 0 there).
    s.symmetry, s.symmetry_label = 0.0, "axis of symmetry r = 0"
    s.axes = ("r", "z")
    s.field_names = dict(AXISYMMETRIC_FIELDS)
    s.runout_reference = r0 * (1.0 + lube2004_runout(h0 / r0))
    s.runout_label = "Lube et al. 2004: r\u221e"
    s.front = picture_front
    s.tau = math.sqrt(h0 / g)
    s.label = time_label(s.tau, "h0")
    return s


#: The registered ``column-collapse`` scene (all geometries).
COLUMN_COLLAPSE = with_geometries(PLANE_STRAIN)
