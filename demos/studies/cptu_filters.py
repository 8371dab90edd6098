#!/usr/bin/env python
"""CPTu: where u2 is read, and what that does to T*_50.

Runs the coupled cone of ``demos/studies/cptu.py`` (the effective-stress clay,
k = 1e-8 m/s, V = 95, pushed 4 D a quarter of a spacing a step in the scene's
domain, held to T* = 2) at D/8 and D/10, keeping every step's particles within
0.6 D of the shoulder with their excess pore pressure.  Then reads u2 through
several filters from those records: the scene's (the shaft from the shoulder
to 0.15 D above it, r <= R + h), discs of radius h and 0.2 to 0.5 D round the
shoulder point (the first, a disc of one spacing, was the scene's former
filter: it takes in the cone's face below the shoulder), and bands on the
shaft 0.1 to 0.5 D tall and one to two spacings wide.  For each it gives u2 at
the end of the push and over the push's last diameter, the held cone's first
step and T*_50 against Teh & Houlsby's 0.245.

Usage (from the repository root)::

    python demos/studies/cptu_filters.py [--n 8 10] [--jobs 2] [--tables]

``--tables`` writes ``docs/validation/cptu_filters.json``.
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from _common import VALIDATION
from cptu import CLAY, STAGE

from skfem_npfem.scenes import get_scene
from skfem_npfem.scenes.footing.cone import U2_FILTER_HEIGHT, shoulder_height, sizes
from skfem_npfem.scenes.footing.cone_dissipation import (
    TEH_HOULSBY_T50_U2,
    half_time,
)

D = 0.0357
PUSH, PER = 4.0, 4.0


def keeper(g: dict, steps: list[dict]):
    """A callback that keeps the particles within 0.6 D of the shoulder."""
    R = D / 2

    def keep(s, p, step) -> bool:
        w = -step.record.extra.get("cone_y", 0.0) / D
        shoulder = shoulder_height(g, w)
        near = np.hypot(p.x[:, 0] - R, p.x[:, 1] - shoulder) <= 0.6 * D
        steps.append(
            {
                "t": s.time,
                "w": w,
                "shoulder": shoulder,
                "x": p.x[near].tolist(),
                "u": p.excess_pore_pressure[near].tolist(),
            }
        )
        return False

    return keep


def record(n: int) -> dict:
    """The run at D/n with the particles near the shoulder at every step."""
    h = D / n
    over = {**CLAY, **STAGE, "spacing": h, "dt": h / PER / 0.02}
    over["penetration"] = PUSH * D
    scene = get_scene("cone-penetration")
    values = scene.resolve(over)
    run = scene.build(values, out=None, progress=False, resume=False)
    steps: list[dict] = []
    run.simulation.callbacks.append(keeper(sizes(values), steps))
    t0 = time.perf_counter()
    run.simulation.run(**run.run_kwargs)
    m = run.metrics(run.simulation)
    return {
        "n": n,
        "h": h,
        "su": values["su"],
        "t50_star_scene": m["t50_star"],
        "unit": m["dissipation"][1][0],
        "steps": steps,
        "wall_s": time.perf_counter() - t0,
    }


def filters(h: float) -> dict:
    """Name -> mask(x, shoulder) of every filter read."""
    R = D / 2
    out = {}
    for r in (h, 0.2 * D, 0.25 * D, 0.375 * D, 0.5 * D):
        name = "disc of one spacing" if r == h else f"disc of {r / D:g} D"
        out[name] = lambda x, s, r=r: np.hypot(x[:, 0] - R, x[:, 1] - s) <= r
    for H in (0.1, U2_FILTER_HEIGHT, 0.25, 0.5):
        for wide in (1.0, 1.5, 2.0):
            name = f"shaft band {H:g} D tall, r <= R + {wide:g} h"

            def band(x, s, H=H, wide=wide):
                above = x[:, 1] - s
                top = max(H * D, h)
                return (above >= 0) & (above <= top) & (x[:, 0] <= R + wide * h)

            out[name] = band
    return out


def read(rec: dict) -> list[dict]:
    """u2 through every filter, its steady mean, first held step and T*_50."""
    steps = rec["steps"]
    t = np.array([s["t"] for s in steps])
    w = np.array([s["w"] for s in steps])
    stop = int(np.argmax(w >= w.max() - 1e-9))
    # The first held step is the dissipation curve's second point (T* = dT).
    unit = (t[stop + 1] - t[stop]) / rec["unit"]
    rows = []
    for name, mask in filters(rec["h"]).items():
        u2 = []
        for s in steps:
            m = mask(np.asarray(s["x"]), s["shoulder"])
            u2.append(float(np.mean(np.asarray(s["u"])[m])) if m.any() else np.nan)
        u2 = np.asarray(u2)
        last = (w >= w.max() - 1.0) & (np.arange(len(w)) <= stop)
        steady = float(np.nanmean(u2[last]))
        curve = [
            [(t[i] - t[stop]) / unit, u2[i] / u2[stop]] for i in range(stop, len(t))
        ]
        t50 = half_time(curve)
        rows.append(
            {
                "filter": name,
                "u2_end_su": u2[stop] / rec["su"],
                "u2_steady_su": steady / rec["su"],
                "first_held": curve[1][1],
                "t50_star": t50,
                "t50_error": None if t50 is None else t50 / TEH_HOULSBY_T50_U2 - 1,
            }
        )
    return rows


def markdown(results: list[dict]) -> str:
    """One table per spacing."""
    lines = []
    for res in results:
        lines += [
            f"D/{res['n']} (the scene's T*_50: {res['t50_star_scene']:.3g})",
            "",
            "| filter | u2 at the stop / s_u | steady u2 / s_u | first held step "
            "| T*_50 (vs 0.245) |",
            "|---|---|---|---|---|",
        ]
        for r in res["filters"]:
            t50 = (
                "n/a"
                if r["t50_star"] is None
                else (f"{r['t50_star']:.3g} ({r['t50_error']:+.0%})")
            )
            lines.append(
                f"| {r['filter']} | {r['u2_end_su']:.2f} | {r['u2_steady_su']:.2f} "
                f"| {r['first_held']:.2f} | {t50} |"
            )
        lines.append("")
    return "\n".join(lines).replace("%", " %")


def run_one(n: int) -> dict:
    """Record the run at D/n and read it through the filters."""
    rec = record(n)
    return {
        "n": n,
        "t50_star_scene": rec["t50_star_scene"],
        "wall_s": rec["wall_s"],
        "filters": read(rec),
    }


def main() -> None:
    """Run the spacings; print the tables; with ``--tables`` write the JSON."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, nargs="+", default=[8, 10])
    parser.add_argument("--jobs", type=int, default=1, help="runs at once")
    parser.add_argument("--tables", action="store_true", help="write the results")
    args = parser.parse_args()
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(run_one, args.n))
    print(markdown(results))
    if args.tables:
        path = VALIDATION / "cptu_filters.json"
        path.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
