#!/usr/bin/env python
"""Stress oscillation per method: roughness over time and sigma_v pictures.

Two dynamic problems, each run with N-PFEM, FEM-remap (P1 and P2, patch
recovery) and the explicit SPFEM through the same scene (``--set method=``):

1. **Granular column collapse**, a = 2 (scene ``column-collapse``: half column
   L0 = 0.2 m against a smooth wall, Mohr-Coulomb phi = 30 deg, psi = 0, rough
   floor), from release to rest.  The stress roughness ``R`` of every step
   (``stress_roughness`` of the step records: rms over interior particles of
   the departure of sigma_v from its mesh neighbours' mean, relative to rms
   sigma_v; ``skfem_npfem.metrics``) against the normalised time
   ``t_bar = t / sqrt(H0 / g)``, and the vertical stress of the particles at
   ``t_bar`` = 1, 2, 3 and at rest (the VTU files of the runs), side by side.
2. **Elastic column under sudden gravity** (scene ``elastic-column``, dynamic,
   H = 4 m, E = 10 MPa, rho = 2000 kg/m^3, released from rest and
   stress-free): ``R`` and the top settlement over two first-mode periods
   ``T = 4 H / c_p``.  SPFEM runs undamped (its default), the implicit methods
   with the backward-Euler scheme of the scene (theta = 1), which damps the
   high modes.

Each configuration runs in its own process (``_study.run_cases``
on Dask), its folder under ``--work`` (default ``out/comparison/oscillation``;
a rerun reuses finished runs).  Writes ``oscillation.json``,
``oscillation.png`` (R over time) and ``oscillation_sigma_v.png`` (pictures)
under ``--out`` (default ``docs/validation/comparison``).

Usage (from the repository root)::

    python demos/studies/compare_oscillation.py              # full: L0/16, ~20 CPU-min
    python demos/studies/compare_oscillation.py --quick    # reduced (tests), in-process
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
from _common import ROOT, benchmark
from _reporting import markdown_table, save_png, write_result
from _study import run_cases, study_arguments, study_folders

from skfem_npfem.io import read_pvd, read_step

OUT = ROOT / "docs" / "validation" / "comparison"
WORK = ROOT / "out" / "comparison" / "oscillation"
G = 9.81

#: Methods compared: label -> scene parameters.
METHODS = {
    "N-PFEM": {"method": "npfem"},
    # N-PFEM as before the stabilisation (particle masses, no stabilisation, no volume
    # correction): the before/after pictures of docs/validation.md.
    "N-PFEM unstabilised": {
        "method": "npfem",
        "nodal_mass": "particle",
        "stabilisation": 0.0,
        "volume_correction": 0.0,
    },
    "FEM-remap P1": {"method": "fem-remap", "element": "p1", "transfer": "recovery"},
    "FEM-remap P2": {"method": "fem-remap", "element": "p2", "transfer": "recovery"},
    "SPFEM": {"method": "spfem"},
}
#: Normalised times of the pictures (plus the final state, at rest).
T_BARS = (1.0, 2.0, 3.0)


def collapse_params(quick: bool) -> dict:
    """The a = 2 collapse: every step written (pictures at any t_bar)."""
    if quick:
        return {"aspect": 2.0, "spacing": 0.2 / 6, "t_end": 0.25, "output_every": 1}
    return {"aspect": 2.0, "spacing": 0.2 / 16, "output_every": 1}


def column_period(H: float = 4.0, E: float = 1.0e7, nu=0.3, rho=2000.0) -> float:
    """First oedometric period ``4 H / c_p`` of the scene's default column, s."""
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    return 4 * H / math.sqrt(M / rho)


def column_params(quick: bool) -> dict:
    """Sudden gravity on the elastic column: two first-mode periods."""
    steps = 20 if quick else 80
    return {
        "mode": "dynamic",
        "spacing": 0.25 if quick else 0.125,
        "dt": round(2 * column_period() / steps, 9),
        "steps": steps,
    }


