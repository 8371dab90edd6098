#!/usr/bin/env python
"""Consolidation: Terzaghi's column and Mandel's specimen, converged, and the cost.

Runs the ``consolidation`` scene (coupled steps: Darcy's dissipation of the
excess pore pressure in the step's cone program) at two or three spacings,
on the lattice and on the perturbed Delaunay mesh, against the exact series
(:mod:`skfem_npfem.scenes.consolidation.exact`):

* Terzaghi: the degree of consolidation U at T_v = 0.01 ... 1, and the
  large-deformation run (remeshed every step) against the fixed mesh;
* Mandel: the centre's pore pressure p_c / p0 at c t / a^2 = 0.01 ... 1 and
  the Mandel–Cryer peak (exact: 1.0764 p0 at c t / a^2 = 0.064, nu = 0.3);
* the cost of a coupled step against a drained step (a water table above
  the column: the static pore pressure only) and a dry one on the same mesh,
  per phase of the step.

Usage (repository root)::

    python demos/studies/consolidation.py            # print the tables
    python demos/studies/consolidation.py --tables   # and write them

``--tables`` writes ``demos/studies/results/consolidation.json``, the tables
``consolidation.inc`` beside it and the figure
``docs/validation/consolidation.png`` (included by docs/verification.md).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np
from _reporting import save_png

from skfem_npfem.scenes import get_scene, run_scene
from skfem_npfem.scenes.consolidation.exact import mandel_pressure, terzaghi_degree
from skfem_npfem.water import Water, WaterTable

ROOT = Path(__file__).resolve().parents[2]
RESULTS = Path(__file__).resolve().parent / "results"
FIGURE = ROOT / "docs" / "validation" / "consolidation.png"

TIMES = (0.01, 0.05, 0.1, 0.2, 0.5, 1.0)
TERZAGHI_SPACINGS = (0.05, 0.025, 0.0125)
MANDEL_SPACINGS = (0.1, 0.05, 0.025)
MESHES = ("lattice", "delaunay")
#: The time-step refinement: ten times shorter first and longest steps.
FINE_STEPS = {"dT": 1e-4, "dT_max": 0.002}


def _at(series: list, times) -> list[float]:
    got = {round(t, 9): v for t, v in series}
    return [got[round(t, 9)] for t in times]


def terzaghi_rows() -> list[dict]:
    """U at :data:`TIMES` for every mesh and spacing, and the remeshed run."""
    rows = []
    for mesh in MESHES:
        for h in TERZAGHI_SPACINGS:
            m = run_scene("consolidation", {"mesh": mesh, "spacing": h})["metrics"]
            u = _at(m["degree_of_consolidation"], TIMES)
            rows.append({"mesh": mesh, "spacing": h, "U": u, **_terzaghi_extra(m)})
    m = run_scene("consolidation", {"spacing": 0.025} | FINE_STEPS)["metrics"]
    u = _at(m["degree_of_consolidation"], TIMES)
    rows.append(
        {"mesh": "lattice, fine steps", "spacing": 0.025, "U": u, **_terzaghi_extra(m)}
    )
    m = run_scene("consolidation", {"spacing": 0.025, "large_deformation": True})
    m = m["metrics"]
    u = _at(m["degree_of_consolidation"], TIMES)
    rows.append({"mesh": "remeshed", "spacing": 0.025, "U": u, **_terzaghi_extra(m)})
    return rows


def _terzaghi_extra(m: dict) -> dict:
    return {
        "first_step_pressure": m["first_step_pressure"],
        "diffusion_number": m["diffusion_number"],
        "curve": m["degree_of_consolidation"],
    }


def mandel_rows() -> list[dict]:
    """p_c / p0 at :data:`TIMES` and the peak, for every mesh and spacing."""
    rows = []
    for mesh in MESHES:
        for h in MANDEL_SPACINGS:
            overrides = {"case": "mandel", "mesh": mesh, "spacing": h}
            rows.append(_mandel_row(mesh, overrides))
    overrides = {"case": "mandel", "spacing": 0.05} | FINE_STEPS
    rows.append(_mandel_row("lattice, fine steps", overrides))
    return rows


def _mandel_row(label: str, overrides: dict) -> dict:
    m = run_scene("consolidation", overrides)["metrics"]
    return {
        "mesh": label,
        "spacing": overrides["spacing"],
        "p": _at(m["centre_pressure"], TIMES),
        "peak": m["peak_pressure"],
        "curve": m["centre_pressure"],
    }


def cost(spacing: float = 0.0125, steps: int = 10) -> dict:
    """Mean time per phase of a step: coupled, drained and dry, same mesh.

    Terzaghi's column (81 x 17 nodes at the default spacing), the same load
    and time step; the drained run has a water table above the column (the
    static pore pressure's force, no pressure variable), the dry one none.
    """
    scene = get_scene("consolidation")
    out = {}
    for kind in ("coupled", "drained", "dry"):
        values = scene.resolve({"spacing": spacing, "dT_max": 1e-3})
        sim = scene.build(values).simulation
        sim.progress = False
        if kind != "coupled":
            water = None
            if kind == "drained":
                water = Water("drained", WaterTable(level=2.0), rho_w=1000.0)
            sim.model = dataclasses.replace(sim.model, water=water)
            sim.callbacks.clear()  # no pore pressure to record
        start = time.perf_counter()
        sim.run(steps=steps)
        wall = (time.perf_counter() - start) / steps
        recs = sim.records[1:]  # the first step warms the caches
        phases = {
            k: float(np.mean([r.timings[k] for r in recs])) for k in recs[0].timings
        }
        out[kind] = {
            "n_particles": int(sim.particles.n),
            "wall": wall,
            "iterations": float(np.mean([r.iterations for r in recs])),
            **phases,
        }
    return out


def markdown(data: dict) -> str:
    """The tables as a MyST fragment."""
    lines = [
        "**Terzaghi: U(T_v) against the exact series** (column 0.2 m x 1 m, "
        "first step T_v = 1e-3 growing by 1.2 per step up to 0.02)",
        "",
        "| mesh | h / H | " + " | ".join(f"T={t:g}" for t in TIMES) + " | max error |",
        "|---|---|" + "---|" * (len(TIMES) + 1),
    ]
    exact = terzaghi_degree(np.array(TIMES))
    lines.append("| exact | | " + " | ".join(f"{u:.4f}" for u in exact) + " | |")
    for r in data["terzaghi"]:
        err = np.abs(np.array(r["U"]) - exact).max()
        lines.append(
            f"| {r['mesh']} | {r['spacing']:g} | "
            + " | ".join(f"{u:.4f}" for u in r["U"])
            + f" | {err:.4f} |"
        )
    lines += [
        "",
        "**Mandel: centre pressure p_c / p0 against the exact series** (a = 1, "
        "b = 0.5, nu = 0.3, same stepping)",
        "",
        "| mesh | h / a | "
        + " | ".join(f"T={t:g}" for t in TIMES)
        + " | peak (T, p_c / p0) |",
        "|---|---|" + "---|" * (len(TIMES) + 1),
    ]
    pe = mandel_pressure(0.0, np.array(TIMES), 0.3)[:, 0]
    fine = np.linspace(1e-3, 0.5, 5000)
    pf = mandel_pressure(0.0, fine, 0.3)[:, 0]
    lines.append(
        "| exact | | "
        + " | ".join(f"{p:.4f}" for p in pe)
        + f" | {fine[pf.argmax()]:.3f}, {pf.max():.4f} |"
    )
    for r in data["mandel"]:
        lines.append(
            f"| {r['mesh']} | {r['spacing']:g} | "
            + " | ".join(f"{p:.4f}" for p in r["p"])
            + f" | {r['peak'][0]:.3f}, {r['peak'][1]:.4f} |"
        )
    c = data["cost"]
    phases = [
        k
        for k in c["coupled"]
        if k not in ("n_particles", "wall", "iterations", "output")
    ]
    lines += [
        "",
        f"**Cost of a step** (Terzaghi's column, {c['coupled']['n_particles']} "
        "particles, mean over 9 steps, seconds; ratio = coupled / drained; "
        "an elastic step has zero cones only, so Clarabel's initial KKT solve "
        "is its answer: 0 interior-point iterations)",
        "",
        "| step | wall | iterations | " + " | ".join(phases) + " |",
        "|---|---|---|" + "---|" * len(phases),
    ]
    for kind in ("coupled", "drained", "dry"):
        r = c[kind]
        lines.append(
            f"| {kind} | {r['wall']:.4f} | {r['iterations']:.1f} | "
            + " | ".join(f"{r[k]:.4f}" for k in phases)
            + " |"
        )
    ratio = [c["coupled"][k] / max(c["drained"][k], 1e-12) for k in phases]
    lines.append(
        f"| ratio | {c['coupled']['wall'] / c['drained']['wall']:.2f} | "
        "| " + " | ".join(f"{v:.2f}" for v in ratio) + " |"
    )
    return "\n".join(lines) + "\n"


def figure(data: dict, path: Path) -> None:
    """U(T) and p_c(t) of the finest lattice runs against the exact curves."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.6))
    T = np.logspace(-3, 0, 300)
    ax1.semilogx(T, terzaghi_degree(T), "k-", label="exact series")
    for r in data["terzaghi"]:
        if r["spacing"] == TERZAGHI_SPACINGS[0] or r["mesh"] == "remeshed":
            c = np.array(r["curve"])
            ax1.semilogx(
                c[:, 0], c[:, 1], ".", ms=4, label=f"{r['mesh']}, h = {r['spacing']:g}"
            )
    ax1.set_xlabel("T_v = c_v t / H^2")
    ax1.set_ylabel("U")
    ax1.set_title("Terzaghi")
    ax1.legend(fontsize=8)
    ax2.semilogx(T, mandel_pressure(0.0, T, 0.3)[:, 0], "k-", label="exact series")
    for r in data["mandel"]:
        if r["spacing"] == MANDEL_SPACINGS[0]:
            c = np.array(r["curve"])
            ax2.semilogx(
                c[:, 0], c[:, 1], ".", ms=4, label=f"{r['mesh']}, h = {r['spacing']:g}"
            )
    ax2.set_xlabel("c t / a^2")
    ax2.set_ylabel("p_c / p0")
    ax2.set_title("Mandel (centre)")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    save_png(fig, path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--tables",
        action="store_true",
        help="write the JSON, the tables and the figure",
    )
    args = parser.parse_args()
    data = {"terzaghi": terzaghi_rows(), "mandel": mandel_rows(), "cost": cost()}
    page = markdown(data)
    print(page)
    if args.tables:
        RESULTS.mkdir(parents=True, exist_ok=True)
        out = RESULTS / "consolidation.json"
        out.write_text(json.dumps(data, indent=1) + "\n")
        out.with_suffix(".inc").write_text(page)
        figure(data, FIGURE)


if __name__ == "__main__":
    main()
