#!/usr/bin/env python
"""Real ground: strength growing with depth, a heavy cone, a softening clay.

Four measurements, each against an independent reference:

1. **Davis & Booker (1973).** A strip footing (B = 2 m) on a weightless Tresca
   clay with ``s_u = s_u0 + k z`` by limit analysis: the smooth footing at
   ``k B / s_u0 = 4`` against their 7.80 kPa (``s_u0`` = 1 kPa, ``k`` = 2
   kPa/m) at spacings B/20, B/40, B/80; then their factor ``F = q / ((2 + pi)
   s_u0 + k B / 4)`` for ``k B / s_u0`` = 0 to 10, smooth and rough, at B/40
   and B/80, against the design code's fit of their chart
   (:func:`skfem_npfem.laws.davis_booker_factor`).
2. **The cone's N_kt.** The cone in a heavy clay (rho = 1800 kg/m^3, s_u = 10
   kPa + 20 kPa/m z, E proportional to s_u) against the weightless uniform
   cone at the same rigidity index (D/8, half a spacing a step, 5 D, steady
   window 2 D): site investigation's assumption N_kt = N_c.
3. **Softening and its regularisation.** The footing pushed to w = B/2 into
   a clay of sensitivity 3 and ductility 10 at spacings B/10, B/20, B/40:
   locally (each particle's own strain) and with the nonlocal strain over
   0.2 B; the mean resistance over w = 0.2..0.5 B and the ideally plastic
   clay's beside it.
4. **Rate.** The same footing (B/10, to w = 0.3 B) with mu = 0.1: ten times
   the speed with ten times the reference rate, and ten times the speed alone.
5. **A heavy clay under the pushed footing** (B/10, to w = 0.3 B, gamma B /
   s_u = 1 and 2.9): the net resistance ``(q - gamma w) / s_u`` against the
   weightless clay's ``q / s_u`` (the weight does no other net work on an
   isochoric mechanism).

Usage (from the repository root)::

    python demos/studies/soil_profiles.py [--out docs/validation] [--quick]
        [--parts davis_booker cone softening rate heavy]

``--quick`` leaves out the B/40 softening runs and the cone (minutes instead
of about half an hour); ``--parts`` runs only those parts and takes the others
from the report already in ``--out``.  Writes ``<out>/soil_profiles.json`` and
``<out>/soil_profiles.inc`` (the tables of docs/validation/soil_profiles.md).
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from pathlib import Path

import numpy as np
from _common import VALIDATION, write_results

import skfem_npfem as npfem
from skfem_npfem.laws import davis_booker_factor

#: Davis & Booker's smooth strip at k B / s_u0 = 4 (PLAXIS 2D Validation
#: Manual, section 3.2), Pa.
DAVIS_BOOKER_Q = 7.80e3
FOOTING = {"analysis": "limit", "refine": "none", "c": 1.0e3, "width": 2.0}
DB_SPACINGS = (0.1, 0.05, 0.025)
F_SPACINGS = (0.05, 0.025)
KAPPAS = (0.0, 1.0, 2.0, 4.0, 10.0)
D = 0.0357
CONE = {"spacing": D / 8, "dt": D / 16 / 0.02, "penetration": 5 * D}
CONE_GROUND = {"rho": 1800.0, "su_gradient": 2.0e4}
SOFT = {"E": 1.0e6, "penetration": 0.5, "sensitivity": 3.0, "ductility": 10.0}
SOFT_LENGTH = 0.2
RATE = {"E": 1.0e6, "penetration": 0.3, "spacing": 0.1, "rate_parameter": 0.1}
HEAVY = {"E": 1.0e6, "penetration": 0.3, "spacing": 0.1}
DENSITIES = (100.0, 300.0)
PARTS = ("davis_booker", "cone", "softening", "rate", "heavy")


def run(scene: str, over: dict) -> dict:
    """A run's metrics (solver notes silenced) and its wall time."""
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = npfem.run_scene(scene, over)["metrics"]
    return {**m, "wall_s": time.perf_counter() - t0}


