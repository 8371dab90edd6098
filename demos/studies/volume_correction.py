#!/usr/bin/env python
"""The volume correction (``volume_correction = kappa``) on the column collapse.

Runs the ``column-collapse`` scene (plane strain, the scene's defaults
otherwise: node masses, beta = 30, alpha = 1.3, dt = 5 ms, to rest) for each
``kappa`` of ``--kappas`` at the default resolution, and the aspect-ratio sweep
a = 0.5 / 1 / 2 / 4 / 8 at 12 particles across L0 for each ``kappa`` of
``--sweep-kappas``.  Reported per run: the mesh-volume change at the end, the
normalised run-out, the final height, the stress roughness R at rest and its
maximum, the number of steps and the median step time (every run in this
process pool, so the step times share one machine load).

Usage (repository root)::

    python demos/studies/volume_correction.py                 # kappa 0, 0.03, 0.1, 0.3
    # more sweep runs added to the committed JSON (runs already in it are kept)
    python demos/studies/volume_correction.py --kappas "" --sweep-kappas 0.03 --append

Writes ``docs/validation/volume_correction.json`` and its tables,
``volume_correction.inc`` beside it (included by docs/validation/stabilisation.md).
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

from _common import (
    ASPECTS,
    LENGTH,
    VALIDATION,
    floats,
    replace_rows,
    run_to_rest,
    write_results,
)

OUT = VALIDATION / "volume_correction.json"


def _merge(old: list[dict], new: list[dict]) -> list[dict]:
    """Runs of ``old`` not rerun in ``new``, then ``new``; sorted by a, kappa."""
    rows = replace_rows(old, new, lambda r: json.dumps(r["overrides"], sort_keys=True))
    return sorted(
        rows,
        key=lambda r: (
            r["overrides"].get("aspect", 0.0),
            r["overrides"].get("volume_correction", 0.0),
        ),
    )


def markdown(rows: list[dict[str, Any]], key: str) -> str:
    """A table of runs, labelled by ``key`` of their overrides."""
    lines = [
        f"| {key} | kappa | particles | volume | run-out | H/L0 | R at the end "
        "| R max | steps | at rest | s/step |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        o = r["overrides"]
        lines.append(
            f"| {o.get(key, 'default')} | {o.get('volume_correction', 0):g} | "
            f"{r['particles']} | {100 * r['volume_change']:+.1f} % | "
            f"{r['normalised_runout']:.2f} | {r['final_height']:.2f} | "
            f"{r['R_at_rest']:.3f} | {r['R_max']:.3f} | {r['steps']} | "
            f"{_at_rest(r)} | {r['step_median_s']:.2f} |"
        )
    return "\n".join(lines)


def _at_rest(row: dict[str, Any]) -> str:
    """yes / no; runs made before the t_end fix stopped at the scene's 1 s."""
    if "at_rest" in row:
        return "yes" if row["at_rest"] else "no"
    return "no (t = 1 s)" if row["steps"] >= 200 else "yes"


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kappas", default="0,0.03,0.1,0.3")
    ap.add_argument("--sweep-kappas", default="0,0.1")
    ap.add_argument(
        "--aspects",
        default=",".join(f"{a:g}" for a in ASPECTS),
        help="aspect ratios of the sweep",
    )
    ap.add_argument("--append", action="store_true", help="add to --out's runs")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    default = [{"volume_correction": float(k)} for k in floats(args.kappas)]
    sweep = [
        {
            "aspect": a,
            "half_width": LENGTH,
            "spacing": LENGTH / 12,
            "volume_correction": k,
        }
        for a in floats(args.aspects)
        for k in floats(args.sweep_kappas)
    ]
    start = time.perf_counter()
    # Largest first, so that the pool ends together.
    tasks = sorted(default + sweep, key=lambda o: -o.get("aspect", 3.0))
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        results = list(pool.map(run_to_rest, tasks))
    by_task = {
        json.dumps(t, sort_keys=True): r for t, r in zip(tasks, results, strict=True)
    }
    pick = [by_task[json.dumps(t, sort_keys=True)] for t in default + sweep]
    old = {"default": [], "sweep": []}
    if args.append and args.out.exists():
        old = json.loads(args.out.read_text())
    out = {
        "default": _merge(old["default"], pick[: len(default)]),
        "sweep": _merge(old["sweep"], pick[len(default) :]),
        "workers": args.workers,
        # With --append: the wall time of all the runs in the file.
        "wall_s": old.get("wall_s", 0.0) + time.perf_counter() - start,
    }
    write_results(args.out, json.dumps(out, indent=1), page_tables(out))
    return out


def page_tables(out: dict[str, Any]) -> str:
    """The two tables of docs/validation/stabilisation.md, with how they were made."""
    return (
        "<!-- Generated by demos/studies/volume_correction.py from "
        "volume_correction.json; "
        "do not edit by hand: rerun it. -->\n\n"
        "Volume: mesh-volume change at the end; run-out "
        "(L - L0)/L0; R: stress roughness of sigma_v; s/step: median step time "
        f"({out['workers']} runs at a time on 2 cores).\n\n"
        "Default collapse (a = 2, 1 035 particles, beta = 30):\n\n"
        + markdown(out["default"], "aspect")
        + "\n\nAspect-ratio sweep, 12 particles across L0:\n\n"
        + markdown(out["sweep"], "aspect")
        + "\n"
    )


if __name__ == "__main__":
    main()
