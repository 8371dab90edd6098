#!/usr/bin/env python
"""The 3D seed column at r0/8 to t_bar = 3: the default against the bare method.

The quick guard of the 3D column's speed.  The quarter cylinder of the seed
column (r0 = 3.9 cm, a = 2, the paper's dt = 2 ms) at spacing r0/8 (986
particles) is run to ``t_bar = t / sqrt(h0/g) = 3`` with the reference
paper's bare method at the paper's settings (no stabilisation, no volume
correction, alpha 1.3, buried slivers dropped, the uniform lattice, tolerance
1e-8, fixed 2 ms steps) and with the geometry's defaults of today (stabilised,
volume-keeping, with the quarter's speed defaults: a graded lattice, the fast
preset, steps of up to 6 ms within one spacing of motion), one after the other
in this process, so that both see the same machine.  For each run:
the wall time, the steps and interior-point iterations, the largest stress
roughness R over the written steps, the volume change and the normalised
run-out at t_bar = 3.  The default's wall time over the bare method's is
printed (the figure the speed work is judged by).

``--variant NAME=JSON`` adds a run with the default plus the scene overrides
``JSON`` (a lever: ``--variant md25='{"max_displacement": 0.25}'``; the
default before its speed levers: ``--variant fixed='{"refine": "none", "tol":
1e-8, "dt": 0.002}'``), run in
the same process after the two; ``--only`` runs only the variants named.

Usage (repository root)::

    python benchmarks/column3d_guard.py                 # about 4 minutes
    python benchmarks/column3d_guard.py --divisions 6   # coarser, quicker
    python benchmarks/column3d_guard.py \\
        --variant fast='{"accuracy": "fast"}' --out /tmp/levers.json

Writes ``benchmarks/results/column3d_guard.json`` and ``.md`` (or ``--out``).
``--plot PNG`` draws R max against the wall time of every run over the
unstabilised one (a variant named ``beta0``, else the bare method), the
default marked (``--plot-from JSON`` draws it from a report without running).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
import warnings
from pathlib import Path
from typing import Any

import _harness as harness

from skfem_npfem.constants import GRAVITY
from skfem_npfem.scenes import run_scene
from skfem_npfem.scenes.collapse.runs import bare_method

OUT = Path(__file__).resolve().parent / "results" / "column3d_guard.json"
#: The seed column (the paper's): radius and height, m.
R0, H0 = 0.039, 0.078
#: The run's end: t_bar = 3.
T3 = 3.0 * math.sqrt(H0 / GRAVITY)


def run_case(overrides: dict[str, Any]) -> dict[str, Any]:
    """One column run to t_bar = 3; its figures and the machine's other load."""
    busy0, cpu0, t0 = harness.cpu_busy_s(), time.process_time(), time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # not at rest at t_bar = 3: expected
        summary = run_scene("column-collapse", overrides)
    wall = time.perf_counter() - t0
    own = time.process_time() - cpu0
    other = (harness.cpu_busy_s() - busy0 - own) / wall
    m, solver = summary["metrics"], summary["solver"]
    return {
        "overrides": overrides,
        "wall_s": wall,
        "other_cores": max(other, 0.0),
        "n_particles": m["n_particles"],
        "steps": solver["steps"],
        "ipm_iterations_total": solver["ipm_iterations_total"],
        "step_time_median_s": solver["step_time_median"],
        "stress_roughness_max": m["stress_roughness_max"],
        "volume_change": m["volume_change"],
        "normalised_runout": m["normalised_runout"],
        "linear_solvers": solver["linear_solvers"],
    }


