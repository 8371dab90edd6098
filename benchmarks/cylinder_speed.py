#!/usr/bin/env python
"""The seed column in 3D: time per step of solver variants, measured interleaved.

Builds the ``column-collapse`` scene's quarter cylinder (the seed column of
docs/seed_column.md, spacing ``r0 / divisions``) once per variant and advances the
variants *alternately*, one step each, so that every variant sees the same
machine load (the machine is shared); each step is timed with the harness's
:class:`~_harness.Meter` (wall, process CPU, cores used by other processes).
Per variant it records every step (IPM iterations, status, the phases of
:attr:`StepRecord.timings`) and summarises s/step, IPM iterations, the share
of each phase, and how far the variant's particles end up from the first
variant's (max |dx| / r0, and the 99 % front radius): a variant that changes
the results by more than the solver tolerance shows here.

Variants (``--variants``, comma separated):

* ``base``: no strength floor (``strength_floor=0``, the former default);
* ``floor``: the default of the 3D scene (``strength_floor=1e-6``);
* ``nocnr``: ``floor`` with ``reproducible=False`` (MKL without conditional
  numerical reproducibility);
* ``fast``: ``floor`` with ``accuracy=fast`` (IPM tolerance 1e-6);
* ``fastnocnr``: both.

Every variant steps the reference paper's bare method (``--method bare``,
pinned whatever the scene's defaults); ``--method default`` steps the
geometry's stabilised, volume-keeping defaults instead.

Usage::

    python benchmarks/cylinder_speed.py --divisions 18 --steps 12 \\
        --variants base,floor --name cylinder_speed_10k
    python benchmarks/cylinder_speed.py --render benchmarks/results/X.json

Writes ``benchmarks/results/<name>.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import _harness as harness
import numpy as np

from skfem_npfem.scenes import get_scene
from skfem_npfem.scenes.collapse.cylinder import SEED, radial_front
from skfem_npfem.scenes.collapse.runs import build_geometry

VARIANTS = {
    "base": {"strength_floor": 0.0},
    "floor": {"strength_floor": 1e-6},
    "nocnr": {"strength_floor": 1e-6, "reproducible": False},
    "fast": {"strength_floor": 1e-6, "accuracy": "fast"},
    "fastnocnr": {"strength_floor": 1e-6, "accuracy": "fast", "reproducible": False},
}
R0 = SEED["radius"]
T_SCALE = math.sqrt(SEED["height"] / SEED["gravity"])


def build(geometry: str, divisions: float, variant: str, method: str = "bare"):
    """A Simulation of the seed column with a variant's solver settings."""
    over = {
        "geometry": geometry,
        "spacing": R0 / divisions,
        "rest_fraction": 0.0,
        **harness.method_overrides(geometry, method),
        **VARIANTS[variant],
    }
    return build_geometry(get_scene("column-collapse").resolve(over)).simulation


def step_record(sim, meter) -> dict:
    r = sim.records[-1]
    return {
        "step": r.step,
        "time": r.time,
        "iterations": r.iterations,
        "status": r.status,
        "retries": r.retries,
        "n_contacts": r.n_contacts,
        "wall": meter.wall,
        "cpu": meter.cpu,
        "others": meter.others,
        "timings": r.timings,
    }


def summarise(steps: list[dict]) -> dict:
    walls = np.array([s["wall"] for s in steps])
    its = np.array([s["iterations"] for s in steps])
    phases: dict[str, float] = {}
    for s in steps:
        for k, v in s["timings"].items():
            phases[k] = phases.get(k, 0.0) + v
    total = sum(phases.values())
    return {
        "steps": len(steps),
        "s_per_step_mean": float(walls.mean()),
        "s_per_step_median": float(np.median(walls)),
        "cpu_per_step_mean": float(np.mean([s["cpu"] for s in steps])),
        "others_mean": float(np.mean([s["others"] for s in steps])),
        "ipm_iterations_total": int(its.sum()),
        "ipm_iterations_mean": float(its.mean()),
        "ipm_iterations_max": int(its.max()),
        "s_per_iteration": float(walls.sum() / max(its.sum(), 1)),
        "statuses": sorted({s["status"] for s in steps}),
        "retries": int(sum(s["retries"] for s in steps)),
        "phase_share": {k: v / total for k, v in phases.items()},
    }


