#!/usr/bin/env python
"""The volume correction (``volume_correction = kappa``) on the column collapse.

Runs the ``column-collapse`` scene (plane strain, the scene's defaults
otherwise: node masses, beta = 30, alpha = 1.3, dt = 5 ms, to rest) for each
``kappa`` of ``--kappas`` at the default resolution, and the aspect-ratio sweep
a = 0.5 / 1 / 2 / 4 / 8 at 12 particles across L0 for ``kappa = 0`` and
``--sweep-kappa``.  Reported per run: the mesh-volume change at the end, the
normalised run-out, the final height, the stress roughness R at rest and its
maximum, the number of steps and the median step time (every run in this
process pool, so the step times share one machine load).

Usage (repository root)::

    python demos/volume_correction.py                 # kappa 0, 0.03, 0.1, 0.3
    python demos/volume_correction.py --kappas 0,0.1 --sweep-kappa 0.1 --workers 2

Writes ``docs/validation/volume_correction.json`` and prints Markdown tables.
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "validation" / "volume_correction.json"
ASPECTS = (0.5, 1.0, 2.0, 4.0, 8.0)
LENGTH = 0.2


def run(overrides: dict[str, Any]) -> dict[str, Any]:
    """One scene run to rest; its metrics and step times."""
    from skfem_npfem.scenes import get_scene

    scene = get_scene("column-collapse")
    values = scene.resolve({**overrides, "threads": 1})
    srun = scene.build(values, out=None, progress=False)
    sim = srun.simulation
    t0 = time.perf_counter()
    sim.run(**srun.run_kwargs)
    m = srun.metrics(sim)
    steps = [sum(r.timings.values()) for r in sim.records]
    return {
        "overrides": overrides,
        "particles": int(sim.particles.n),
        "steps": len(sim.records),
        "volume_change": m["volume_change"],
        "normalised_runout": m["normalised_runout"],
        "final_height": m.get("final_height"),
        "R_at_rest": m["stress_roughness"],
        "R_max": m["stress_roughness_max"],
        "step_median_s": float(np.median(steps)),
        "wall_s": time.perf_counter() - t0,
    }


def markdown(rows: list[dict[str, Any]], key: str) -> str:
    """A table of runs, labelled by ``key`` of their overrides."""
    lines = [
        f"| {key} | kappa | particles | volume | run-out | H/L0 | R at rest | R max "
        "| steps | s/step |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        o = r["overrides"]
        lines.append(
            f"| {o.get(key, 'default')} | {o.get('volume_correction', 0):g} | "
            f"{r['particles']} | {100 * r['volume_change']:+.1f} % | "
            f"{r['normalised_runout']:.2f} | {r['final_height']:.2f} | "
            f"{r['R_at_rest']:.3f} | {r['R_max']:.3f} | {r['steps']} | "
            f"{r['step_median_s']:.2f} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kappas", default="0,0.03,0.1,0.3")
    ap.add_argument("--sweep-kappa", type=float, default=0.1)
    ap.add_argument("--no-sweep", action="store_true")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    default = [{"volume_correction": float(k)} for k in args.kappas.split(",")]
    sweep = []
    if not args.no_sweep:
        sweep = [
            {
                "aspect": a,
                "length": LENGTH,
                "spacing": LENGTH / 12,
                "volume_correction": k,
            }
            for a in ASPECTS
            for k in (0.0, args.sweep_kappa)
        ]
    start = time.perf_counter()
    # Largest first, so that the pool ends together.
    tasks = sorted(default + sweep, key=lambda o: -o.get("aspect", 3.0))
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        results = list(pool.map(run, tasks))
    by_task = {
        json.dumps(t, sort_keys=True): r for t, r in zip(tasks, results, strict=True)
    }
    pick = [by_task[json.dumps(t, sort_keys=True)] for t in default + sweep]
    out = {
        "default": pick[: len(default)],
        "sweep": pick[len(default) :],
        "workers": args.workers,
        "wall_s": time.perf_counter() - start,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=1))
    print(markdown(out["default"], "aspect"))
    if sweep:
        print()
        print(markdown(out["sweep"], "aspect"))
    return out


if __name__ == "__main__":
    main()
