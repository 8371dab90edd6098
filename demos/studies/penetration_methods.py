#!/usr/bin/env python
"""Footing penetration: N-PFEM beside FEM-remap P1 and P2, toward w/B = 1.

Runs the ``footing-penetration`` scene (smooth rigid strip footing pushed
into weightless Tresca clay, half model, remeshed every step) with each
method -- ``npfem``, ``fem-remap`` with P1 elements, ``fem-remap`` with P2
elements (recovery transfer) -- for E_u/s_u = 100 (the scene's default) and
1000 (stiff enough that Prandtl's ``q/s_u = 2 + pi`` is the reference at
small w/B), at the spacing B/10 (and B/20 with ``--spacing 0.1 0.05``),
each as far as it goes toward w/B = 1 within a wall-time budget per run.

A run that stops early is recorded with where (w/B) and why: the solver's
status (a step that fails at the smallest load step), a parameter or mesh
error, or the budget.  Every run records its curve q/s_u against w/B, the
scene's metrics (``bearing_factor`` at w/B = 0.1, ``final_bearing_factor``,
``max_body_penetration``), the mapped Gauss-point stresses returned to the
yield surface (``yield_violations``, fem-remap) and its wall time.

Usage (from the repository root)::

    python demos/studies/penetration_methods.py [--spacing 0.1 0.05]
        [--ratio 100 1000] [--methods npfem p1 p2] [--budget 300]
        [--out docs/validation] [--append] [--replot]

Writes ``<out>/penetration_methods.json`` (compact: curves rounded to four
digits) and ``<out>/penetration_methods.png`` (q/s_u against w/B, one panel
per E_u/s_u, the three methods and Prandtl's line; ``--replot`` redraws it
from the JSON without running).  Wall times are from a machine shared with
other jobs.
"""

from __future__ import annotations

import argparse
import json
import math
import time
import traceback
from pathlib import Path

from _common import VALIDATION, WORK, replace_rows
from _reporting import save_png

from skfem_npfem.errors import ParameterError, SolverError
from skfem_npfem.scenes import get_scene

SCENE = "footing-penetration"
PRANDTL = 2.0 + math.pi
SU = 1.0e3  # the scene's default s_u, Pa

#: The methods compared: label -> scene parameters.
METHODS = {
    "npfem": {"method": "npfem"},
    "p1": {"method": "fem-remap", "element": "p1", "transfer": "recovery"},
    "p2": {"method": "fem-remap", "element": "p2", "transfer": "recovery"},
}
LABELS = {"npfem": "N-PFEM", "p1": "FEM-remap P1", "p2": "FEM-remap P2"}


def run_case(spacing: float, ratio: float, method: str, budget: float) -> dict:
    """One run toward w/B = 1 (stopped by a failure or the budget)."""
    scene = get_scene(SCENE)
    values = scene.resolve({"spacing": spacing, "E": ratio * SU, **METHODS[method]})
    srun = scene.build(values, out=None, progress=False)
    sim = srun.simulation
    t0 = time.perf_counter()
    stopped, reason = "end", ""
    try:
        sim.run(
            t_end=srun.run_kwargs["t_end"],
            stop=lambda s: time.perf_counter() - t0 > budget,
        )
        if sim.time < srun.run_kwargs["t_end"] * (1 - 1e-9):
            stopped, reason = "budget", f"wall-time budget {budget:g} s"
    except SolverError as err:
        stopped, reason = "solver", str(err)
    except (ParameterError, ValueError, FloatingPointError, RuntimeError) as err:
        stopped, reason = "error", f"{type(err).__name__}: {err}"
        traceback.print_exc()
    wall = time.perf_counter() - t0
    m = srun.metrics(sim) if sim.records else {}
    curve = m.get("curve", [])
    recs = sim.records
    statuses = sorted({r.status for r in recs})
    return {
        "spacing": spacing,
        "E_over_su": ratio,
        "method": method,
        "n_particles": int(sim.particles.n),
        "steps": len(recs),
        "w_over_B_reached": curve[-1][0] if curve else 0.0,
        "stopped_by": stopped,
        "reason": reason,
        "statuses": statuses,
        "bearing_factor": m.get("bearing_factor"),
        "vs_prandtl_at_0.1": None
        if m.get("bearing_factor") is None
        else m["bearing_factor"] / PRANDTL - 1.0,
        "final_bearing_factor": m.get("final_bearing_factor"),
        "max_body_penetration": m.get("max_body_penetration"),
        "yield_violations": m.get("yield_violations"),
        "remapped_steps": m.get("remapped_steps"),
        "max_dropped_elements": max(
            (r.extra.get("dropped_elements", 0) for r in recs), default=0
        ),
        "wall_time": wall,
        "curve": [[round(w, 4), round(q, 4)] for w, q in curve],
        "violations_per_step": [int(r.extra.get("yield_violations", 0)) for r in recs],
    }


def running_mean(curve: list[list[float]], half: float) -> tuple[list, list]:
    """The curve's mean over ``w/B +- half`` at each of its points.

    Averages the saw-tooth of soil nodes passing the footing's edge (one
    spacing of penetration: ``half = spacing / (2 B)``).
    """
    w = [c[0] for c in curve]
    q = [c[1] for c in curve]
    mean = []
    for wi in w:
        near = [qj for wj, qj in zip(w, q, strict=True) if abs(wj - wi) <= half + 1e-9]
        mean.append(sum(near) / len(near))
    return w, mean