def davis_booker() -> dict:
    """The smooth strip at k B / s_u0 = 4 by spacing; F(k B / s_u0) at B/40, B/80."""
    conv = []
    for h in DB_SPACINGS:
        m = run("strip-footing", {**FOOTING, "su_gradient": 2.0e3, "spacing": h})
        conv.append({"spacing": h, "q": m["q_ult"], "wall_s": m["wall_s"]})
    table = []
    for kappa in KAPPAS:
        row = {"kappa": kappa}
        for interface in ("smooth", "rough"):
            row[f"{interface}_fit"] = davis_booker_factor(kappa, interface)
            for h in F_SPACINGS:
                over = {**FOOTING, "spacing": h, "interface": interface}
                over["su_gradient"] = kappa * 1.0e3 / 2.0
                q = run("strip-footing", over)["q_ult"]
                key = interface if h == F_SPACINGS[0] else f"{interface}_fine"
                row[key] = q / ((2 + math.pi) * 1.0e3 + kappa * 1.0e3 / 4)
        table.append(row)
    return {"convergence": conv, "F": table}


def cone() -> dict:
    """N_c of the uniform cone and N_kt of the heavy one, with their curves."""
    over = {**CONE, "steady_window": 2.0}
    out = {}
    for name, extra in (("uniform", {}), ("ground", CONE_GROUND)):
        m = run("cone-penetration", {**over, **extra})
        out[name] = {
            k: m[k] for k in ("cone_factor", "cone_factor_mean", "curve", "wall_s")
        }
        out[name]["q_net"] = m["q_net"]
    return out


def late_mean(curve: list) -> float:
    """Mean q/s_u over w/B >= 0.2."""
    c = np.asarray(curve)
    return float(c[c[:, 0] >= 0.2, 1].mean())


def softening(spacings: tuple[float, ...]) -> list[dict]:
    """Local and nonlocal softening, and the ideal clay, at each spacing."""
    rows = []
    for h in spacings:
        row = {"spacing": h}
        for name, over in (
            ("ideal", {"E": 1.0e6, "penetration": 0.5}),
            ("local", SOFT),
            ("nonlocal", {**SOFT, "softening_length": SOFT_LENGTH}),
        ):
            m = run("footing-penetration", {**over, "spacing": h})
            row[name] = late_mean(m["curve"])
            row[f"{name}_wall_s"] = m["wall_s"]
        rows.append(row)
    return rows


def rate() -> dict:
    """The speed's effect with and without the reference rate scaled with it."""
    out = {}
    for name, over in (
        ("slow", {"speed": 1.0, "reference_rate": 1e-2}),
        ("both", {"speed": 10.0, "reference_rate": 1e-1}),
        ("fast", {"speed": 10.0, "reference_rate": 1e-2}),
    ):
        out[name] = run("footing-penetration", {**RATE, **over})["curve"]
    slow, both, fast = (np.asarray(out[k])[1:, 1] for k in ("slow", "both", "fast"))
    out["both_vs_slow_max"] = float(np.abs(both / slow - 1).max())
    rise = fast / slow - 1
    out["fast_vs_slow"] = [float(rise.min()), float(rise.mean()), float(rise.max())]
    return out


def heavy() -> list[dict]:
    """The heavy clay's net curve against the weightless clay's, per density."""
    light = np.asarray(run("footing-penetration", HEAVY)["curve"])
    late = light[:, 0] >= 0.1
    rows = []
    for rho in DENSITIES:
        m = run("footing-penetration", {**HEAVY, "rho": rho})
        net, raw = np.asarray(m["net_curve"]), np.asarray(m["curve"])
        rows.append(
            {
                "rho": rho,
                "gamma_B_over_su": rho * 9.81 * 1.0 / 1.0e3,
                "light": float(light[late, 1].mean()),
                "net": float(net[late, 1].mean()),
                "raw": float(raw[late, 1].mean()),
            }
        )
    return rows


