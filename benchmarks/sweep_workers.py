"""Wall time of one 8-run sweep on a local Dask cluster with 1 and 2 workers.

The sweep (docs/sweep.md): ``column-collapse`` at spacing 0.02 m (L0/10), aspect
ratio 1 and 2 x friction angle 25, 30, 35, 40 degrees, each run to rest (a few
seconds each).  The same sweep runs with 1 and 2 workers back to back, in the
order 1, 2, 2, 1 (``--rounds 2``) so that a drift of the machine's load hits
both alike; every sweep starts from an empty folder, so the wall time includes
starting and stopping the cluster.  Also recorded: the sum of the runs' own
wall times (the serial work), the solver threads per run the sweep chose, and
the cores other processes kept busy meanwhile (the machine may be shared).

Usage (from the repository root)::

    PYTHONPATH=. python benchmarks/sweep_workers.py            # writes results/
    PYTHONPATH=. python benchmarks/sweep_workers.py --rounds 1 --out /tmp/b
    python benchmarks/sweep_workers.py --render benchmarks/results/sweep_workers.json
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

import _harness as harness

SCENE = "column-collapse"
GRID = {"aspect": [1.0, 2.0], "phi": [25.0, 30.0, 35.0, 40.0]}
FIXED = {"spacing": 0.02}


def one_sweep(workers: int) -> dict:
    """Run the sweep once with ``workers`` local workers; its record."""
    from skfem_npfem import sweep

    busy0, cpu0, kids0 = harness.cpu_busy_s(), time.process_time(), _children_cpu()
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="sweep_workers_") as tmp:
        t0 = time.perf_counter()
        table = sweep(
            SCENE, GRID, fixed=FIXED, out=tmp, workers=workers, progress=False
        )
        wall = time.perf_counter() - t0
    busy = (harness.cpu_busy_s() - busy0) / wall
    # The worker processes (children of the nannies, our children) are waited
    # for when the cluster stops, so their CPU time is in RUSAGE_CHILDREN.
    ours = time.process_time() - cpu0 + _children_cpu() - kids0
    threads = sorted(set(table["threads"].astype(int)))
    return {
        "workers": workers,
        "wall_s": wall,
        "runs": len(table),
        "failed": int((table["status"] != "ok").sum()),
        "sum_run_wall_s": float(table["wall_time_total"].sum()),
        "steps_total": int(table["solver.steps"].sum()),
        "particles": sorted(set(table["n_particles"].astype(int))),
        "solver_threads_per_run": threads,
        "busy_cores_all_processes": busy,
        "cpu_s_this_sweep": ours,
        "busy_cores_other_processes": max(busy - ours / wall, 0.0),
        "load_1min_before": load,
    }


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def markdown(report: dict) -> str:
    """The Markdown table of a report."""
    m = report["machine"]
    lines = [
        "# Sweep wall time: 1 vs 2 local Dask workers",
        "",
        f"`benchmarks/sweep_workers.py`: {report['sweep']}.",
        "",
        f"Machine: {m['cpu']}, {m['cores_available']} cores available, "
        f"{m['memory_gb']} GB; Python {m['python']}, dask {report['dask']}; "
        f"{m['date']}.  **The machine was shared with other sessions** "
        "(other cores: the cores other processes kept busy during the sweep, "
        "from /proc/stat minus this sweep's CPU time; 2.0 would mean both).",
        "",
        "| order | workers | solver threads/run | wall (s) | sum of run walls (s) "
        "| CPU of the sweep (s) | cores the sweep got | other cores | load before |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for i, r in enumerate(report["sweeps"], 1):
        lines.append(
            f"| {i} | {r['workers']} | {r['solver_threads_per_run']} "
            f"| {r['wall_s']:.1f} | {r['sum_run_wall_s']:.1f} "
            f"| {r.get('cpu_s_this_sweep', float('nan')):.1f} "
            f"| {r.get('cpu_s_this_sweep', float('nan')) / r['wall_s']:.2f} "
            f"| {r.get('busy_cores_other_processes', float('nan')):.2f} "
            f"| {r['load_1min_before']:.2f} |"
        )
    s = report["summary"]
    lines += [
        "",
        f"Mean wall time: {s['wall_1_worker_s']:.1f} s with 1 worker, "
        f"{s['wall_2_workers_s']:.1f} s with 2 workers (speed-up "
        f"{s['speedup']:.2f}x).  A sweep can only go faster with a second worker "
        "if it gets a second core: 'cores the sweep got' (its CPU time over its "
        "wall time) says how much of the machine it had.",
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=2, help="1: order 1, 2; 2: 1,2,2,1")
    ap.add_argument("--out", type=Path, default=HERE / "results")
    ap.add_argument(
        "--wait-load",
        type=float,
        default=None,
        help="before each sweep wait (at most 10 min) for a 1-min load below this",
    )
    ap.add_argument("--render", help="rewrite the .md of this JSON report")
    args = ap.parse_args(argv)
    if args.render:
        return harness.render(args.render, markdown)
    import dask

    order = [1, 2] if args.rounds == 1 else [1, 2, 2, 1] * (args.rounds // 2)
    sweeps = []
    for workers in order:
        if args.wait_load is not None:
            harness.wait_for_quiet(args.wait_load, 600.0)
        rec = one_sweep(workers)
        print(
            f"{workers} worker(s): {rec['wall_s']:.1f} s "
            f"(runs {rec['sum_run_wall_s']:.1f} s, "
            f"CPU {rec['cpu_s_this_sweep']:.1f} s, other processes "
            f"{rec['busy_cores_other_processes']:.2f} cores)",
            flush=True,
        )
        sweeps.append(rec)

    def mean(n: int) -> float:
        walls = [r["wall_s"] for r in sweeps if r["workers"] == n]
        return sum(walls) / len(walls)

    report = {
        "benchmark": "sweep_workers",
        "sweep": f"{SCENE}, grid {GRID}, fixed {FIXED}: 8 runs to rest",
        "dask": dask.__version__,
        "machine": harness.machine_info(),
        "sweeps": sweeps,
        "summary": {
            "wall_1_worker_s": mean(1),
            "wall_2_workers_s": mean(2),
            "speedup": mean(1) / mean(2),
        },
    }
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "sweep_workers.json"
    harness.write_report(path, report, markdown(report))
    print(markdown(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
