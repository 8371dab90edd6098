#!/usr/bin/env python
"""A whole 3D quarter-cylinder PFEM run, step by step, written as JSON lines.

The seed column in 3D (docs/seed_column.md) runs to rest in ~135 steps of 2 ms;
this runs the suite's ``cylinder3d-*`` case (``benchmarks/suite.py``) for that
many steps and writes one line per step: time, IPM iterations, status,
cumulative wall time, active particles, radial fronts (99 % quantile and
farthest particle), top height, largest speed and the mesh-volume change.
A solver failure is reported with the step.

Usage::

    PYTHONPATH=. python benchmarks/cylinder3d_run.py --case cylinder3d-4k --steps 135
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

import suite


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", default="cylinder3d-4k")
    ap.add_argument("--steps", type=int, default=135)
    ap.add_argument("--backend", default="auto")
    ap.add_argument("--preset", default="high")
    ap.add_argument("--out", default=None, help="JSON-lines file")
    args = ap.parse_args(argv)
    out = Path(args.out or HERE / "results" / f"{args.case}_full.jsonl")
    sim, _ = suite.build(args.case, args.backend, args.preset, 0)
    t0 = time.perf_counter()
    with open(out, "w") as log:
        for k in range(args.steps):
            try:
                sim.run(steps=1)
            except Exception as err:  # report and keep the finished lines
                print(f"failed at step {k}: {type(err).__name__}: {err}", flush=True)
                return 1
            r = sim.records[-1]
            x = sim.particles.x
            radius = np.hypot(x[:, 0], x[:, 1])
            rec = {
                "step": k,
                "t": sim.time,
                "it": r.iterations,
                "status": r.status,
                "wall": time.perf_counter() - t0,
                "n_active": int(r.n_active),
                "r99": float(np.quantile(radius, 0.99)),
                "rmax": float(radius.max()),
                "zmax": float(x[:, 2].max()),
                "vmax": float(np.linalg.norm(sim.particles.v, axis=1).max()),
                "vol": float(r.volume_change),
            }
            log.write(json.dumps(rec) + "\n")
            log.flush()
            if k % 10 == 0:
                print(rec, flush=True)
    print(f"done: t = {sim.time:.3f} s, {time.perf_counter() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
