#!/usr/bin/env python
"""What the cone's one-step load drops are: its collapse load, step by step.

``cone-penetration`` (smooth cone, weightless Tresca clay, the scene's
rigidity index) at D/8, the cone moving half a spacing a step, pushed 5 D,
run one step at a time.  For every step it solves the rigid smooth cone's
limit analysis on the step's start: one limit program on the step's own
triangulation of its start positions (the same axisymmetric nodal
integration, the elements spanning the cone dropped as the step drops them),
the particles within a quarter spacing of the cone's outline moving with it
(their velocity normal to the outline the cone's, along it free: ``u = V e_z
+ a t``, one ``V`` for all: ``limit_analysis``'s ``velocity_map``), the
supports held.  The soil is weightless
Tresca, so this collapse force is a property of the particles' positions
alone.  Beside it: the step's cone force, the holes of the step's mesh (closed
loops of its boundary other than the outline of the soil) and where the
mechanism's fastest particle is, relative to the cone's shoulder.

This is the measurement the footing's drops were explained by
(``footing_drops.py``: there a hole the alpha test opened on the symmetry
axis); the particles that the cone meets during a step (within about half a
spacing ahead of its face) are not in the program, so the collapse force can
be under the step's force without a drop.

Usage (from the repository root)::

    python demos/studies/cone_drops.py [--out docs/validation] [--per 8] [--push 5]

Writes ``<out>/cone_drops.json`` and ``<out>/cone_drops.inc`` (about 15
minutes on one core).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from _common import VALIDATION, write_results
from _reporting import markdown_table
from scipy.sparse.csgraph import connected_components

import skfem_npfem as npfem
from skfem_npfem.limit.analysis import limit_analysis
from skfem_npfem.mesh.delaunay import p1_mesh
from skfem_npfem.mesh.operators import strain_operator
from skfem_npfem.scenes.footing.cone import build, shoulder_height, sizes
from skfem_npfem.step.boundary_jobs import without_spanned

#: Particles this close to the cone's outline (in spacings) move with it.
REACH = 0.25
#: A step whose force is under this fraction of the median after 2 D is a drop.
DROP = 0.8


def velocity_map(fixed: np.ndarray, face: np.ndarray, normal: np.ndarray):
    """``T``: velocity unknowns to nodal dofs, the face's particles on the cone.

    Column 0 is the cone's vertical velocity ``V``; a face particle's dofs
    are ``V e_z + a t`` (``t`` along the outline; ``a`` its own column, none
    if a dof of it is held); every other free dof has its own column.
    """
    N = fixed.shape[0]
    free = ~fixed
    slide = face & free.all(axis=1)
    own = free & ~face[:, None]
    n_own, n_slide = int(own.sum()), int(slide.sum())
    rows, cols, vals = [], [], []
    ride = np.flatnonzero(face & free[:, 1])
    rows.append(2 * ride + 1), cols.append(np.zeros(ride.size, int))
    vals.append(np.ones(ride.size))
    k = np.flatnonzero(slide)
    t = np.column_stack([-normal[k, 1], normal[k, 0]])
    a = 1 + n_own + np.arange(n_slide)
    rows += [2 * k, 2 * k + 1]
    cols += [a, a]
    vals += [t[:, 0], t[:, 1]]
    node, axis = np.nonzero(own)
    rows.append(2 * node + axis), cols.append(1 + np.arange(n_own))
    vals.append(np.ones(n_own))
    shape = (2 * N, 1 + n_own + n_slide)
    return sp.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape
    )


def collapse_force(sim, x0: np.ndarray, fixed0: np.ndarray, t0: float) -> dict:
    """The smooth rigid cone's collapse force on a step's start (see above)."""
    model, h = sim.model, sim.mesh_source.h
    tri = sim.mesh_source.last
    used = np.unique(tri.simplices)
    local = np.full(len(x0), -1)
    local[used] = np.arange(used.size)
    active, t, _ = without_spanned(
        model.boundaries, x0, used, local[tri.simplices].T, t0
    )
    op, _ = strain_operator(p1_mesh(x0[active], t), model.components, True)
    xa = x0[active]
    dist, normal, _ = model.bodies[0].signed_distance(xa, t0)
    face = dist < REACH * h
    fixed = np.asarray(fixed0, bool)[active]
    # The smooth cone pushes normal to its outline: a normal reference load on
    # the face (unit total, downward) does work through the cone's unknown only.
    pushed = face & (normal[:, 1] < 0.0)
    load = np.zeros((active.size, 2))
    load[pushed] = -normal[pushed] / normal[pushed, 1].sum()
    res = limit_analysis(
        op,
        model.materials,
        np.asarray(sim.particles.material)[active],
        load,
        fixed=fixed,
        velocity_map=velocity_map(fixed, face, normal),
    )
    u = res.velocity
    speed = np.linalg.norm(u, axis=1)
    k = int(np.argmax(speed))
    return {
        "collapse": float(res.multiplier),
        "status": res.status,
        "fastest": float(speed[k] / np.abs(u[face, 1]).max()),
        "fastest_at": xa[k].tolist(),
    }


def holes(x: np.ndarray, simplices: np.ndarray) -> int:
    """Closed loops of a triangulation's boundary besides the largest one."""
    e = np.sort(np.concatenate([simplices[:, [i, (i + 1) % 3]] for i in range(3)]), 1)
    edges, count = np.unique(e, axis=0, return_counts=True)
    b = edges[count == 1]
    nodes, inv = np.unique(b, return_inverse=True)
    pairs = inv.reshape(-1, 2)
    g = sp.coo_matrix(
        (np.ones(len(b)), (pairs[:, 0], pairs[:, 1])), shape=(nodes.size,) * 2
    )
    return connected_components(g, directed=False)[0] - 1