def cases(quick: bool) -> dict:
    """All configurations: (scene, params) by name."""
    out = {}
    col = column_params(quick)
    for label, method in METHODS.items():
        key = label.lower().replace(" ", "-")
        out[f"collapse_{key}"] = (
            "column-collapse",
            {**collapse_params(quick), **method},
        )
        out[f"column_{key}"] = ("elastic-column", {**col, **method})
    return out


def snapshots(folder: Path, t_scale: float) -> list[dict]:
    """Particle states at the t_bar of :data:`T_BARS` (nearest output) and the end."""
    series = read_pvd(folder / "result.pvd")
    times = np.array([t for t, _ in series])
    picks = [(float(tb), int(np.argmin(np.abs(times - tb * t_scale)))) for tb in T_BARS]
    picks = [(tb, k) for tb, k in picks if times[-1] >= tb * t_scale * 0.98]
    picks.append((float(times[-1] / t_scale), len(series) - 1))
    out = []
    for tb, k in picks:
        m = read_step(series[k][1])
        cells = np.vstack([c.data for c in m.cells if c.type == "triangle"])
        out.append(
            {
                "t_bar_target": tb,
                "t_bar": float(times[k] / t_scale),
                "x": m.points[:, :2],
                "cells": cells,
                "sigma_v": np.asarray(m.point_data["stress"])[:, 1],
            }
        )
    return out


def summarise(summaries: dict, quick: bool) -> dict:
    """The JSON result: roughness histories and scalar metrics per method."""
    cp = collapse_params(quick)
    H0 = cp["aspect"] * 0.2
    t_scale = math.sqrt(H0 / G)
    period = column_period()
    result = {
        "quick": quick,
        "t_scale": t_scale,
        "period": period,
        "collapse": {},
        "column": {},
    }
    for label in METHODS:
        key = label.lower().replace(" ", "-")
        for problem, scale in (("collapse", t_scale), ("column", period)):
            s = summaries.get(f"{problem}_{key}")
            if s is None:
                result[problem][label] = None
                continue
            hist = s["history"]
            entry = {
                "t": [h["time"] / scale for h in hist],
                "roughness": [h.get("stress_roughness") for h in hist],
                "stress_roughness": s["metrics"]["stress_roughness"],
                "stress_roughness_max": s["metrics"]["stress_roughness_max"],
                "steps": s["solver"]["steps"],
                "wall_time": s["wall_time_total"],
            }
            if problem == "column":
                entry["settlement"] = [h.get("settlement_top") for h in hist]
                entry["settlement_exact"] = s["metrics"]["settlement_exact"]
            else:
                entry["normalised_runout"] = s["metrics"]["normalised_runout"]
                entry["at_rest"] = s["metrics"]["at_rest"]
            result[problem][label] = entry
    return result


def at_times(entry: dict, t_bars) -> list[float | None]:
    """Roughness at the steps nearest to the given normalised times."""
    t = np.array(entry["t"])
    out = []
    for tb in t_bars:
        k = int(np.argmin(np.abs(t - tb)))
        out.append(entry["roughness"][k] if abs(t[k] - tb) < 0.05 else None)
    return out


def table(result: dict) -> str:
    """Markdown: roughness per method at t_bar = 1, 2, 3, at rest, max; column."""
    rows = []
    for label in METHODS:
        c, e = result["collapse"][label], result["column"][label]
        if c is None or e is None:
            rows.append([label] + ["failed"] * 7)
            continue
        rows.append(
            [
                label,
                *at_times(c, T_BARS),
                c["stress_roughness"],
                c["stress_roughness_max"],
                e["stress_roughness_max"],
                e["stress_roughness"],
            ]
        )
    head = [
        "method",
        *(f"collapse R, t̄ = {tb:g}" for tb in T_BARS),
        "collapse R at rest",
        "collapse R max",
        "column R max",
        "column R end",
    ]
    return markdown_table(head, rows)