def tables(report: dict) -> str:
    """The markdown tables of the page."""
    db = report["davis_booker"]
    lines = [
        "| spacing | q (kPa) | vs 7.80 kPa | wall (s) |",
        "|---|---|---|---|",
    ]
    for r in db["convergence"]:
        lines.append(
            f"| B/{2 / r['spacing']:g} | {r['q'] / 1e3:.3f} | "
            f"{r['q'] / DAVIS_BOOKER_Q - 1:+.2%} | {r['wall_s']:.1f} |"
        )
    lines += [
        "",
        "| k B / s_u0 | F smooth B/40 | B/80 | fit | B/80 vs fit "
        "| F rough B/40 | B/80 | fit | B/80 vs fit |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in db["F"]:
        cells = [f"{r['kappa']:g}"]
        for i in ("smooth", "rough"):
            fine, fit = r[f"{i}_fine"], r[f"{i}_fit"]
            cells += [f"{r[i]:.3f}", f"{fine:.3f}", f"{fit:.3f}"]
            cells.append(f"{fine / fit - 1:+.1%}")
        lines.append("| " + " | ".join(cells) + " |")
    if "cone" in report:
        c = report["cone"]
        u, g = c["uniform"], c["ground"]
        lines += [
            "",
            "| cone | steady factor (median) | mean over the window | wall (s) |",
            "|---|---|---|---|",
            f"| weightless, uniform: N_c | {u['cone_factor']:.3f} | "
            f"{u['cone_factor_mean']:.3f} | {u['wall_s']:.0f} |",
            f"| heavy, s_u(z): N_kt | {g['cone_factor']:.3f} "
            f"({g['cone_factor'] / u['cone_factor'] - 1:+.1%}) | "
            f"{g['cone_factor_mean']:.3f} | {g['wall_s']:.0f} |",
        ]
    lines += [
        "",
        "| spacing | ideal | local softening | nonlocal (0.2 B) | "
        "local vs previous | nonlocal vs previous |",
        "|---|---|---|---|---|---|",
    ]
    prev = None
    for r in report["softening"]:
        ch = ["", ""]
        if prev is not None:
            ch = [
                f"{r['local'] / prev['local'] - 1:+.1%}",
                f"{r['nonlocal'] / prev['nonlocal'] - 1:+.1%}",
            ]
        lines.append(
            f"| B/{1 / r['spacing']:g} | {r['ideal']:.3f} | {r['local']:.3f} | "
            f"{r['nonlocal']:.3f} | {ch[0]} | {ch[1]} |"
        )
        prev = r
    rt = report["rate"]
    lo, mean, hi = rt["fast_vs_slow"]
    lines += [
        "",
        "| rate check | measured |",
        "|---|---|",
        f"| 10 x speed and 10 x reference rate vs 1 x | {rt['both_vs_slow_max']:.1e} "
        "(largest relative difference of a step) |",
        f"| 10 x speed alone vs 1 x | {lo:+.1%} to {hi:+.1%}, mean {mean:+.1%} |",
    ]
    if "heavy" in report:
        lines += [
            "",
            "| gamma B / s_u | weightless q/s_u | heavy (q - gamma w)/s_u | "
            "heavy q/s_u |",
            "|---|---|---|---|",
        ]
        for r in report["heavy"]:
            lines.append(
                f"| {r['gamma_B_over_su']:.2f} | {r['light']:.3f} | {r['net']:.3f} "
                f"({r['net'] / r['light'] - 1:+.1%}) | {r['raw']:.3f} |"
            )
    return "\n".join(lines).replace("%", " %") + "\n"


def main() -> None:
    """Run the four studies; write the JSON and the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=VALIDATION)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--parts", nargs="*", choices=PARTS, default=list(PARTS))
    args = parser.parse_args()
    saved = args.out / "soil_profiles.json"
    report = json.loads(saved.read_text()) if saved.exists() else {}
    parts = {
        "davis_booker": davis_booker,
        "cone": cone,
        "softening": lambda: softening(
            (0.1, 0.05) if args.quick else (0.1, 0.05, 0.025)
        ),
        "rate": rate,
        "heavy": heavy,
    }
    for name in args.parts:
        if name == "cone" and args.quick:
            continue
        report[name] = parts[name]()
    text = tables(report)
    write_results(
        args.out / "soil_profiles.json", json.dumps(report, indent=1) + "\n", text
    )


if __name__ == "__main__":
    main()
