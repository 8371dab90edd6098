#!/usr/bin/env python
"""How rough is a smooth field? The stress roughness R against its floor.

The stress roughness ``R`` (``skfem_npfem.metrics``) compares
each interior particle's vertical stress with the mean of its mesh neighbours.
On an irregular mesh a *smooth* field does not score zero: a gradient gives
``grad s . (x_i - mean_j x_j)`` wherever the neighbours are not centred on the
node, and curvature adds ``O(h^2)``.  Both grow relative to the stress itself
when the body is only a few particles thick, as the deposit of a coarse
collapse is.

For every step of each run this study records ``R`` and its floor: the ``R``
of the least-squares cubic fit of the same stresses on the same particles and
mesh (:func:`skfem_npfem.metrics.roughness_floor`), and the excess
``sqrt(R^2 - floor^2)``, the part a smooth field of that shape would not have.
Runs: the aspect-ratio sweep a = 0.5 / 1 / 2 / 4 / 8 of ``column-collapse``
at its default settings (stabilisation 30; ``--kappas`` sets the volume
correction) at N = 12 particles across L0
(the validation page's primary sweep) and at N = 22 (the scene's default
spacing L0/22; a = 2 at N = 22 is the default collapse), each to rest
(t_end = 15 sqrt(H0/g) as a cap); ``--repeats`` adds realisations of the
same runs (see :func:`run`), since R max is the extreme of a chaotic history.

Usage (repository root)::

    python demos/studies/roughness_floor.py                 # both sweeps, 2 workers
    python demos/studies/roughness_floor.py --kappas 0.1 --append
    python demos/studies/roughness_floor.py --across 22 --kappas 0,0.1 \\
        --repeats 1 --append

Writes ``docs/validation/roughness_floor.json`` (per run its summary) and its
table ``roughness_floor.inc`` (included by docs/validation/stabilisation.md);
the runs with their per-step histories go to ``out/roughness_floor.json`` (not
committed).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

#: The sweep of the volume-correction study (aspects, L0 and the t_end cap
#: t_end = T_END_FACTOR sqrt(H0 / g)) and its results writer are in _common.
from _common import (
    ASPECTS,
    LENGTH,
    T_END_FACTOR,
    VALIDATION,
    WORK,
    replace_rows,
    write_results,
)

OUT = VALIDATION / "roughness_floor.json"
#: The same runs with their per-step histories (gitignored).
FULL = WORK / "roughness_floor.json"
ACROSS = (12, 22)


#: Young's modulus of the scene; a repeat multiplies it by 1 + REPEAT_NUDGE k.
E_DEFAULT = 1.0e7
REPEAT_NUDGE = 1e-9


def run(spec: tuple[float, int, float, int]) -> dict[str, Any]:
    """One collapse to rest with R and its floor recorded at every step.

    ``spec`` is (aspect, particles across L0, kappa, repeat).  Repeat ``k > 0``
    changes E by the relative ``REPEAT_NUDGE k``: physically nothing, but the
    remeshed flow is chaotic, so the round-off difference grows into another
    realisation of the same collapse (its R history, run-out and volume show
    the run-to-run spread).
    """
    from skfem_npfem.metrics import roughness_floor, roughness_index
    from skfem_npfem.scenes import get_scene

    aspect, across, kappa, repeat = spec
    scene = get_scene("column-collapse")
    t_end = T_END_FACTOR * math.sqrt(aspect * LENGTH / 9.81)
    values = scene.resolve(
        {
            "aspect": aspect,
            "spacing": LENGTH / across,
            "volume_correction": kappa,
            "E": E_DEFAULT * (1.0 + REPEAT_NUDGE * repeat),
            "t_end": t_end,
            "threads": 1,
        }
    )
    srun = scene.build(values, out=None, progress=False)
    sim = srun.simulation
    hist: dict[str, list[float]] = {"t": [], "R": [], "floor": [], "interior": []}

    def record(sim: Any, p: Any, result: Any) -> bool:
        d = p.x.shape[1]
        cells = np.asarray(result.cells)
        s = np.asarray(p.stress)[:, d - 1]
        r, n = roughness_index(cells, s)
        floor = roughness_floor(p.x, cells, s) if np.isfinite(r) else float("nan")
        for key, value in zip(hist, (sim.time, r, floor, n), strict=True):
            hist[key].append(float(f"{value:.5g}"))
        return False

    sim.callbacks.append(record)
    t0 = time.perf_counter()
    sim.run(**srun.run_kwargs)
    m = srun.metrics(sim)
    return {
        "aspect": aspect,
        "across": across,
        "stabilisation": values["stabilisation"],
        "volume_correction": kappa,
        "repeat": repeat,
        "particles": int(sim.particles.n),
        "normalised_runout": m["normalised_runout"],
        "volume_change": m["volume_change"],
        "at_rest": bool(m["at_rest"]),
        "R_max_metric": m["stress_roughness_max"],
        "wall_s": time.perf_counter() - t0,
        "history": hist,  # per step; 5 significant digits
    }


def summary(r: dict[str, Any]) -> dict[str, float]:
    """R max, the floor at that step, the largest floor and excess, the end.

    A compact row (committed, without its per-step history) carries it.
    """
    if "history" not in r:
        return r["summary"]
    R = np.array(r["history"]["R"], float)
    F = np.array(r["history"]["floor"], float)
    ok = np.isfinite(R) & np.isfinite(F)
    excess = np.sqrt(np.maximum(R**2 - F**2, 0.0))
    k = int(np.nanargmax(np.where(ok, R, np.nan)))
    last = int(np.flatnonzero(ok)[-1])
    return {
        "R_max": float(R[k]),
        "floor_at_R_max": float(F[k]),
        "step_of_R_max": k + 1,
        "floor_max": float(np.nanmax(F[ok])),
        "excess_max": float(np.nanmax(excess[ok])),
        "R_end": float(R[last]),
        "floor_end": float(F[last]),
        "steps_over_0.10": int(np.count_nonzero(R[ok] > 0.10)),
        "steps": int(ok.sum()),
    }


def page(rows: list[dict[str, Any]]) -> str:
    """The markdown table of the runs."""
    lines = [
        "<!-- Generated by demos/studies/roughness_floor.py from roughness_floor.json; "
        "do not edit by hand: rerun it (--page). -->",
        "",
        "R: the stress roughness of sigma_v at each step; floor: "
        "R of the least-squares cubic fit of the same stresses on the same mesh "
        "(what a smooth field of that shape scores); excess: sqrt(R^2 - floor^2). "
        "Default settings of `column-collapse` (stabilisation 30) but for kappa "
        "(`volume_correction`), each run to rest.",
        "",
        "| N across L0 | a | kappa | repeat | particles | R max | floor at that step "
        "| steps with R > 0.10 "
        "| largest floor | largest excess | R at the end | floor at the end "
        "| run-out | volume |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(rows, key=_key):
        s = summary(r)
        lines.append(
            f"| {r['across']} | {r['aspect']:g} | {r['volume_correction']:g} | "
            f"{r['repeat']} | {r['particles']} | "
            f"{s['R_max']:.3f} | {s['floor_at_R_max']:.3f} | "
            f"{s['steps_over_0.10']} of {s['steps']} | {s['floor_max']:.3f} | "
            f"{s['excess_max']:.3f} | {s['R_end']:.3f} | {s['floor_end']:.3f} | "
            f"{r['normalised_runout']:.2f} | {100 * r['volume_change']:+.1f} % |"
        )
    return "\n".join(lines) + "\n"


def compact(r: dict[str, Any]) -> dict[str, Any]:
    """The committed row: the run without its per-step history, its summary."""
    out = {k: v for k, v in r.items() if k != "history"}
    out["summary"] = summary(r)
    return out


def _key(r: dict[str, Any]) -> tuple[int, float, float, int]:
    return (r["across"], r["volume_correction"], r["aspect"], r["repeat"])


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--aspects", default=",".join(f"{a:g}" for a in ASPECTS))
    ap.add_argument("--across", default=",".join(str(n) for n in ACROSS))
    ap.add_argument("--kappas", default="0", help="volume_correction values")
    ap.add_argument(
        "--repeats", default="0", help="repeat indices (0: the run itself; see run)"
    )
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--append", action="store_true", help="keep --out's other runs")
    ap.add_argument("--page", action="store_true", help="only the page from the JSON")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument(
        "--full",
        type=Path,
        default=FULL,
        help="the runs with their per-step histories (not committed; --out "
        "holds the summaries the page needs)",
    )
    args = ap.parse_args(argv)
    source = args.full if args.full.exists() else args.out
    old = json.loads(source.read_text()) if source.exists() else []
    text = None
    if args.page:
        rows = old
    else:
        specs = [
            (float(a), int(n), float(k), int(rep))
            for rep in args.repeats.split(",")
            for k in args.kappas.split(",")
            for n in args.across.split(",")
            for a in args.aspects.split(",")
        ]
        # Largest runs first, so that the pool ends with the small ones.
        specs.sort(key=lambda s: -s[0] * s[1] ** 2)
        new = []
        with ProcessPoolExecutor(args.workers) as pool:
            for r in pool.map(run, specs):
                new.append(r)
                s = summary(r)
                print(
                    f"a = {r['aspect']:g}, N = {r['across']}, kappa = "
                    f"{r['volume_correction']:g}, repeat {r['repeat']}: "
                    f"{r['particles']} particles, "
                    f"{s['steps']} steps, R max {s['R_max']:.3f} (floor "
                    f"{s['floor_at_R_max']:.3f}), {r['wall_s']:.0f} s",
                    flush=True,
                )
        rows = replace_rows(old if args.append else [], new, _key)
        # One run a line: the per-step histories make an indented file large.
        args.full.parent.mkdir(parents=True, exist_ok=True)
        args.full.write_text("[\n" + ",\n".join(json.dumps(r) for r in rows) + "\n]\n")
        text = "[\n" + ",\n".join(json.dumps(compact(r)) for r in rows) + "\n]\n"
    write_results(args.out, text, page(rows))
    return rows


if __name__ == "__main__":
    main()
