#!/usr/bin/env python
"""The cone factor N_c: convergence, speed against accuracy, and its trend with I_r.

Runs the ``cone-penetration`` scene (smooth cone, wished in place; the steady
N_c is the median over the last diameter of the push) for each case below and
tabulates the steady cone factor against Teh & Houlsby's (1991)
``1.25 + 1.84 ln I_r`` with the wall time of each run.

The ``d*`` cases are the first set-up (rollers on the soil's top, the tip 5 D
deep, a 5 D push; pinned by ``ROLLERS``):

* resolutions D/8, D/12, D/16, D/20 at I_r = 100 (the cone moves half a spacing a
  step; D/20 is the set-up's convergence reference);
* the time step: D/12 with the cone moving a quarter of a spacing a step;
* the trend: I_r = 30 and 300 at D/12;
* the soil's radius (its outer wall a roller): 15 D and 60 D at D/8, against
  the default 30 D.

The ``s*`` cases have sigma_0 as a surcharge on a free top and the tip 10 D
deep (today's set-up):

* pushed 5 D (the default push before the longer runs): D/8, D/12, D/16,
  I_r = 30 and 300, and a start 15 D deep at D/12;
* pushed 8 D (``-w8``), to see where the curve levels off: D/12, D/16 (the
  set-up's convergence reference), I_r = 300 and D/12 with the cone moving a
  whole spacing a step (``-dt1``);
* today's defaults, a 6 D push (``-w6``): D/12 at I_r = 30, 100 and 300, and
  at I_r = 100 with particles added where the soil stretches round the
  shoulder (``-refined``: ``refine=bodies``).

Each case is a separate process-sized run; cases already in the JSON are
kept unless ``--redo`` (so the study can be run in parts, e.g. two at once on
two cores with ``--cases``).

Usage (from the repository root)::

    python demos/studies/cone_penetration.py [--cases d8,d12,...] [--redo]
        [--threads N] [--out docs/validation]

Writes ``<out>/cone_penetration.json``, ``<out>/cone_penetration.inc`` (the
table of docs/validation/cone_penetration.md) and
``<out>/cone_penetration.png`` (the curves, and N_c error against wall
time); ``--cases ""`` only renders the table and the picture from the JSON.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
from _reporting import save_png

import skfem_npfem as npfem

D = 0.0357

#: The set-up of the first cases: the soil's top on rollers (a closed
#: container that the shaft's volume pressurises) and the tip 5 D deep.
ROLLERS = {"surface": "rollers", "depth": 5 * D, "penetration": 5 * D}
#: The push of the first surcharge cases (the default then).
FIVE = {"penetration": 5 * D}

#: Case name -> scene overrides (beyond the defaults).
CASES: dict[str, dict] = {
    "d8": {"spacing": D / 8, **ROLLERS},
    "d12": {"spacing": D / 12, **ROLLERS},
    "d16": {"spacing": D / 16, **ROLLERS},
    "d20": {"spacing": D / 20, **ROLLERS},
    "d12-dt": {"spacing": D / 12, "dt": 0.25 * (D / 12) / 0.02, **ROLLERS},
    "d12-ir30": {"spacing": D / 12, "rigidity_index": 30.0, **ROLLERS},
    "d12-ir300": {"spacing": D / 12, "rigidity_index": 300.0, **ROLLERS},
    "d8-r15": {"spacing": D / 8, "domain_radius": 15.0, **ROLLERS},
    "d8-r60": {"spacing": D / 8, "domain_radius": 60.0, **ROLLERS},
    # the surcharge on a free top, the tip 10 D deep (today's set-up), pushed 5 D
    # (the default push before the longer runs below showed N_c still rising)
    "s8": {"spacing": D / 8, **FIVE},
    "s12": {"spacing": D / 12, **FIVE},
    "s16": {"spacing": D / 16, **FIVE},
    "s12-depth15": {"spacing": D / 12, "depth": 15 * D, **FIVE},
    "s12-ir30": {"spacing": D / 12, "rigidity_index": 30.0, **FIVE},
    "s12-ir300": {"spacing": D / 12, "rigidity_index": 300.0, **FIVE},
    # a longer push (8 D): where the curve levels off
    "s12-w8": {"spacing": D / 12, "penetration": 8 * D},
    "s16-w8": {"spacing": D / 16, "penetration": 8 * D},
    "s12-ir300-w8": {"spacing": D / 12, "rigidity_index": 300.0, "penetration": 8 * D},
    # today's defaults (a 6 D push)
    "s12-w6": {"spacing": D / 12},
    # the same with particles added where the soil stretches round the shoulder
    "s12-w6-refined": {"spacing": D / 12, "refine": "bodies"},
    "s12-ir30-w6": {"spacing": D / 12, "rigidity_index": 30.0},
    "s12-ir300-w6": {"spacing": D / 12, "rigidity_index": 300.0},
    # the cone moving a whole spacing a step (the default moves half of one)
    "s12-w8-dt1": {"spacing": D / 12, "penetration": 8 * D, "dt": (D / 12) / 0.02},
}
RESOLUTION = ("d8", "d12", "d16", "d20")
#: The same model with today's set-up, refined in space, time or push length.
RESOLUTION_NOW = ("s8", "s12", "s16", "s12-w6", "s12-w8", "s12-w8-dt1", "s16-w8")
#: The convergence reference of each set-up: its finest (and longest) run.
FINEST = {"rollers": "d20", "surcharge": "s16-w8"}


def lu2004_nc(rigidity_index: float) -> float:
    """Lu et al.'s (2004) large-deformation fit for a smooth cone, isotropic stress.

    ``3.4 + 1.6 ln I_r`` (quoted from memory: docs/references.md).
    """
    return 3.4 + 1.6 * np.log(rigidity_index)


def same_model(name: str) -> bool:
    """A case of its set-up's model, refined in space or time only."""
    return name in (*RESOLUTION, *RESOLUTION_NOW, "d12-dt")


