#!/usr/bin/env python
"""Which time step can I afford?  The 2D column collapse (a = 2) for several Δt.

Runs the ``column-collapse`` scene (half column, a = 2, L0 = 0.2 m,
Mohr-Coulomb phi = 30 deg, default spacing L0/22 = 1 035 particles) to rest with

* fixed time steps Δt = 1, 2, 5, 10 ms (the scene halves Δt only when the solver
  fails; ``retries`` counts those), and
* the displacement-controlled adaptive step ``max_displacement`` = 0.25 and 0.5
  (largest particle displacement per step below that fraction of the spacing),
  starting from and capped at ``--adaptive-dt-max`` (default 10 ms),

each in its own subprocess, and tabulates the normalised run-out
(L_inf - L0)/L0, the final height H_inf/L0, the collapse time, stress measures
at the end, the number of steps and IPM iterations and the wall time.

Stress measures (end of the run, compressive stress positive, normalised by
rho g H0 of the initial column):

* ``sigma_yy_max``: the largest vertical stress -sigma_yy of any particle;
* ``sigma_yy_base``: the mean -sigma_yy of the particles on the floor (y < h/2);
* ``floor_force``: the floor's total normal force / the weight (1 at rest).

Usage (from the repository root)::

    python benchmarks/dt_sweep.py                     # all configurations
    python benchmarks/dt_sweep.py --spacing-div 16 --configs dt=0.005,md=0.5
    python benchmarks/dt_sweep.py --render benchmarks/results/dt_sweep.json

Writes ``<out>/dt_sweep.json`` and ``<out>/dt_sweep.md`` (default
``benchmarks/results``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent

import _harness as harness
import _tables as docs_tables

DEFAULT_CONFIGS = "dt=0.001,dt=0.002,dt=0.005,dt=0.01,md=0.25,md=0.5"
L0, ASPECT = 0.2, 2.0


def overrides(config: str, args) -> dict:
    """``dt=0.002`` (fixed) or ``md=0.25`` (adaptive) -> scene overrides."""
    key, _, val = config.partition("=")
    ov = {
        "aspect": ASPECT,
        "half_width": L0,
        "spacing": L0 / args.spacing_div,
        "t_end": args.t_end,
        "output_every": 10**6,
        "threads": args.threads,
    }
    if args.accuracy:
        ov["accuracy"] = args.accuracy
    if args.linear_solver:
        ov["linear_solver"] = args.linear_solver
    if key == "dt":
        ov["dt"] = float(val)
    elif key == "md":
        ov["dt"] = args.adaptive_dt_max
        ov["max_displacement"] = float(val)
    else:
        raise ValueError(f"config {config!r}: use dt=<s> or md=<fraction>")
    return ov


def child(config: str, ov: dict) -> dict:
    """Run one configuration in this process."""
    import numpy as np

    from skfem_npfem.scenes import get_scene

    scene = get_scene("column-collapse")
    values = scene.resolve(ov)
    last: dict = {}  # the mesh of the last step (records keep scalars only)
    with harness.Meter() as meter:
        srun = scene.build(values, out=None, progress=False)
        sim = srun.simulation
        sim.callbacks.append(lambda s, p, step: last.update(active=step.active))
        sim.run(**srun.run_kwargs)
    m = srun.metrics(sim)
    summ = sim.summary()
    p = sim.particles
    rho, g = values["rho"], values["gravity"]
    H0 = values["aspect"] * values["half_width"]
    h = values["spacing"]
    scale = rho * g * H0
    act = np.zeros(p.n, bool)
    act[last["active"]] = True
    syy = -p.stress[:, 1]
    base = act & (p.x[:, 1] < 0.5 * h)
    dts = np.array([r.dt for r in sim.records])
    weight = float(p.mass.sum()) * g
    return {
        "config": config,
        "overrides": ov,
        "particles": int(p.n),
        "normalised_runout": m["normalised_runout"],
        "final_height": m["final_height"],
        "collapse_time": m["collapse_time"],
        "collapse_time_normalised": m["collapse_time_normalised"],
        "at_rest": m["at_rest"],
        "end_time": sim.time,
        "volume_change": m["volume_change"],
        "n_inactive_final": m["n_inactive_final"],
        "sigma_yy_max": float(syy[act].max() / scale),
        "sigma_yy_base": float(syy[base].mean() / scale) if base.any() else None,
        "floor_force": float(p.wall_force[:, 0].sum() / weight),
        "steps": summ["steps"],
        "retries": summ["retries"],
        "dt_min": float(dts.min()),
        "dt_max": float(dts.max()),
        "dt_mean": float(dts.mean()),
        "ipm_iterations_total": summ["ipm_iterations_total"],
        "ipm_iterations_mean": summ["ipm_iterations_mean"],
        "statuses": summ["statuses"],
        "linear_solvers": summ["linear_solvers"],
        "step_time_median": summ["step_time_median"],
        "wall_s": meter.wall,
        "cpu_s": meter.cpu,
        "peak_memory_mb": summ["peak_memory_mb"],
        "loadavg_before": meter.load_before,
        "loadavg_after": os.getloadavg()[0],
        "other_cores": meter.others,
    }


def run_one(config: str, args) -> dict:
    ov = overrides(config, args)
    if args.wait_idle > 0:
        harness.wait_for_idle(args.wait_idle, args.wait_max)
    res, note, wall, _ = harness.run_child(
        Path(__file__).resolve(),
        ["--child", json.dumps({"config": config, "ov": ov})],
        args.timeout,
    )
    if res is None:
        return {"config": config, "overrides": ov, "note": note}
    res["subprocess_s"] = wall
    return res


def label(config: str) -> str:
    key, _, val = config.partition("=")
    if key == "dt":
        return f"Δt = {1000 * float(val):g} ms"
    return f"adaptive, max_displacement = {val}"


def fmt(v, f):
    return (
        "—" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, f)
    )


def markdown(report: dict) -> str:
    s = report["settings"]
    lines = [
        "# Column collapse (a = 2): time-step sweep",
        "",
        f"{report.get('machine', '')}",
        "",
        f"Spacing L0/{s['spacing_div']:g} ({report['runs'][0].get('particles', '?')} "
        f"particles), run to rest (kinetic energy < 1e-3 of its maximum after "
        f"2 sqrt(H0/g)), cap t_end = {s['t_end']:g} s; solver: "
        f"{s.get('accuracy') or 'default preset'}, backend "
        f"{s.get('linear_solver') or 'auto'}; adaptive runs start at and are capped by "
        f"Δt = {1000 * s['adaptive_dt_max']:g} ms.  Stresses at the end, over "
        "rho g H0.  `wall` = build + run (s); `cpu` = process CPU time; `load` = "
        "1-min load average before-after; `others` = mean cores used by other "
        "processes during the run (2 cores; > 0.25: the wall time is inflated).",
        "",
        "| time step | (L_inf-L0)/L0 | H_inf/L0 | t_collapse (s) | at rest (t) | "
        "σ_yy max | σ_yy base | floor force / weight | volume change | steps | "
        "Δt min-max (ms) | IPM it. | it./step | wall s | cpu s | s/step | load "
        "| others |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in report["runs"]:
        if "note" in r:
            lines.append(f"| {label(r['config'])} | {r['note'][:100]} |")
            continue
        lines.append(
            f"| {label(r['config'])} | {r['normalised_runout']:.3f} | "
            f"{r['final_height']:.3f} | {fmt(r['collapse_time'], '.3f')} | "
            f"{'yes' if r['at_rest'] else 'no'} ({r['end_time']:.3f}) | "
            f"{r['sigma_yy_max']:.3f} | {fmt(r['sigma_yy_base'], '.3f')} | "
            f"{r['floor_force']:.3f} | {r['volume_change']:+.3f} | {r['steps']}"
            + (f" ({r['retries']} retries)" if r["retries"] else "")
            + f" | {1000 * r['dt_min']:.2g}-{1000 * r['dt_max']:.2g} | "
            f"{r['ipm_iterations_total']} | {r['ipm_iterations_mean']:.1f} | "
            f"{r['wall_s']:.1f} | {r['cpu_s']:.1f} | {r['step_time_median']:.3f} | "
            f"{r['loadavg_before']:.1f}-{r['loadavg_after']:.1f} | "
            f"{r.get('other_cores', math.nan):.2f} |"
        )
    lines.append("")
    return "\n".join(lines)


# ---------------------------------------------------------------------------
# The tables of the docs pages, rendered from the committed JSON (--tables).

TABLES: docs_tables.Tables = {}
docs_table = docs_tables.registry(TABLES)


@docs_table(f"{docs_tables.RESULTS}/dt_sweep.json")
def dt_sweep() -> str:
    """The default collapse to rest against the time step (benchmarks/dt_sweep.py)."""
    out = []
    for r in docs_tables.load(f"{docs_tables.RESULTS}/dt_sweep.json")["runs"]:
        key, _, value = r["config"].partition("=")
        if key == "dt":
            label = f"Δt = {1e3 * float(value):g} ms"
        else:
            label = f"adaptive, `max_displacement={value}`"
        out.append(
            [
                label,
                docs_tables.num(r["normalised_runout"]),
                docs_tables.num(r["final_height"]),
                docs_tables.num(r["collapse_time"]),
                docs_tables.num(r["sigma_yy_base"]),
                docs_tables.pct(r["volume_change"]),
                r["steps"],
                f"{r['wall_s']:.0f}",
            ]
        )
    return docs_tables.md(
        [
            "time step",
            "(L∞−L0)/L0",
            "H∞/L0",
            "collapse time (s)",
            "σ_yy at the base",
            "volume change",
            "steps",
            "wall (s)",
        ],
        out,
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--configs", default=DEFAULT_CONFIGS)
    ap.add_argument("--spacing-div", type=float, default=22.0, help="spacing = L0/div")
    ap.add_argument("--t-end", type=float, default=3.0, help="safety cap (s)")
    ap.add_argument("--adaptive-dt-max", type=float, default=0.01)
    ap.add_argument("--accuracy", choices=("high", "fast"), default=None)
    ap.add_argument("--linear-solver", default=None)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="parallel runs (wall times then compete for the cores)",
    )
    ap.add_argument("--timeout", type=float, default=7200.0)
    ap.add_argument(
        "--wait-idle",
        type=float,
        default=0.0,
        help="before each run wait until other processes use fewer cores than this",
    )
    ap.add_argument("--wait-max", type=float, default=1800.0)
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--name", default="dt_sweep")
    ap.add_argument("--render", metavar="FILE.json")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    args = ap.parse_args(argv)
    if args.tables:
        return docs_tables.write(TABLES)
    if args.child:
        d = json.loads(args.child)
        harness.emit_result(child(d["config"], d["ov"]))
        return 0
    if args.render:
        return harness.render(args.render, markdown)
    import platform

    import clarabel
    import numpy

    machine = (
        f"Python {platform.python_version()}, numpy {numpy.__version__}, clarabel "
        f"{clarabel.__version__}, {os.cpu_count()} cores; "
        f"{time.strftime('%Y-%m-%dT%H:%M:%S%z')}."
    )
    configs = [c for c in args.configs.split(",") if c]
    report = {
        "machine": machine,
        "settings": {
            "spacing_div": args.spacing_div,
            "t_end": args.t_end,
            "adaptive_dt_max": args.adaptive_dt_max,
            "accuracy": args.accuracy,
            "linear_solver": args.linear_solver,
            "threads": args.threads,
            "jobs": args.jobs,
            "niceness": os.nice(0),
        },
        "runs": [],
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{args.name}.json"
    results: dict[str, dict] = {}

    def work(c):
        print(f"{c} ... (load {os.getloadavg()[0]:.2f})", flush=True)
        r = run_one(c, args)
        results[c] = r
        report["runs"] = [results[k] for k in configs if k in results]
        harness.write_report(path, report, markdown(report))
        if "note" in r:
            print(f"{c}: {r['note']}", flush=True)
        else:
            print(
                f"{c}: runout {r['normalised_runout']:.3f}, H {r['final_height']:.3f}, "
                f"steps {r['steps']}, wall {r['wall_s']:.1f} s",
                flush=True,
            )

    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        list(pool.map(work, configs))
    print(markdown(report))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