def run(args) -> dict:
    names = [v.strip() for v in args.variants.split(",") if v.strip()]
    sims = {v: build(args.geometry, args.divisions, v, args.method) for v in names}
    steps: dict[str, list[dict]] = {v: [] for v in names}
    for k in range(args.steps):
        for v in names:
            with harness.Meter() as m:
                sims[v].run(steps=1)
            steps[v].append(step_record(sims[v], m))
        line = "  ".join(
            f"{v}: {steps[v][-1]['iterations']} it {steps[v][-1]['wall']:.1f} s"
            for v in names
        )
        print(f"step {k + 1}: {line}", flush=True)
    ref = sims[names[0]].particles
    out = {}
    for v in names:
        p = sims[v].particles
        out[v] = {
            "settings": VARIANTS[v],
            "summary": summarise(steps[v]),
            "front_radius": radial_front(p.x, p.mass),
            "top": float(p.x[:, -1].max()),
            "max_dx_over_r0_vs_first": float(np.abs(p.x - ref.x).max() / R0),
            "steps": steps[v],
        }
    return {
        "name": args.name,
        "geometry": args.geometry,
        "method": args.method,
        "divisions": args.divisions,
        "n_particles": int(ref.n),
        "t_end": sims[names[0]].time,
        "t_bar_end": sims[names[0]].time / T_SCALE,
        "machine": harness.machine_info(),
        "variants": out,
    }


def markdown(rep: dict) -> str:
    lines = [
        f"# {rep['name']}: the seed column, {rep['geometry']}, spacing r0/"
        f"{rep['divisions']:g} ({rep['n_particles']} particles), "
        f"{next(iter(rep['variants'].values()))['summary']['steps']} steps "
        f"(t/sqrt(h0/g) = {rep['t_bar_end']:.2f}), "
        f"{rep.get('method', 'bare')} method",
        "",
        harness.code_line(rep["machine"]["code"]),
        "",
        "Variants advanced alternately, one step each (same machine load); "
        "`others`: cores used by other processes during the steps.",
        "",
        "| variant | s/step (mean) | median | CPU s/step | IPM it. total | mean | max "
        "| s/iteration | solve+setup % | mesh % | statuses | front r/r0 | "
        "max dx/r0 vs first | others |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for v, d in rep["variants"].items():
        s, ph = d["summary"], d["summary"]["phase_share"]
        solver = ph.get("solve", 0) + ph.get("setup", 0)
        lines.append(
            f"| {v} | {s['s_per_step_mean']:.3g} | {s['s_per_step_median']:.3g} | "
            f"{s['cpu_per_step_mean']:.3g} | {s['ipm_iterations_total']} | "
            f"{s['ipm_iterations_mean']:.1f} | {s['ipm_iterations_max']} | "
            f"{s['s_per_iteration']:.3g} | {100 * solver:.1f} | "
            f"{100 * ph.get('mesh', 0):.1f} | {', '.join(s['statuses'])} | "
            f"{d['front_radius'] / R0:.4f} | {d['max_dx_over_r0_vs_first']:.1e} | "
            f"{s['others_mean']:.2f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--geometry", default="quarter-cylinder")
    ap.add_argument("--divisions", type=float, default=18.0, help="r0 / spacing")
    ap.add_argument("--steps", type=int, default=12)
    ap.add_argument("--variants", default="base,floor")
    ap.add_argument("--name", default=None)
    harness.add_method_argument(ap)
    ap.add_argument("--render", default=None, help="rewrite FILE.md from FILE.json")
    args = ap.parse_args(argv)
    if args.render:
        return harness.render(args.render, markdown)
    args.name = args.name or f"cylinder_speed_{args.divisions:g}"
    t0 = time.perf_counter()
    rep = run(args)
    rep["wall_total_s"] = time.perf_counter() - t0
    path = harness.HERE / "results" / f"{args.name}.json"
    harness.write_report(Path(path), rep, markdown(rep))
    print(markdown(rep))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
