#!/usr/bin/env python
"""Cost of the 3D quarter cylinder's symmetry planes: prescribed dofs vs walls.

The seed column's quarter cylinder is built twice: as the scene builds it
(particles on a symmetry plane have its normal displacement prescribed, the
planes are frictionless walls for the others) and with the planes as walls only
(no prescribed dofs, every particle on a plane is a contact candidate).  The
two are stepped alternately in this process from rest, so that both see the
same machine load; per step the wall time, IPM iterations and contact
candidates are recorded, with the ratio of the summed times.

Both step the reference paper's bare method, as the committed result was
measured (``--method bare``, pinned whatever the scene's defaults);
``--method default`` steps the quarter cylinder's defaults of today.

Usage (repository root)::

    python benchmarks/symmetry_planes.py --divisions 12 --steps 6 --threads 1

Writes ``benchmarks/results/symmetry_planes.json``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import _harness as harness
import numpy as np

from skfem_npfem.io import write_json
from skfem_npfem.scenes import get_scene

OUT = Path(__file__).resolve().parent / "results" / "symmetry_planes.json"
R0 = 0.039


def build(
    divisions: int, threads: int, linear_solver: str, method: str = "bare"
) -> dict[str, Any]:
    """The two simulations: ``fixity`` (the scene's) and ``walls``."""
    scene = get_scene("column-collapse")
    values = scene.resolve(
        {
            "geometry": "quarter-cylinder",
            "spacing": R0 / divisions,
            "linear_solver": linear_solver,
            "threads": threads,
            **harness.method_overrides("quarter-cylinder", method),
        }
    )
    sims = {}
    for name in ("fixity", "walls"):
        sim = scene.build(values, out=None, progress=False).simulation
        if name == "walls":
            p = sim.particles
            sim.particles = p.replace(fixed=np.zeros_like(p.fixed))
        sims[name] = sim
    return sims


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Step both models alternately and write the JSON (returned)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--divisions", type=int, default=12, help="r0 / spacing")
    ap.add_argument("--steps", type=int, default=6)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--linear-solver", default="mkl")
    ap.add_argument("--out", type=Path, default=OUT)
    harness.add_method_argument(ap)
    args = ap.parse_args(argv)
    start = time.perf_counter()
    sims = build(args.divisions, args.threads, args.linear_solver, args.method)
    rows: dict[str, list[dict[str, Any]]] = {name: [] for name in sims}
    for _ in range(args.steps):
        for name, sim in sims.items():
            t0 = time.perf_counter()
            sim.run(steps=1)
            rec = sim.records[-1]
            rows[name].append(
                {
                    "step": sim.step,
                    "wall_s": time.perf_counter() - t0,
                    "iterations": rec.iterations,
                    "contacts": rec.n_contacts,
                    "status": rec.status,
                }
            )
            print(name, rows[name][-1], flush=True)
    total = {n: sum(r["wall_s"] for r in rs) for n, rs in rows.items()}
    its = {n: sum(r["iterations"] for r in rs) for n, rs in rows.items()}
    result = {
        "divisions": args.divisions,
        "method": args.method,
        "particles": int(sims["fixity"].particles.n),
        "threads": args.threads,
        "linear_solver": args.linear_solver,
        "steps": rows,
        "total_wall_s": total,
        "iterations": its,
        "seconds_per_iteration": {n: total[n] / its[n] for n in total},
        "ratio_fixity_over_walls": total["fixity"] / total["walls"],
        "note": "2 cores, shared machine: both models stepped alternately in one run",
        "wall_s": time.perf_counter() - start,
    }
    write_json(args.out, result)
    print({k: v for k, v in result.items() if k != "steps"})
    return result


if __name__ == "__main__":
    main()
