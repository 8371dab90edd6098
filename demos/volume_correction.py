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

    python demos/volume_correction.py                 # kappa 0, 0.03, 0.1, 0.3
    # more sweep runs added to the committed JSON (runs already in it are kept)
    python demos/volume_correction.py --kappas "" --sweep-kappas 0.03 --append

Writes ``docs/validation/volume_correction.json`` and its tables,
``volume_correction.md`` beside it (included by docs/validation.md).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "validation" / "volume_correction.json"
ASPECTS = (0.5, 1.0, 2.0, 4.0, 8.0)
LENGTH = 0.2


#: t_end = T_END_FACTOR * sqrt(H0 / g), a cap the at-rest rule stops before (as
#: in demos/collapse_validation.py); the scene's own 1 s stops tall columns early.
T_END_FACTOR = 15.0


def run(overrides: dict[str, Any]) -> dict[str, Any]:
    """One scene run to rest; its metrics and step times."""
    from skfem_npfem.scenes import get_scene

    scene = get_scene("column-collapse")
    h0 = overrides.get("aspect", 2.0) * overrides.get("half_width", LENGTH)
    t_end = T_END_FACTOR * math.sqrt(h0 / 9.81)
    # kappa = 0 unless the overrides say otherwise (0.1 became the scene's
    # default after this study).
    values = scene.resolve(
        {"t_end": t_end, "volume_correction": 0.0, **overrides, "threads": 1}
    )
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
        "at_rest": bool(m["at_rest"]),
        "step_median_s": float(np.median(steps)),
        "wall_s": time.perf_counter() - t0,
    }


def _floats(text: str) -> list[float]:
    return [float(k) for k in text.split(",") if k.strip()]


def replace_rows(
    old: list[dict], new: list[dict], key: Callable[[dict], Any]
) -> list[dict]:
    """Runs of ``old`` whose ``key`` no run of ``new`` has, then ``new``.

    How the studies of this folder add runs to their committed JSON (``--append``).
    """
    done = {key(r) for r in new}
    return [r for r in old if key(r) not in done] + list(new)


def write_results(path: Path, text: str | None, page: str) -> None:
    """The JSON ``text`` at ``path`` (None: keep it), ``page`` beside it as .md.

    The page is printed too.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    if text is not None:
        path.write_text(text)
    path.with_suffix(".md").write_text(page)
    print(page)


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
    default = [{"volume_correction": float(k)} for k in _floats(args.kappas)]
    sweep = [
        {
            "aspect": a,
            "half_width": LENGTH,
            "spacing": LENGTH / 12,
            "volume_correction": k,
        }
        for a in _floats(args.aspects)
        for k in _floats(args.sweep_kappas)
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
    """The two tables of docs/validation.md, with how they were made."""
    return (
        "# Volume correction: measured\n\n"
        "Generated by `demos/volume_correction.py` from `volume_correction.json` "
        "(do not edit by hand). Volume: mesh-volume change at the end; run-out "
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