def markdown(report: dict[str, Any]) -> str:
    """The report as a Markdown table, each wall time over the bare method's."""
    cases = report["cases"]
    bare = cases.get("bare", {}).get("wall_s")
    lines = [
        f"3D seed column, quarter cylinder at r0/{report['divisions']}, to "
        "t_bar = 3 (one process, one run after the other)",
        "",
        "| run | particles | steps | IPM it. | wall, s | / bare | other cores "
        "| R max | volume | run-out / r0 |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, c in cases.items():
        ratio = "" if bare is None else f"{c['wall_s'] / bare:.2f}"
        r = c["stress_roughness_max"]
        r = "-" if r is None else f"{r:.3f}"
        lines.append(
            f"| {name} | {c['n_particles']} | {c['steps']} | "
            f"{c['ipm_iterations_total']} | {c['wall_s']:.0f} | {ratio} | "
            f"{c['other_cores']:.2f} | {r} | "
            f"{100 * c['volume_change']:+.2f} % | {c['normalised_runout']:.3f} |"
        )
    lines += ["", harness.code_line(report["machine"]["code"])]
    return "\n".join(lines) + "\n"


def plot(report: dict[str, Any], path: Path) -> None:
    """R max against wall time over the unstabilised run, the default marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = report["cases"]
    ref = cases.get("beta0", cases.get("bare"))
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for name, c in cases.items():
        if c["stress_roughness_max"] is None:
            continue
        x, y = c["wall_s"] / ref["wall_s"], c["stress_roughness_max"]
        style = ("*", 14, "C3") if name == "default" else ("o", 7, "C0")
        ax.plot(x, y, style[0], ms=style[1], color=style[2])
        label = "default" if name == "default" else name
        ax.annotate(label, (x, y), textcoords="offset points", xytext=(5, 4))
    ax.axhline(0.10, color="k", lw=0.8, ls="--", label="R = 0.10")
    ax.set_yscale("log")
    ax.set_xlabel("wall time to t_bar = 3, x the unstabilised run")
    ax.set_ylabel("stress roughness R max over the run")
    ax.set_title(f"3D quarter cylinder, r0/{report['divisions']}: smoothness and cost")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--divisions", type=int, default=8, help="r0 / spacing")
    ap.add_argument("--variant", action="append", default=[], metavar="NAME=JSON")
    ap.add_argument("--only", default=None, help="comma-separated runs to run")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--threads", type=int, default=1, help="OMP threads")
    ap.add_argument("--plot", type=Path, default=None, help="PNG of R against cost")
    ap.add_argument("--plot-from", type=Path, default=None, help="a report to draw")
    args = ap.parse_args(argv)
    if args.plot_from is not None:
        if args.plot is None:
            ap.error("--plot-from needs --plot PNG")
        plot(json.loads(args.plot_from.read_text()), args.plot)
        return {}
    os.environ.setdefault("OMP_NUM_THREADS", str(args.threads))
    base = {"geometry": "quarter-cylinder", "spacing": R0 / args.divisions}
    base["t_end"] = T3
    runs = {"bare": {**base, **bare_method("quarter-cylinder")}, "default": base}
    for text in args.variant:
        name, _, over = text.partition("=")
        if not name or not over:
            ap.error(f"--variant {text!r}: expected NAME=JSON")
        runs[name] = {**base, **json.loads(over)}
    if args.only:
        runs = {k: v for k, v in runs.items() if k in args.only.split(",")}
    report: dict[str, Any] = {
        "divisions": args.divisions,
        "t_end": T3,
        "machine": harness.machine_info(),
        "idle_before": harness.wait_for_idle(0.3, 120.0),
        "cases": {},
    }
    for name, over in runs.items():
        report["cases"][name] = run_case(over)
        print(name, json.dumps(report["cases"][name]), flush=True)
    cases = report["cases"]
    if "bare" in cases and "default" in cases:
        ratio = cases["default"]["wall_s"] / cases["bare"]["wall_s"]
        report["default_over_bare"] = ratio
        print(f"default / bare wall time: {report['default_over_bare']:.2f}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    harness.write_report(args.out, report, markdown(report))
    print(markdown(report))
    if args.plot is not None:
        plot(report, args.plot)
    return report


if __name__ == "__main__":
    main()