def finest(name: str, rows: dict[str, dict]) -> dict | None:
    """The reference run of the set-up of case ``name`` (rollers or surcharge)."""
    return rows.get(FINEST[CASES.get(name, {}).get("surface", "surcharge")])


def run_case(name: str, threads: int = 0) -> dict:
    """One run: the steady N_c, its window's range, the curve and the cost.

    ``threads`` (0: the scene's automatic choice) is the linear solver's
    thread count; it is not part of the case (it changes the wall time only).
    """
    overrides = dict(CASES[name])
    t0 = time.perf_counter()
    s = npfem.run_scene("cone-penetration", {**overrides, "threads": threads})
    m = s["metrics"]
    return {
        "case": name,
        "overrides": overrides,
        "D_over_h": round(D / overrides["spacing"], 3),
        "rigidity_index": overrides.get("rigidity_index", 100.0),
        "N_c": m["cone_factor"],
        "N_c_mean": m["cone_factor_mean"],
        "N_c_range": m["cone_factor_range"],
        "drops": m["cone_factor_drops"],
        "reference": m["cone_factor_reference"],
        "error": m["relative_error"],
        "max_body_penetration": m["max_body_penetration"],
        "particles": m["n_particles"],
        "inserted": m.get("inserted", 0),
        "steps": s["solver"]["steps"],
        "ipm_iterations": s["solver"]["ipm_iterations_total"],
        "peak_memory_mb": s["solver"].get("peak_memory_mb"),
        "wall_s": time.perf_counter() - t0,
        "curve": [[round(w, 4), round(q, 4)] for w, q in m["curve"]],
        "cpu_count": os.cpu_count(),
        "threads": threads,
    }


def per_diameter(curve: list[list[float]]) -> list[float]:
    """Median N_c of the steps over each whole diameter of the push from w = D."""
    c = np.asarray(curve, float)
    edges = np.arange(1.0, np.floor(c[-1, 0] + 1e-9) + 1e-9)
    return [
        float(np.median(c[(c[:, 0] > a) & (c[:, 0] <= a + 1.0), 1])) for a in edges[:-1]
    ]