def late_mean(curve: list[list[float]], lo: float = 0.5) -> float | None:
    """Mean q/s_u over the points with w/B >= ``lo`` (None: not reached)."""
    late = [q for w, q in curve if w >= lo - 1e-9]
    return sum(late) / len(late) if late and curve[-1][0] >= 1.0 - 1e-9 else None


def plot(rows: list[dict], path: Path) -> None:
    """q/s_u against w/B: one panel per E_u/s_u, the methods and Prandtl."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ratios = sorted({r["E_over_su"] for r in rows})
    fig, axes = plt.subplots(
        1, len(ratios), figsize=(5.2 * len(ratios), 4.2), squeeze=False
    )
    colours = {"npfem": "C0", "p1": "C3", "p2": "C2"}
    styles = {0.1: "-", 0.05: "--", 0.025: ":"}
    for ax, ratio in zip(axes[0], ratios, strict=True):
        for r in rows:
            if r["E_over_su"] != ratio or not r["curve"]:
                continue
            w, q = zip(*r["curve"], strict=True)
            style, colour = styles.get(r["spacing"], "-."), colours[r["method"]]
            ax.plot(w, q, style, color=colour, lw=0.6, alpha=0.35)
            wm, qm = running_mean(r["curve"], 0.5 * r["spacing"])
            ax.plot(
                wm,
                qm,
                style,
                color=colour,
                lw=1.6,
                label=f"{LABELS[r['method']]}, h = B/{1 / r['spacing']:.0f}",
            )
            if r["stopped_by"] != "end":
                ax.plot(wm[-1], qm[-1], "x", color=colour, ms=8)
        ax.axhline(PRANDTL, color="k", lw=0.8, ls=":", label="Prandtl 2 + pi")
        ax.axvline(0.1, color="0.7", lw=0.6)
        ax.set_xlabel("w/B")
        ax.set_ylabel("q/s_u")
        ax.set_title(
            f"E_u/s_u = {ratio:g}, smooth footing\n"
            "thick: mean over one spacing of w; thin: each step; x: stopped",
            fontsize=9,
        )
        ax.set_xlim(0, 1)
        ax.set_ylim(0, None)
        ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    save_png(fig, path, dpi=110)
    plt.close(fig)


def main() -> None:
    """Run the cases and write JSON + picture."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--spacing", type=float, nargs="*", default=[0.1])
    ap.add_argument("--ratio", type=float, nargs="*", default=[100.0, 1000.0])
    ap.add_argument("--methods", nargs="*", default=list(METHODS), choices=METHODS)
    ap.add_argument("--budget", type=float, default=300.0)
    ap.add_argument("--out", default=str(VALIDATION))
    ap.add_argument(
        "--append", action="store_true", help="keep the other runs of the JSON"
    )
    ap.add_argument(
        "--replot", action="store_true", help="redraw the picture from the JSON"
    )
    args = ap.parse_args()
    out = Path(args.out)
    path = out / "penetration_methods.json"
    if args.replot:
        data = json.loads(path.read_text())
        write(path, data["meta"], data["runs"])
        return
    rows = []
    for spacing in args.spacing:
        for ratio in args.ratio:
            for method in args.methods:
                row = run_case(spacing, ratio, method, args.budget)
                rows.append(row)
                bf = row["bearing_factor"]
                print(
                    f"h {spacing:g} E/su {ratio:g} {method:5s} "
                    f"w/B {row['w_over_B_reached']:.3f} ({row['stopped_by']}) "
                    f"N(0.1) {'-' if bf is None else f'{bf:.3f}'} "
                    f"final {row['final_bearing_factor']} "
                    f"viol {row['yield_violations']} {row['wall_time']:.0f} s",
                    flush=True,
                )
                WORK.mkdir(exist_ok=True)
                (WORK / "penetration_methods_partial.json").write_text(
                    json.dumps(rows, separators=(",", ":"))
                )
    if args.append and path.exists():
        old = json.loads(path.read_text())["runs"]
        rows = replace_rows(
            old, rows, key=lambda r: (r["spacing"], r["E_over_su"], r["method"])
        )
    meta = {
        "scene": SCENE,
        "interface": "smooth",
        "su": SU,
        "reference": "Prandtl 2 + pi",
        "budget_s": args.budget,
        "note": "wall times on a 2-core machine shared with other jobs",
    }
    out.mkdir(parents=True, exist_ok=True)
    write(path, meta, rows)


def write(path: Path, meta: dict, rows: list[dict]) -> None:
    """The JSON (derived numbers recomputed from the curves) and the picture."""
    order = {m: k for k, m in enumerate(METHODS)}
    rows = sorted(
        rows, key=lambda r: (r["spacing"], r["E_over_su"], order[r["method"]])
    )
    for r in rows:
        r["mean_q_w_0.5_to_1"] = late_mean(r["curve"])
    body = ",\n".join(json.dumps(r, separators=(",", ":")) for r in rows)
    path.write_text(
        '{"meta":'
        + json.dumps(meta, separators=(",", ":"))
        + ',\n"runs":[\n'
        + body
        + "\n]}\n"
    )
    plot(rows, path.with_suffix(".png"))
    print(f"wrote {path} and {path.with_suffix('.png')}")


if __name__ == "__main__":
    main()