def plot_roughness(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    for label in METHODS:
        c, e = result["collapse"][label], result["column"][label]
        if c is not None:
            axes[0].plot(c["t"], _nan(c["roughness"]), label=label)
        if e is not None:
            axes[1].plot(e["t"], _nan(e["roughness"]), label=label)
            u = np.array(_nan(e["settlement"])) / e["settlement_exact"]
            axes[2].plot(e["t"], u, label=label)
    axes[0].set_xlabel("t / sqrt(H0/g)")
    axes[0].set_title("column collapse a = 2: stress roughness")
    axes[1].set_xlabel("t / T (first oedometric period)")
    axes[1].set_title("elastic column, sudden gravity: roughness")
    axes[2].set_xlabel("t / T")
    axes[2].set_title("top settlement / static settlement")
    for ax in axes[:2]:
        ax.set_ylabel("R")
        ax.set_yscale("log")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    save_png(fig, path)


def plot_pictures(pictures: dict, rho_g_h: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    labels = [k for k in METHODS if pictures.get(k)]
    ncol = max(len(pictures[k]) for k in labels)
    snaps = [s for k in labels for s in pictures[k]]
    x_max = max(float(s["x"][:, 0].max()) for s in snaps)
    y_max = max(float(s["x"][:, 1].max()) for s in snaps)
    width = 3.4
    height = width * y_max / x_max + 0.35
    fig, axes = plt.subplots(
        len(labels),
        ncol,
        figsize=(width * ncol + 1.2, height * len(labels)),
        squeeze=False,
    )
    for i, label in enumerate(labels):
        for j in range(ncol):
            ax = axes[i, j]
            ax.set_axis_off()
            if j >= len(pictures[label]):
                continue
            snap = pictures[label][j]
            tri = Triangulation(snap["x"][:, 0], snap["x"][:, 1], snap["cells"])
            im = ax.tripcolor(
                tri,
                snap["sigma_v"] / rho_g_h,
                shading="gouraud",
                vmin=-1.0,
                vmax=0.0,
                cmap="viridis",
            )
            ax.set_xlim(0.0, x_max)
            ax.set_ylim(0.0, y_max)
            ax.set_aspect("equal")
            last = j == len(pictures[label]) - 1
            when = "end" if last else f"t̄ = {snap['t_bar']:.2f}"
            ax.set_title(f"{label}, {when}", fontsize=8)
    fig.colorbar(im, ax=axes, shrink=0.6, label="sigma_v / (rho g H0)")
    save_png(fig, path)


def _nan(values) -> list[float]:
    return [np.nan if v is None else v for v in values]


#: The table of the docs page, the one this study stores in its JSON (--tables).
docs_tables = benchmark("_tables")
TABLES = docs_tables.stored(
    "docs/validation/comparison/oscillation.json", "oscillation"
)


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    study_arguments(ap, OUT, WORK)
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    args = ap.parse_args(argv)
    if args.tables:
        docs_tables.write(TABLES)
        return {}
    start = time.perf_counter()
    work, out, workers = study_folders(args, OUT, "quick" if args.quick else "full")
    summaries = run_cases(
        cases(args.quick), work, workers=workers, scheduler=args.scheduler
    )
    result = summarise(summaries, args.quick)
    cp = collapse_params(args.quick)
    H0 = cp["aspect"] * 0.2
    t_scale = result["t_scale"]
    pictures = {}
    for label in METHODS:
        key = label.lower().replace(" ", "-")
        if summaries.get(f"collapse_{key}") is not None:
            pictures[label] = snapshots(work / f"collapse_{key}", t_scale)
    result["pictures_t_bar"] = {k: [s["t_bar"] for s in v] for k, v in pictures.items()}
    result["wall_time"] = time.perf_counter() - start
    text = table(result)
    result["table"] = text
    write_result(out / "oscillation.json", result)
    plot_roughness(result, out / "oscillation.png")
    plot_pictures(pictures, 1800.0 * G * H0, out / "oscillation_sigma_v.png")
    print(text)
    return result


if __name__ == "__main__":
    main()
