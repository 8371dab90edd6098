#!/usr/bin/env python
"""What the footing's one-step load drops are: measured step by step.

``footing-penetration`` with the holes the alpha test opens inside the soil
left open (``seal_cavities=false``; otherwise at its defaults: a smooth rigid
strip pushed to w = B into weightless Tresca clay, E/s_u = 100, B/20 graded
away from the footing, the footing moving a quarter of the spacing a step)
shows a few steps whose load falls by 20-40 % and comes back in the next
step.  This study runs it
one step at a time and records, for every step, the load q/s_u, its dip below
the mean of the two neighbouring steps (over the median load beyond w = 0.1 B),
and three things the step did to the soil:

* the triangles of the step's mesh that the step turned over (positive
  area at the start, none or negative at the end), and the largest distance
  a particle moved in the step over the footing's own motion;
* the largest element strain increment of the step: the norm of the
  (element-constant) strain of the step's displacement increment on each
  triangle of the step's own mesh.  Nodal integration smooths the strains
  over each particle's cell, so a triangle can deform far more than the
  strains its particles' stresses see; one that inverts in the step shows a
  value of order one or more;
* the largest release of vertical stress at a particle, ``max(s_yy,n+1 -
  s_yy,n)`` (compression negative: how much of its compressive vertical
  stress a particle lost in the step);
* the triangles of the step's mesh that the last step's mesh did not have
  (the remeshing the step starts with: the particles' cells, over which
  their stresses act, change with it);
* the smooth footing's collapse load on the step's start: one limit program
  on its particles and the step's own mesh, the particles within a quarter
  spacing of the base tied and loaded (weightless Tresca soil: a property of
  the positions alone, not of the stresses).

It then runs the scene with one setting changed at a time (a stiffer clay
E/s_u = 1000, nu = 0.45 instead of 0.495, half the step, and the stress
stabilisation at beta = 3) and reports the load drops and the largest dip of
each, so that what does not remove them is measured too; and it solves the
step of the largest dip again on triangulations of the same particles with
other tie-breaking (jitter up to 5e-2 h^2), to tell the step's mesh from the
state it starts from.  Last, it runs the scene with inertia (dynamic steps
and a soil of density 10 and 100 kg/m^3, gravity still off): whether the
dips are a velocity field that a quasi-static step picks among many.  And it
runs the step table again at the scene's defaults, ``seal_cavities=true``
(the holes the alpha test opens inside the soil kept meshed).  The runs are
one process, one after another (about 20 minutes in all; ``--parts`` runs
some and keeps the others from the JSON).

Usage (from the repository root)::

    python demos/studies/footing_drops.py [--out docs/validation]
        [--parts stepwise,resolved,variants,inertia,sealed]

Writes ``<out>/footing_drops.json`` and ``<out>/footing_drops.inc`` (tables of
docs/validation/particle_insertion.md).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from _common import VALIDATION, write_results
from _reporting import markdown_table
from skfem import MeshTri
from soil_profiles import run

import skfem_npfem as npfem
from skfem_npfem.limit.analysis import limit_analysis
from skfem_npfem.mesh.smoothing import nodal_integration
from skfem_npfem.scenes.footing.penetration import build

#: The holes left open: every run but the last part's (the scene's default seals).
OPEN = {"seal_cavities": False}
#: The settings changed one at a time (from :data:`OPEN`).
VARIANTS = {
    "seal_cavities = false": {},
    "E/s_u = 1000": {"E": 1.0e6},
    "nu = 0.45": {"nu": 0.45},
    "half the step": {"dt": 0.00625},
    "stabilisation beta = 3": {"stabilisation": 3.0},
}
#: A step whose load is this far (over the median) under its neighbours' mean
#: counts as a dip in the step table.
DIP = 0.10


def dips(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Each step's dip under the mean of its neighbours, over the median load.

    The first and last steps have one neighbour only and get 0.

    Examples
    --------
    >>> dips(np.array([5.0, 4.0, 5.0, 5.0]), np.array([0.2, 0.3, 0.4, 0.5]))
    array([0. , 0.2, 0. , 0. ])
    """
    out = np.zeros(q.size)
    median = np.median(q[w >= 0.1]) if np.any(w >= 0.1) else np.median(q)
    out[1:-1] = (0.5 * (q[:-2] + q[2:]) - q[1:-1]) / median
    return np.maximum(out, 0.0)


