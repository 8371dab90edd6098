#!/usr/bin/env python
"""CPTu: what u2 loses in the held cone's first steps, with and without flow.

Runs the CPTu study's D/8 cone in the scene's domain (pushed 4 D, a quarter of
a spacing a step, V = 95) and holds it for a few steps (to T* = 0.03), twice:
with the clay's conductivity and with it divided by 1e8 from the moment the
cone stops (no flow: only the soil's and the contact's own response to the
stop).  Prints u2 (the mean excess pore pressure within a spacing of the
shoulder) over the last push steps and the first held ones, and the excess
pore pressure of the particles on the shaft within two spacings above the
shoulder at the stop and after the first held step.

Usage (from the repository root; about 15 minutes with two cores)::

    python demos/studies/cptu_hold.py [--jobs 2]

Writes ``docs/validation/cptu_hold.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from _common import VALIDATION

from skfem_npfem.scenes import get_scene
from skfem_npfem.scenes.footing.cone import shoulder_height, sizes
from skfem_npfem.scenes.footing.cone_dissipation import time_factor_seconds

D = 0.0357
N, PER, PUSH = 8, 4.0, 4.0


def run(no_flow: bool) -> dict:
    """The push and the first held steps; u2 and the shaft particles' u."""
    h = D / N
    over = {
        "material": "mohr-coulomb",
        "phi": 25.0,
        "nu": 0.3,
        "drainage": "coupled",
        "k": 1e-8,
        "dissipation": True,
        "dT": 0.002,
        "dt_growth": 1.3,
        "dT_max": 0.1,
        "T_end": 0.03,
        "spacing": h,
        "dt": h / PER / 0.02,
        "penetration": PUSH * D,
    }
    scene = get_scene("cone-penetration")
    values = scene.resolve(over)
    srun = scene.build(values, out=None, progress=False, resume=False)
    sim = srun.simulation
    g = sizes(values)
    R = D / 2
    t_push = g["w"] / values["speed"]
    su = values["su"]
    rows: list[dict] = []

    def record(s, p, step) -> bool:
        w = -step.record.extra.get("cone_y", 0.0) / D
        shoulder = shoulder_height(g, w)
        x = p.x
        near = np.hypot(x[:, 0] - R, x[:, 1] - shoulder) <= h
        shaft = (
            (np.abs(x[:, 0] - R) < 0.05 * h)
            & (x[:, 1] > shoulder + 0.5 * h)
            & (x[:, 1] < shoulder + 2 * h)
        )
        u = p.excess_pore_pressure
        held = s.time > t_push * (1 + 1e-9)
        rows.append(
            {
                "T_star": (s.time - t_push) / time_unit if held else None,
                "u2": float(u[near].mean()) / su,
                "shaft_ids": np.flatnonzero(shaft).tolist(),
                "shaft_u": (u[shaft] / su).tolist(),
            }
        )
        # The step that ends the push has just made the cone a held body:
        # from the next step on, no flow if asked.
        if no_flow and not held and s.time >= t_push * (1 - 1e-9):
            water = s.model.water
            s.model.water = dataclasses.replace(
                water, permeability=water.permeability * 1e-8
            )
        return False

    time_unit = time_factor_seconds(values)
    sim.callbacks.append(record)
    sim.run(**srun.run_kwargs)
    stop = max(i for i, r in enumerate(rows) if r["T_star"] is None)
    first = rows[stop + 1]
    at_stop = dict(zip(rows[stop]["shaft_ids"], rows[stop]["shaft_u"], strict=True))
    after = dict(zip(first["shaft_ids"], first["shaft_u"], strict=True))
    both = sorted(set(at_stop) & set(after))
    return {
        "no_flow": no_flow,
        "u2_last_push": [r["u2"] for r in rows[stop - 3 : stop + 1]],
        "u2_held": [[r["T_star"], r["u2"]] for r in rows[stop + 1 :]],
        "shaft_at_stop": [at_stop[i] for i in both],
        "shaft_after_first_held_step": [after[i] for i in both],
    }


def main() -> None:
    """Both runs; print and write the results."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        res = list(pool.map(run, [False, True]))
    for r in res:
        flow = "k / 1e8 when held" if r["no_flow"] else "k"
        print(
            f"{flow}: u2/s_u over the last push steps {np.round(r['u2_last_push'], 2)}"
        )
        held = [[round(t, 4), round(u, 2)] for t, u in r["u2_held"]]
        print(f"  held [T*, u2/s_u]: {held}")
        print(f"  shaft particles at the stop {np.round(r['shaft_at_stop'], 2)}")
        after = np.round(r["shaft_after_first_held_step"], 2)
        print(f"  after the first held step   {after}")
    (VALIDATION / "cptu_hold.json").write_text(json.dumps(res, indent=1) + "\n")


if __name__ == "__main__":
    main()