def markdown(rows: dict[str, dict]) -> str:
    """The table of every case, and the resolution errors against the finest.

    ``N_c`` is the scene's steady value (median over the last diameter);
    ``per D`` the medians over each diameter of the push from w = D on (a
    steady curve has equal ones); ``drops`` counts the last diameter's steps
    whose N_c is under 0.8 times the steady value (a step where the soil round
    the cone gave way).
    """
    lines = [
        "| case | D/h | I_r | particles | steps | N_c | range (last D) "
        "| mean (last D) | per D from w = D | Teh & Houlsby | error | vs finest "
        "| drops | wall (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name in CASES:
        if name not in rows:
            continue
        r = rows[name]
        vs, best = "–", finest(name, rows)
        if best and same_model(name):
            vs = f"{r['N_c'] / best['N_c'] - 1:+.1%}"
        lo, hi = r["N_c_range"]
        steps = " / ".join(f"{q:.2f}" for q in per_diameter(r["curve"]))
        added = r.get("inserted", 0)
        particles = f"{r['particles']} + {added}" if added else f"{r['particles']}"
        lines.append(
            f"| {name} | {r['D_over_h']:g} | {r['rigidity_index']:g} "
            f"| {particles} | {r['steps']} | {r['N_c']:.2f} "
            f"| {lo:.2f}–{hi:.2f} | {r['N_c_mean']:.2f} | {steps} "
            f"| {r['reference']:.2f} | {r['error']:+.1%} "
            f"| {vs} | {r['drops']} | {r['wall_s']:.0f} |"
        )
    return "\n".join(lines) + "\n"


def picture(rows: dict[str, dict], path: Path) -> None:
    """Left: N_c against w/D (today's set-up, I_r = 100); right: error vs time.

    The right panel has every case of a set-up's model (rollers or surcharge)
    with its |N_c / N_c(reference) - 1| against its wall time.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for name in RESOLUTION_NOW:
        if name not in rows:
            continue
        r = rows[name]
        c = list(zip(*r["curve"], strict=True)) if r["curve"] else ([], [])
        a.plot(c[0], c[1], lw=1.0, label=f"{name} (N_c {r['N_c']:.2f})")
    a.axhline(npfem.laws.teh_houlsby_nc(100.0), ls="--", lw=0.8, color="grey")
    a.axhline(lu2004_nc(100.0), ls=":", lw=0.8, color="grey")
    a.set_xlabel("w / D (push from the embedded start)")
    a.set_ylabel("N_c = (q_c - sigma_0) / s_u")
    a.set_ylim(6, 12)
    a.set_title(
        "today's set-up, I_r = 100 (the other cases: the table);\n"
        "grey: Teh & Houlsby 1991 (dashed), Lu et al. 2004 (dotted)",
        fontsize=8,
    )
    a.legend(fontsize=7, loc="lower right")
    for name, r in rows.items():
        best = finest(name, rows)
        if best is None or r is best or not same_model(name):
            continue
        err = abs(r["N_c"] / best["N_c"] - 1)
        closed = bool(CASES[name].get("surface"))
        b.loglog(
            r["wall_s"],
            max(err, 1e-3),
            "s" if closed else "o",
            mfc="none" if closed else None,
        )
        b.annotate(name, (r["wall_s"], max(err, 1e-3)), fontsize=8)
    b.axhline(0.03, ls=":", color="grey")
    b.axvline(900, ls=":", color="grey")
    b.set_xlabel("wall time (s)")
    b.set_ylabel("|N_c / N_c(finest) - 1|")
    b.set_title("speed against accuracy (I_r = 100; squares: rollers on top)")
    fig.tight_layout()
    save_png(fig, path, dpi=110)
    plt.close(fig)


def plastic_zone(out: Path, spacing: float = D / 8, redo: bool = False) -> None:
    """A push of 2 D with output: the plastic zone and sigma_zz round the cone.

    The run's folder (``out/cone_penetration/zone``) is reused unless ``redo``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    from skfem_npfem.io import read_pvd, read_step

    folder = Path("out") / "cone_penetration" / "zone"
    if redo or not (folder / "result.pvd").exists():
        npfem.run_scene(
            "cone-penetration", {"spacing": spacing, "penetration": 2 * D}, out=folder
        )
    series = read_pvd(folder / "result.pvd")
    m = read_step(series[-1][1])
    tri = Triangulation(
        m.points[:, 0] / D, m.points[:, 1] / D, m.cells_dict["triangle"]
    )
    sig = m.point_data["stress"]  # rr, zz, theta-theta, rz
    centre, radius = (
        0.5 * (sig[:, 0] + sig[:, 1]),
        np.hypot(0.5 * (sig[:, 0] - sig[:, 1]), sig[:, 3]),
    )
    principal = np.stack([centre + radius, centre - radius, sig[:, 2]], axis=1)
    mobilised = 0.5 * np.ptp(principal, axis=1) / 1e4  # Tresca: 1 = yielding
    szz = -sig[:, 1] / 1e4
    fig, axes = plt.subplots(1, 2, figsize=(9, 5.2), sharey=True)
    for ax, f, label, cmap, top in (
        (axes[0], mobilised, "mobilised strength (s1 - s3) / 2 s_u", "magma", 1.0),
        (axes[1], szz, "-sigma_zz / s_u", "viridis", None),
    ):
        pc = ax.tripcolor(tri, f, shading="gouraud", cmap=cmap, vmax=top)
        fig.colorbar(pc, ax=ax, orientation="horizontal", label=label, pad=0.12)
        ax.set_aspect("equal")
        ax.set_xlim(0, 6)
        ax.set_ylim(4.5, 15)
        ax.set_xlabel("r / D")
    axes[0].set_ylabel("z / D")
    fig.suptitle(
        f"cone-penetration at D/{D / spacing:.0f}, pushed 2 D (I_r = 100, smooth)"
    )
    fig.tight_layout()
    save_png(fig, out / "cone_penetration_zone.png", dpi=100)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--out", default="docs/validation")
    ap.add_argument("--redo", action="store_true")
    ap.add_argument(
        "--threads",
        type=int,
        default=0,
        help="linear-solver threads of each run (0: automatic; 1: a core per run "
        "when two run side by side)",
    )
    ap.add_argument(
        "--zone", action="store_true", help="also draw the plastic zone (a D/8 run)"
    )
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "cone_penetration.json"
    for name in filter(None, args.cases.split(",")):
        if name not in CASES:
            raise SystemExit(f"error: unknown case {name!r}: one of {', '.join(CASES)}")
        rows = json.loads(path.read_text()) if path.exists() else {}
        if name in rows and not args.redo:
            continue
        row = run_case(name, args.threads)
        print(
            f"{name}: N_c {row['N_c']:.3f} ({row['error']:+.1%}), "
            f"{row['wall_s']:.0f} s",
            flush=True,
        )
        rows = json.loads(path.read_text()) if path.exists() else {}
        rows[name] = row
        path.write_text(json.dumps(rows, separators=(",", ":")) + "\n")
    rows = json.loads(path.read_text())
    (out / "cone_penetration.inc").write_text(markdown(rows))
    picture(rows, out / "cone_penetration.png")
    if args.zone:
        plastic_zone(out, redo=args.redo)


if __name__ == "__main__":
    main()
