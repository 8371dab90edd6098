#!/usr/bin/env python
"""How far one step's cone force moves when the step's start is nudged.

``cone-penetration`` with a rounded shoulder (``shoulder_round=2``) at D/8,
half a spacing a step, pushed to ``--start`` D.  From there, for ``--samples``
successive steps, the step is repeated from copies of its start whose
particles within 2 D of the tip are moved by a random displacement of
``eps`` spacings (each coordinate normal with that standard deviation; the
axis's particles keep r = 0, held dofs are not moved, and particles moved
into the cone are put back on its outline, as the run itself does after every
step) for ``eps`` = 1e-6, 1e-3 and 1e-2, three draws each, and the change of
the step's cone force is recorded, with how many triangles of the step's
start differ from the unnudged one's and how many contact rows it has more.

A force that moves in proportion to ``eps`` is a smooth function of the
particles' positions; one that jumps by a fixed amount at small ``eps``
changes with something discrete (the triangulation, the contact set).  The
step-to-step scatter of the cone's resistance is set against both.

Usage (from the repository root)::

    python demos/studies/cone_sensitivity.py [--out docs/validation] [--per 8]

Writes ``<out>/cone_sensitivity.json`` and ``<out>/cone_sensitivity.inc``
(about 10 minutes on one core).
"""

from __future__ import annotations

import argparse
import copy
import json
import time
from pathlib import Path

import numpy as np
from _common import VALIDATION, write_results
from _reporting import markdown_table

import skfem_npfem as npfem
from skfem_npfem.boundary import project_out_of_bodies
from skfem_npfem.scenes.footing.cone import build, sizes

#: Sizes of the nudge, in spacings.
EPS = (1e-6, 1e-3, 1e-2)
#: Draws per size and step.
DRAWS = 3


def nudged(sim, eps: float, h: float, reach: float, tip: float, rng):
    """A copy of ``sim`` with its particles near the tip moved by ``eps`` h."""
    s = copy.deepcopy(sim)
    x = s.particles.x
    move = eps * h * rng.standard_normal(x.shape)
    move[np.asarray(s.particles.fixed, bool)] = 0.0
    move[x[:, 0] < 0.05 * h, 0] = 0.0  # the axis's particles stay on it
    move[np.hypot(x[:, 0], x[:, 1] - tip) > reach] = 0.0
    x += move
    x[:], _, _ = project_out_of_bodies(s.model.bodies, x, s.particles.v, s.time)
    return s


def force(sim) -> tuple[float, set, int]:
    """The cone's vertical force after one more step (N), its start's
    triangles (sorted node triples) and its number of contact rows."""
    sim.run(steps=1)
    tris = {tuple(t) for t in np.sort(sim.mesh_source.last.simplices, axis=1)}
    rec = sim.records[-1]
    return float(rec.extra["cone_force_y"]), tris, rec.n_contacts


def run(per: float, start: float, samples: int, seed: int = 1) -> tuple[dict, float]:
    """The cone at D/``per`` pushed ``start`` D, then ``samples`` nudged steps;
    the record and the seconds it took."""
    scene = npfem.get_scene("cone-penetration")
    D = scene.resolve({})["diameter"]
    values = scene.resolve({"spacing": D / per, "shoulder_round": 2.0})
    sim, g = build(values, progress=False).simulation, sizes(values)
    h, t0, rng = values["spacing"], time.perf_counter(), np.random.default_rng(seed)
    while not sim.records or -sim.records[-1].extra["cone_y"] < start * D:
        sim.run(steps=1)
    rows = []
    for _ in range(samples):
        base = copy.deepcopy(sim)
        f0, tris0, rows0 = force(sim)
        tip = g["z_tip"] + base.records[-1].extra["cone_y"]
        row = {"w": -sim.records[-1].extra["cone_y"] / D, "force": f0}
        for eps in EPS:
            change, swapped, contacts = [], [], []
            for _ in range(DRAWS):
                f, tris, n = force(nudged(base, eps, h, 2 * D, tip, rng))
                change.append(f / f0 - 1.0)
                swapped.append(len(tris ^ tris0))
                contacts.append(n - rows0)
            row[f"{eps:g}"] = change
            row[f"{eps:g} triangles swapped"] = swapped
            row[f"{eps:g} contact rows added"] = contacts
        rows.append(row)
        print(json.dumps(row), flush=True)
    return {"per": per, "start": start, "steps": rows}, time.perf_counter() - t0


def summary(result: dict) -> tuple[dict, str]:
    """Per size of nudge: the median and largest change; beside the scatter."""
    steps = result["steps"]
    f = np.array([s["force"] for s in steps])
    out = {"step_to_step": float(np.abs(np.diff(f)).max() / f.mean())}
    rows = []
    for eps in EPS:
        d = np.abs([v for s in steps for v in s[f"{eps:g}"]])
        swapped = [v for s in steps for v in s[f"{eps:g} triangles swapped"]]
        same = np.array(swapped) == 0
        rows_added = [v for s in steps for v in s[f"{eps:g} contact rows added"]]
        largest_same = float(d[same].max()) if same.any() else None
        out[f"{eps:g}"] = {
            "median": float(np.median(d)),
            "largest": float(d.max()),
            "largest_same_triangles": largest_same,
            "contact_rows_changed": int(np.count_nonzero(rows_added)),
        }
        rows.append(
            [
                f"{eps:g}",
                f"{np.median(d):.2e}",
                f"{d.max():.2e}",
                int(np.sum(d > 1e-3)),
                f"{int(same.sum())} / {largest_same:.2e}" if same.any() else "0 / -",
                int(np.count_nonzero(rows_added)),
                d.size,
            ]
        )
    head = ["nudge (spacings)", "median change (size)", "largest change (size)"]
    head += ["changes over 0.1 %", "same triangles / their largest change"]
    head += ["contact rows changed", "steps repeated"]
    return out, markdown_table(head, rows)


def parser() -> argparse.ArgumentParser:
    """The study's options: where to write, the spacing, where and how long."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=VALIDATION)
    for name, kind, default in (("per", float, 8.0), ("start", float, 3.0)):
        ap.add_argument(f"--{name}", type=kind, default=default)
    ap.add_argument("--samples", type=int, default=8, help="steps repeated")
    return ap


def lead(result: dict) -> str:
    """The sentence above the table: the set-up and the step-to-step change."""
    first, s = result["steps"][0]["w"], result["summary"]
    return (
        f"{len(result['steps'])} successive steps from w = {first:.2f} D at "
        f"D/{result['per']:g}, each repeated {DRAWS} times per size of nudge; the "
        f"largest change of the cone force from one of these steps to the next "
        f"is {100 * s['step_to_step']:.1f} % of their mean.\n\n"
    )


def main() -> None:
    args = parser().parse_args()
    result, wall = run(args.per, args.start, args.samples)
    result["wall_s"] = wall
    result["summary"], table = summary(result)
    text = json.dumps(result, indent=1)
    write_results(args.out / "cone_sensitivity.json", text, lead(result) + table)


if __name__ == "__main__":
    main()
