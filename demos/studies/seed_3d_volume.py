#!/usr/bin/env python
"""Where the 3D seed column's volume goes, and the 3D default that keeps it.

The 3D quarter of the seed column (``column-collapse --set
geometry=quarter-cylinder``) run to rest with the speed levers
(``accuracy=fast``, dt = 4 ms), at r0/8 for the screening and at r0/12 for the
chosen default.  Each case is one scene run with one extra callback, which
keeps at every step the volume budget of the particles:

* ``mesh``: the step's alpha-shape mesh volume over what the particles carry,
  ``V_ref = sum m / rho`` (all particles);
* ``alpha_*``: the end-of-step particle cloud remeshed with the alpha factors
  1.3, 1.6, 2.0 and 3.0, over ``V_ref`` (what the alpha test alone drops);
* ``inactive``: the mass fraction of particles in no element (detached);
* ``interior`` and ``boundary``: the cells of the particles off and on the
  boundary of the run's own alpha shape over their ``m / rho`` (below 1: the
  particles are closer packed than their masses say);
* ``R``: the stress roughness of sigma_v (the scene's per-step metric).

The run summaries and the budgets stay in ``--work``; a case whose summary is
there is not run again.  ``--out`` (default ``docs/seed_column``) receives
``volume_3d.json`` (cases not run again are kept as they are): per case the
overrides, R at rest and its maximum, R per step, the volume change, run-out,
height, detached mass, steps, interior-point iterations, wall time and the
budget at rest (docs/seed_column.md, "Where the
3D volume goes" and "The 3D default to rest").

Usage::

    python demos/studies/seed_3d_volume.py --cases r8-default-before,r8-alpha-2.0
    python demos/studies/seed_3d_volume.py            # every case (about 1 h)
    python demos/studies/seed_3d_volume.py --cases r12-slivers-beta-1000 \\
        --picture r12-slivers-beta-1000   # the 3D default, its sigma_v picture
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from _common import ROOT, WORK

from skfem_npfem.mesh.delaunay import alpha_shape
from skfem_npfem.scenes import get_scene
from skfem_npfem.scenes.collapse.runs import CYLINDER_FIDELITY

R0 = 0.039
OUT = ROOT / "docs" / "seed_column"
ALPHAS = (1.3, 1.6, 2.0, 3.0)
#: Every case: the quarter with both speed levers, one thread, to rest.
#: (measured on the uniform lattice, before the quarter's graded default)
BASE = {
    "geometry": "quarter-cylinder",
    "accuracy": "fast",
    "dt": 4e-3,
    "refine": "none",
    "threads": 1,
}
#: The measured default before: alpha 1.3, beta 30, mode mean, kappa 0.
BEFORE = {"alpha": 1.3, "stabilisation_mode": "mean", "volume_correction": 0.0}
#: What every case before the sliver cases ran with (the 3D defaults of that
#: time: beta 30, buried slivers dropped from the mesh).
THEN = {"stabilisation": 30.0, "buried_slivers": "drop"}
VERT = "vertical"


def _r8(**o: Any) -> dict[str, Any]:
    return {**BASE, "spacing": R0 / 8, **BEFORE, **THEN, **o}


#: name -> scene overrides.
CASES: dict[str, dict[str, Any]] = {
    "r8-default-before": _r8(),
    "r8-alpha-1.6": _r8(alpha=1.6),
    "r8-alpha-2.0": _r8(alpha=2.0),
    "r8-vertical": _r8(stabilisation_mode=VERT),
    "r8-kappa-0.1": _r8(volume_correction=0.1),
    "r8-kappa-0.2": _r8(volume_correction=0.2),
    "r8-alpha-2.0-kappa-0.1": _r8(alpha=2.0, volume_correction=0.1),
    "r8-vertical-alpha-2.0-kappa-0.1": _r8(
        alpha=2.0, stabilisation_mode=VERT, volume_correction=0.1
    ),
    "r8-vertical-alpha-2.0-kappa-0.2": _r8(
        alpha=2.0, stabilisation_mode=VERT, volume_correction=0.2
    ),
    "r8-vertical-alpha-2.0-kappa-0.15": _r8(
        alpha=2.0, stabilisation_mode=VERT, volume_correction=0.15
    ),
    # sigma_v alone coupled (the cheaper factor), otherwise the default.
    "r8-sigma-v-alpha-2.0-kappa-0.15": _r8(
        alpha=2.0, stabilisation_mode="sigma_v", volume_correction=0.15
    ),
    # The scene's 3D default then (alpha 2.0, vertical, beta 30, kappa 0.15).
    "r12-default": {**BASE, "spacing": R0 / 12, "output_every": 1, **THEN},
    # The default with a larger factor (the axisymmetric default's beta).
    "r8-beta-100": _r8(
        alpha=2.0, stabilisation_mode=VERT, volume_correction=0.15,
        stabilisation=100.0, threads=2,
    ),
    "r12-beta-100": {**BASE, "spacing": R0 / 12, "output_every": 1, **THEN,
                     "stabilisation": 100.0, "threads": 2},
    # Buried slivers meshed (the conforming 3D mesh), beta 30 to 1000
    # (r12-slivers-beta-1000: today's 3D default).
    "r8-slivers": {**BASE, "spacing": R0 / 8, "output_every": 1,
                   "stabilisation": 30.0},
    "r8-slivers-beta-100": {**BASE, "spacing": R0 / 8, "output_every": 1,
                            "stabilisation": 100.0},
    "r12-slivers-beta-100": {**BASE, "spacing": R0 / 12, "output_every": 1,
                             "stabilisation": 100.0},
    "r12-slivers-beta-300": {**BASE, "spacing": R0 / 12, "output_every": 1,
                             "stabilisation": 300.0},
    "r12-slivers-beta-1000": {**BASE, "spacing": R0 / 12, "output_every": 1},
}  # fmt: skip


def _cell_volumes(x: np.ndarray, simplices: np.ndarray) -> np.ndarray:
    """A quarter of the volume of every tetrahedron at each of its vertices."""
    a, b, c, d = (x[simplices[:, i]] for i in range(4))
    v = np.abs(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)) / 6.0
    w = np.repeat(v / 4.0, 4)
    return np.bincount(simplices.ravel(), weights=w, minlength=x.shape[0])


def budget_recorder(values: dict[str, Any], rows: list[dict[str, float]]):
    """A scene callback appending the volume budget of each step to ``rows``."""
    rho, h, alpha = values["rho"], values["spacing"], values["alpha"]

    def record(sim, p, step) -> bool:
        m = p.mass
        vref = m.sum() / rho
        active = np.zeros(p.n, bool)
        active[step.active] = True
        row = {
            "step": sim.step,
            "time": sim.time,
            "mesh": step.record.mesh_volume / vref,
            "inactive": float(m[~active].sum() / m.sum()),
            "R": step.record.extra.get("stress_roughness", float("nan")),
        }
        for a in ALPHAS:
            tri = alpha_shape(p.x, h, a)
            row[f"alpha_{a}"] = tri.volume / vref
            if a == alpha:
                vi = _cell_volumes(p.x, tri.simplices)
                inner = tri.active & ~tri.boundary
                edge = tri.active & tri.boundary
                row["interior"] = float(vi[inner].sum() / (m[inner].sum() / rho))
                row["boundary"] = float(vi[edge].sum() / (m[edge].sum() / rho))
                row["interior_mass"] = float(m[inner].sum() / m.sum())
        rows.append(row)
        return False

    return record


def run_case(name: str, work: Path) -> dict[str, Any]:
    """Run one case unless its files are in ``work``; its compact record."""
    folder = work / name
    summary, budget = folder / "summary.json", folder / "budget.json"
    if not (summary.exists() and budget.exists()):
        scene = get_scene("column-collapse")
        rows: list[dict[str, float]] = []

        def build(values, out=None, progress=None, resume=False):
            srun = scene.build(values, out=out, progress=progress, resume=resume)
            srun.simulation.callbacks.append(budget_recorder(values, rows))
            return srun

        folder.mkdir(parents=True, exist_ok=True)
        replace(scene, build=build).run(
            CASES[name], out=folder, summary=summary, progress=False
        )
        budget.write_text(json.dumps(rows))
    return compact(
        json.loads(summary.read_text()), json.loads(budget.read_text()), CASES[name]
    )


def settings(params: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """alpha, beta, mode, kappa and the sliver rule of a case (3D defaults)."""
    beta, mode, kappa = CYLINDER_FIDELITY["quarter-cylinder"]
    out = {
        "alpha": params["alpha"],
        "stabilisation": beta,
        "stabilisation_mode": mode,
        "volume_correction": kappa,
        "buried_slivers": "keep",
    }
    out.update({k: v for k, v in overrides.items() if k in out})
    return out


def _num(x: float | None) -> float | None:
    """Rounded, None for a missing or NaN value (R of too few interior nodes)."""
    return None if x is None or not np.isfinite(x) else round(float(x), 4)


def compact(
    summary: dict[str, Any], rows: list[dict[str, float]], overrides: dict[str, Any]
) -> dict[str, Any]:
    """What docs/seed_column.md quotes from one case."""
    m, s, p = summary["metrics"], summary["solver"], summary["parameters"]
    last = rows[-1]
    return {
        "spacing": p["spacing"],
        "settings": settings(p, overrides),
        "particles": m["n_particles"],
        "steps": s["steps"],
        "ipm_mean": round(s["ipm_iterations_mean"], 2),
        "ipm_max": s["ipm_iterations_max"],
        "ipm_total": s["ipm_iterations_total"],
        "wall_s": round(summary["wall_time_total"], 1),
        "at_rest": m["at_rest"],
        "R_at_rest": _num(m["stress_roughness"]),
        "R_max": m["stress_roughness_max"],
        "volume_change": m["volume_change"],
        "normalised_runout": m["normalised_runout"],
        "final_height": m["final_height"],
        "detached_mass_fraction": m["detached_mass_fraction"],
        "budget_at_rest": {k: round(v, 4) for k, v in last.items() if k != "R"},
        "R_per_step": [_num(row["R"]) for row in rows],
        "mesh_per_step": [round(row["mesh"], 4) for row in rows],
    }


def main(argv: list[str] | None = None) -> int:
    """Run the chosen cases (all by default) and write volume_3d.json."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES), help="comma-separated")
    ap.add_argument("--work", type=Path, default=WORK / "seed_3d_volume")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument(
        "--picture",
        default="",
        help="a finished case whose vertical stress at t_bar = 0, 1, 2, 3 goes "
        "to <out>/sigma_v_3d_<case>.png",
    )
    args = ap.parse_args(argv)
    names = [c for c in args.cases.split(",") if c]
    bad = [c for c in names if c not in CASES]
    if bad:
        raise SystemExit(
            f"error: --cases: unknown case {bad[0]!r}; one of {list(CASES)}"
        )
    for name in names:
        run_case(name, args.work)
    done = [n for n in CASES if (args.work / n / "budget.json").exists()]
    records = {n: run_case(n, args.work) for n in done}
    for n, r in records.items():
        rest = r["R_at_rest"]
        print(
            f"{n}: R {float('nan') if rest is None else rest:.3f} / "
            f"{r['R_max']:.3f}, volume {100 * r['volume_change']:+.1f} %, "
            f"run-out {r['normalised_runout']:.3f}"
        )
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "volume_3d.json"
    # Cases run before, whose work folders are gone, stay as they were.
    kept = json.loads(path.read_text())["cases"] if path.exists() else {}
    for n, rec in kept.items():  # records older than the sliver rule's setting
        if n in CASES:
            rule = CASES[n].get("buried_slivers", "keep")
            rec["settings"].setdefault("buried_slivers", rule)
    records = {n: records.get(n, kept.get(n)) for n in CASES if n in {*records, *kept}}
    path.write_text(json.dumps({"cases": records}, indent=1, default=float) + "\n")
    print("wrote", path)
    if args.picture:
        from seed_defaults import snapshot_row

        folder = args.work / args.picture
        file = args.out / f"sigma_v_3d_{args.picture}.png"
        tmp = args.work / "plots" / args.picture
        print("wrote", snapshot_row(folder, "stress_zz", (0, 1, 2, 3), file, tmp))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