def element_strain(x0: np.ndarray, x1: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Norm of each triangle's strain increment from positions ``x0`` to ``x1``.

    ``tri`` (ne, 3) global indices.  The increment is the symmetric part of the
    gradient of the P1 displacement on the triangle at ``x0``.

    Examples
    --------
    >>> x0 = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> element_strain(x0, 1.1 * x0, np.array([[0, 1, 2]])).round(4).tolist()
    [0.1414]
    """
    du = x1 - x0
    a, b, c = (x0[tri[:, k]] for k in range(3))
    J = np.stack([b - a, c - a], axis=2)
    dU = np.stack([du[tri[:, 1]] - du[tri[:, 0]], du[tri[:, 2]] - du[tri[:, 0]]], 2)
    grad = dU @ np.linalg.inv(J)
    eps = 0.5 * (grad + grad.transpose(0, 2, 1))
    return np.linalg.norm(eps, axis=(1, 2))


def inverted(x0: np.ndarray, x1: np.ndarray, tri: np.ndarray) -> int:
    """Triangles (ne, 3) positive at ``x0`` that the step turned over at ``x1``.

    Examples
    --------
    >>> x0 = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> inverted(x0, x0 * [1.0, -1.0], np.array([[0, 1, 2]]))
    1
    """

    def area2(x: np.ndarray) -> np.ndarray:
        a, b, c = (x[tri[:, k]] for k in range(3))
        return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (
            c[:, 0] - a[:, 0]
        )

    return int(np.sum((area2(x0) > 0) & (area2(x1) <= 0)))


def collapse_load(
    values: dict, sim, x0: np.ndarray, fixed: np.ndarray, tri, base: float
) -> float:
    """The smooth rigid footing's collapse pressure over s_u on a step's start.

    One limit program on the step's own triangulation of its start positions
    ``x0`` (the same nodal integration), the particles on the footing's base
    (within a quarter spacing of it, ``base`` its height) tied vertically and
    loaded, the supports ``fixed`` held.  The soil is weightless Tresca, so
    this is a property of the configuration alone, not of the stresses.
    """
    b, h = values["width"] / 2, values["spacing"]
    used = np.unique(tri.simplices)
    local = np.full(len(x0), -1)
    local[used] = np.arange(used.size)
    mesh = MeshTri(
        np.ascontiguousarray(x0[used].T), np.ascontiguousarray(local[tri.simplices].T)
    )
    xu = x0[used]
    foot = np.flatnonzero((xu[:, 0] <= b + 1e-9) & (np.abs(xu[:, 1] - base) < h / 4))
    free = fixed[used].copy()
    free[foot, 1] = False
    load = np.zeros((used.size, 2))
    load[foot, 1] = -values["su"] * b / foot.size
    res = limit_analysis(
        nodal_integration(mesh, (0, 1, 3)),
        sim.model.materials,
        np.zeros(used.size, int),
        load,
        fixed=free,
        tied=[2 * foot + 1],
    )
    return float(res.multiplier)


def stepwise(over: dict) -> dict:
    """The footing run one step at a time: load, dip, strain and stress release."""
    values = npfem.get_scene("footing-penetration").resolve(over)
    srun = build(values, progress=False)
    sim = srun.simulation
    B, su = values["width"], values["su"]
    surface = float(sim.particles.x[:, 1].max())
    t0 = time.perf_counter()
    rows = []
    before = None  # the last step's triangles
    while sim.time < srun.run_kwargs["t_end"] * (1 - 1e-12):
        x0, s0 = sim.particles.x.copy(), sim.particles.stress.copy()
        fixed = np.asarray(sim.particles.fixed, bool).copy()
        base = surface + (sim.records[-1].extra["footing_y"] if sim.records else 0.0)
        sim.run(steps=1)
        tri = sim.mesh_source.last
        if not np.array_equal(tri.points, x0):
            raise RuntimeError("the mesher's last triangulation is not the step's")
        p, rec = sim.particles, sim.records[-1]
        footing = values["speed"] * rec.dt
        strain = element_strain(x0, p.x, tri.simplices)
        release = p.stress[:, 1] - s0[:, 1]
        now = set(map(tuple, np.sort(tri.simplices, axis=1).tolist()))
        rows.append(
            {
                "w": -rec.extra["footing_y"] / B,
                "q": rec.extra["footing_force_y"] / (B / 2) / su,
                "element_strain": float(strain.max()),
                "inverted": inverted(x0, p.x, tri.simplices),
                "largest_motion": float(
                    np.linalg.norm(p.x - x0, axis=1).max() / footing
                ),
                "stress_release": float(release.max() / su),
                "new_triangles": None if before is None else len(now - before),
                "collapse": collapse_load(values, sim, x0, fixed, tri, base),
            }
        )
        before = now
    w = np.array([r["w"] for r in rows])
    d = dips(np.array([r["q"] for r in rows]), w)
    for r, di in zip(rows, d, strict=True):
        r["dip"] = float(di)
    return {"steps": rows, "wall_s": time.perf_counter() - t0}


#: Tie-breaking of the re-solved step's triangulations: (seed, jitter / h^2).
RETRIANGULATIONS = ((0, 1e-6), (1, 1e-2), (2, 5e-2))


def resolved(over: dict, step: int) -> list[dict]:
    """The step ``step`` (0-based) solved again on other triangulations.

    The run is repeated up to that step, and the step is solved on the
    triangulation of the same particles with each tie-breaking of
    :data:`RETRIANGULATIONS` (the first is the scene's own): whether the dip
    comes from that step's mesh or from the state the step starts from.
    """
    out = []
    for seed, jitter in RETRIANGULATIONS:
        values = npfem.get_scene("footing-penetration").resolve(over)
        srun = build(values, progress=False)
        sim = srun.simulation
        sim.run(steps=step)
        sim.mesh_source.seed, sim.mesh_source.jitter = seed, jitter
        sim.run(steps=1)
        rec = sim.records[-1]
        q = rec.extra["footing_force_y"] / (values["width"] / 2) / values["su"]
        out.append({"seed": seed, "jitter": jitter, "q": q})
    return out


#: Densities of the soil given to the weightless footing's steps with inertia.
DENSITIES = (10.0, 100.0)


def inertial(rho: float) -> dict:
    """The footing at its defaults with dynamic steps and a soil of density ``rho``.

    The scene's soil is weightless and its steps quasi-static; here the steps
    keep the inertia of a soil of density ``rho`` (kg/m^3; gravity stays
    off): a swirl of particles that a quasi-static step may pick among many
    equally admissible fields costs kinetic energy.  Returns the largest dip,
    the dips of 10 % or more, the triangles turned over in the run and the
    largest particle motion of a step over the footing's.
    """
    values = npfem.get_scene("footing-penetration").resolve(OPEN)
    srun = build(values, progress=False)
    sim = srun.simulation
    sim.model.mode = "dynamic"
    sim.model.materials[0].rho = rho
    # The nodal masses are the cells' volumes times the density (the scene's
    # default nodal_mass=mesh); the particles' own masses are set alike.
    p = sim.particles
    sim.particles = p.replace(mass=rho * p.mass / p.mass.sum() * domain_area(values))
    B, su = values["width"], values["su"]
    t0 = time.perf_counter()
    q, w, turned, motion = [], [], 0, 0.0
    while sim.time < srun.run_kwargs["t_end"] * (1 - 1e-12):
        x0 = sim.particles.x.copy()
        sim.run(steps=1)
        tri, rec = sim.mesh_source.last, sim.records[-1]
        q.append(rec.extra["footing_force_y"] / (B / 2) / su)
        w.append(-rec.extra["footing_y"] / B)
        turned += inverted(x0, sim.particles.x, tri.simplices)
        step = np.linalg.norm(sim.particles.x - x0, axis=1).max()
        motion = max(motion, step / (values["speed"] * rec.dt))
    d = dips(np.array(q), np.array(w))
    return {
        "rho": rho,
        "largest_dip": float(d.max()),
        "dips": int(np.sum(d >= DIP)),
        "inverted": turned,
        "largest_motion": motion,
        "q_01": float(np.interp(0.1, w, q)),
        "wall_s": time.perf_counter() - t0,
    }


def domain_area(values: dict) -> float:
    """The modelled half-domain's area, m^2 (its width over 2 times its depth).

    Examples
    --------
    >>> domain_area({"width": 1.0, "domain_width": 10.0, "domain_depth": 5.0})
    25.0
    """
    B = values["width"]
    return 0.5 * values["domain_width"] * B * values["domain_depth"] * B


def variant(over: dict) -> dict:
    """One run's load drops, largest dip, largest fall and roughness."""
    m = run("footing-penetration", {**OPEN, **over})
    c = np.asarray(m["curve"])
    return {
        "load_drops": m["load_drops"],
        "largest_dip": float(dips(c[:, 1], c[:, 0]).max()),
        "bearing_factor": m["bearing_factor"],
        "stress_roughness_max": m["stress_roughness_max"],
        "steps": int(c.shape[0]),
        "wall_s": m["wall_s"],
    }


def tables(result: dict) -> str:
    """The step table (the dips and the median step) and the variants' table."""
    steps = result["stepwise"]["steps"]
    strain = np.array([s["element_strain"] for s in steps])
    release = np.array([s["stress_release"] for s in steps])
    turned = np.array([s["inverted"] for s in steps])
    motion = np.array([s["largest_motion"] for s in steps])
    dipped = np.array([s["dip"] >= DIP for s in steps])
    rows = [
        [
            f"{s['w']:.3f}",
            f"{s['q']:.3f}",
            f"{100 * s['dip']:.1f} %",
            s["inverted"],
            f"{s['largest_motion']:.1f}",
            f"{s['element_strain']:.2f}",
            f"{s['stress_release']:.2f}",
            s.get("new_triangles", "-"),
            f"{s['collapse']:.3f}" if "collapse" in s else "-",
        ]
        for s in steps
        if s["dip"] >= DIP
    ]
    new = [s["new_triangles"] for s in steps if s.get("new_triangles") is not None]
    rows.append(
        [
            "median step",
            f"{np.median([s['q'] for s in steps]):.3f}",
            f"{100 * np.median([s['dip'] for s in steps]):.1f} %",
            f"{np.median(turned):.0f} (most in a step without a dip: "
            f"{turned[~dipped].max(initial=0)})",
            f"{np.median(motion):.1f} (most without a dip: "
            f"{motion[~dipped].max(initial=0.0):.1f})",
            f"{np.median(strain):.2f}",
            f"{np.median(release):.2f}",
            f"{np.median(new):.0f}" if new else "-",
            f"{np.median([s.get('collapse', np.nan) for s in steps]):.3f}",
        ]
    )
    head = ["w/B", "q/s_u", "dip", "triangles turned over"]
    head += ["largest particle motion / footing's"]
    head += ["largest element strain increment", "largest s_yy release / s_u"]
    head += ["triangles new since the last step"]
    page = markdown_table([*head, "collapse load of the step's start / s_u"], rows)
    vrows = [
        [
            name,
            v["load_drops"],
            f"{100 * v['largest_dip']:.1f} %",
            f"{v['bearing_factor']:.3f}",
            f"{v['stress_roughness_max']:.3f}",
            v["steps"],
            f"{v['wall_s']:.0f} s",
        ]
        for name, v in result["variants"].items()
    ]
    again = result.get("resolved", [])
    if again:
        q = ", ".join(
            f"{r['q']:.3f} (seed {r['seed']}, jitter {r['jitter']:g})" for r in again
        )
        page += f"\n\nThe largest dip's step solved on three triangulations: {q}."
    head = ["setting", "load drops", "largest dip", "q/s_u at w = 0.1 B", "R max"]
    page += "\n\n" + markdown_table([*head, "steps", "wall"], vrows)
    runs = []
    if "inertia" in result:
        runs = [result["quasi_static"], *result["inertia"]]
    if runs:
        irows = [
            [
                "0 (quasi-static)" if r["rho"] == 0 else f"{r['rho']:g}",
                r["dips"],
                f"{100 * r['largest_dip']:.1f} %",
                r["inverted"],
                f"{r['largest_motion']:.1f}",
                f"{r['q_01']:.3f}",
            ]
            for r in runs
        ]
        head = ["soil density, kg/m^3", "dips >= 10 %", "largest dip"]
        head += ["triangles turned over (run)", "largest particle motion / footing's"]
        head.append("q/s_u at w = 0.1 B (curve interpolated)")
        page += "\n\n" + markdown_table(head, irows)
    return page + "\n"


def quasi_static(stepwise_result: dict) -> dict:
    """The step table's run in the inertia table's terms (density 0)."""
    steps = stepwise_result["steps"]
    d = np.array([s["dip"] for s in steps])
    w = [s["w"] for s in steps]
    return {
        "rho": 0.0,
        "largest_dip": float(d.max()),
        "dips": int(np.sum(d >= DIP)),
        "inverted": int(sum(s["inverted"] for s in steps)),
        "largest_motion": max(s["largest_motion"] for s in steps),
        "q_01": float(np.interp(0.1, w, [s["q"] for s in steps])),
        "wall_s": stepwise_result["wall_s"],
    }


PARTS = ("stepwise", "resolved", "variants", "inertia", "sealed")


def summary(stepwise_result: dict) -> dict:
    """A stepwise run's dips, loads and collapse loads in one row."""
    steps = stepwise_result["steps"]
    d = np.array([s["dip"] for s in steps])
    w = np.array([s["w"] for s in steps])
    limit = np.array([s["collapse"] for s in steps])
    return {
        "dips": int(np.sum(d >= DIP)),
        "largest_dip": float(d.max()),
        "largest_collapse_dip": float(dips(limit, w).max()),
        "q_01": float(np.interp(0.1, w, [s["q"] for s in steps])),
        "q_1": float(steps[-1]["q"]),
        "above_collapse": float(max(s["q"] / s["collapse"] for s in steps)),
        "wall_s": stepwise_result["wall_s"],
    }


def sealed_table(result: dict) -> str:
    """The holes open against sealed (the default), step by step."""
    rows = []
    for name, key in (
        ("seal_cavities = false", "stepwise"),
        ("seal_cavities = true (default)", "sealed"),
    ):
        if key not in result:
            continue
        r = summary(result[key])
        rows.append(
            [
                name,
                r["dips"],
                f"{100 * r['largest_dip']:.1f} %",
                f"{100 * r['largest_collapse_dip']:.1f} %",
                f"{r['q_01']:.3f}",
                f"{r['q_1']:.3f}",
                f"{r['above_collapse']:.3f}",
                f"{r['wall_s']:.0f} s",
            ]
        )
    head = ["mesh", "dips >= 10 %", "largest dip", "largest dip of the collapse load"]
    head += ["q/s_u at w = 0.1 B", "q/s_u at w = B"]
    head += ["largest q over the collapse load", "wall (with the limit programs)"]
    return markdown_table(head, rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=VALIDATION)
    ap.add_argument(
        "--parts",
        default=",".join(PARTS),
        help="the parts to run (the others kept from the JSON): " + ", ".join(PARTS),
    )
    args = ap.parse_args()
    parts = args.parts.split(",")
    path = args.out / "footing_drops.json"
    result = json.loads(path.read_text()) if path.exists() else {}
    if "stepwise" in parts:
        result["stepwise"] = stepwise(OPEN)
    dip = [s["dip"] for s in result["stepwise"]["steps"]]
    if "resolved" in parts:
        result["resolved"] = resolved(OPEN, int(np.argmax(dip)))
    if "variants" in parts:
        result["variants"] = {}
        for name, over in VARIANTS.items():
            result["variants"][name] = variant(over)
            print(name, result["variants"][name], flush=True)
    if "inertia" in parts:
        result["inertia"] = [inertial(rho) for rho in DENSITIES]
    if "inertia" in result:
        result["quasi_static"] = quasi_static(result["stepwise"])
    if "sealed" in parts:
        result["sealed"] = stepwise({})
    text = tables(result)
    if "sealed" in result:
        text += "\n" + sealed_table(result) + "\n"
    write_results(path, json.dumps(result, indent=1), text)


if __name__ == "__main__":
    main()