def run(per: float, push: float) -> dict:
    """The cone at D/``per`` pushed ``push`` D, one step at a time."""
    D = npfem.get_scene("cone-penetration").resolve({})["diameter"]
    over = {"spacing": D / per, "penetration": push * D}
    values = npfem.get_scene("cone-penetration").resolve(over)
    srun = build(values, progress=False)
    sim, g = srun.simulation, sizes(values)
    t0, rows = time.perf_counter(), []
    while sim.time < srun.run_kwargs["t_end"] * (1 - 1e-12):
        x0, start = sim.particles.x.copy(), sim.time
        fixed0 = np.asarray(sim.particles.fixed, bool).copy()
        sim.run(steps=1)
        rec, tri = sim.records[-1], sim.mesh_source.last
        if not np.array_equal(tri.points, x0):
            raise RuntimeError("the mesher's last triangulation is not the step's")
        w = -rec.extra["cone_y"] / D  # the push at the end of the step, in D
        try:
            c = collapse_force(sim, x0, fixed0, start)
        except npfem.SolverError as err:  # recorded, not hidden: no collapse force
            c = {"collapse": None, "status": err.status, "fastest": None}
            c["fastest_at"] = [np.nan, np.nan]
        rel = np.array(c.pop("fastest_at"))
        rel -= [D / 2, shoulder_height(g, w - rec.dt * values["speed"] / D)]
        rows.append(
            {
                "w": w,
                "force": rec.extra["cone_force_y"],
                **c,
                "fastest_from_shoulder": (rel / values["spacing"]).tolist(),
                "holes": holes(x0, tri.simplices),
            }
        )
        print(len(rows), rows[-1], flush=True)
    return {"over": over, "steps": rows, "wall_s": time.perf_counter() - t0}


def summary(result: dict) -> tuple[dict, str]:
    """The steady part's ratios, its drop steps and a table of them."""
    steps = [s for s in result["steps"] if s["w"] > 2.0 and s["collapse"] is not None]
    force = np.array([s["force"] for s in steps])
    ratio = np.array([s["collapse"] / s["force"] for s in steps])
    median = float(np.median(force))
    drop = force < DROP * median
    out = {
        "steps": len(steps),
        "median_force": median,
        "ratio_median": float(np.median(ratio)),
        "within_5_percent": int(np.sum(np.abs(ratio - 1.0) <= 0.05)),
        "under": int(np.sum(ratio < 0.95)),
        "drops": int(drop.sum()),
        "holes": int(max(s["holes"] for s in result["steps"])),
        "unsolved": sum(s["collapse"] is None for s in result["steps"]),
    }
    rows = [
        [
            f"{s['w']:.2f}",
            f"{s['force'] / median:.3f}",
            f"{s['collapse'] / median:.3f}",
            f"{s['fastest']:.1f}",
            "({:+.1f}, {:+.1f})".format(*s["fastest_from_shoulder"]),
            s["holes"],
        ]
        for s, d in zip(steps, drop, strict=True)
        if d or s["collapse"] < 0.95 * s["force"]
    ]
    head = ["w/D", "force / median", "collapse force / median"]
    head += ["fastest particle / cone", "its place from the shoulder, (r, z) / h"]
    return out, markdown_table([*head, "holes in the mesh"], rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=VALIDATION)
    ap.add_argument("--per", type=float, default=8.0)
    ap.add_argument("--push", type=float, default=5.0)
    args = ap.parse_args()
    result = run(args.per, args.push)
    result["summary"], table = summary(result)
    s = result["summary"]
    page = (
        f"After 2 D ({s['steps']} steps): the collapse force over the step's force "
        f"has median {s['ratio_median']:.3f}; {s['within_5_percent']} steps within "
        f"5 %, {s['under']} under 0.95; {s['drops']} drops (force under "
        f"{DROP} x the median); at most {s['holes']} holes in a step's mesh; "
        f"{s['unsolved']} limit programs unsolved.  "
        "The steps that drop or whose collapse force is under 0.95 of their force:"
        f"\n\n{table}\n"
    )
    write_results(args.out / "cone_drops.json", json.dumps(result, indent=1), page)


if __name__ == "__main__":
    main()
