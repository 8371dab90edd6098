#!/usr/bin/env python
"""Partially drained penetration: the footing's backbone curve q/q_undrained against V.

Runs ``footing-penetration`` (smooth strip footing, B = 1 m, half model 5 B
wide and 5 B deep) in the weightless effective-stress clay of
docs/validation/undrained_footing.md's footing test: c' = 1 kPa / cos 25 deg,
phi' = 25 deg, psi = 0, the skeleton's nu' = 0.3 and E' = 2 G (1 + nu') with
G = 10^6 / 2.99 Pa (E_u / s_u = 1000 at s_u = c' cos phi' = 1 kPa).  The soil
starts stress-free, drained and coupled alike.  The footing moves at a fixed
speed v = 1 m/s; the conductivity ``k`` sets the normalised velocity

    V = v B / c_v,   c_v = k M / gamma_w,   M = E' (1 - nu') / ((1 + nu')(1 - 2 nu'))

from ``--V`` (default 0.001 to 100).  Each row reports q/s_u at w/B = 0.1
(the scene's ``bearing_factor``) and at w/B = 0.15, and their ratio to the
same scene with ``drainage=undrained``; the drained end is the same clay dry
(weightless: its static pore pressure is nil, so drained and dry are alike).

Usage (from the repository root)::

    python demos/studies/penetration_backbone.py [--spacing 0.1] [--per 16] [--tables]

``--tables`` writes ``docs/validation/penetration_backbone.json``, the table
``docs/validation/penetration_backbone.inc`` and the figure
``docs/validation/penetration_backbone.png`` (included by
docs/validation/penetration_backbone.md).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
from _common import VALIDATION
from _reporting import save_png, write_result

import skfem_npfem as npfem
from skfem_npfem.constants import GRAVITY

#: The clay: s_u = c' cos phi' = 1 kPa, E_u / s_u = 1000.
PHI = 25.0
NU = 0.3
E_SKELETON = 2 * (1.0e6 / (2 * 1.495)) * (1 + NU)
CLAY = {
    "material": "mohr-coulomb",
    "c": 1.0e3 / math.cos(math.radians(PHI)),
    "phi": PHI,
    "psi": 0.0,
    "E": E_SKELETON,
    "nu": NU,
    "penetration": 0.15,
}
SPEED, WIDTH, RHO_W = 1.0, 1.0, 1000.0
VS = (0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0)


def constrained_modulus() -> float:
    """``M = E' (1 - nu') / ((1 + nu')(1 - 2 nu'))`` of the skeleton, Pa."""
    return E_SKELETON * (1 - NU) / ((1 + NU) * (1 - 2 * NU))


def conductivity(V: float) -> float:
    """The ``k`` (m/s) giving ``V = v B / c_v`` at the study's speed."""
    return SPEED * WIDTH * RHO_W * GRAVITY / (V * constrained_modulus())


def run(over: dict, spacing: float, per: float) -> dict:
    """q/s_u at w/B = 0.1 and 0.15 of one run (the footing moves spacing/per a step)."""
    values = {
        **CLAY,
        "spacing": spacing,
        "dt": spacing / per / SPEED,
        "speed": SPEED,
        **over,
    }
    t0 = time.perf_counter()
    m = npfem.run_scene("footing-penetration", values)["metrics"]
    return {
        "q_01": m["bearing_factor"],
        "q_015": m["final_bearing_factor"],
        "V": m.get("normalised_velocity"),
        "max_excess": m.get("max_excess_pore_pressure"),
        "wall_s": time.perf_counter() - t0,
    }


def with_ratios(runs: list[dict], undrained: dict, keys: dict[str, str]) -> None:
    """Each run's ``keys`` (value -> ratio name) over the undrained run's, in place."""
    for r in runs:
        for key, ratio in keys.items():
            r[ratio] = r[key] / undrained[key]


def backbone(vs, spacing: float, per: float) -> dict:
    """The drained and undrained ends and the coupled rows at each V."""
    ends = {
        "drained": run({}, spacing, per),
        "undrained": run({"drainage": "undrained"}, spacing, per),
    }
    rows = []
    for V in vs:
        r = run({"drainage": "coupled", "k": conductivity(V)}, spacing, per)
        rows.append(r)
        print(f"V = {V:g}: q/s_u = {r['q_01']:.3f}", flush=True)
    keys = {"q_01": "q_01_ratio", "q_015": "q_015_ratio"}
    with_ratios([*rows, *ends.values()], ends["undrained"], keys)
    return {"spacing": spacing, "per": per, "ends": ends, "rows": rows}


def markdown(res: dict) -> str:
    """One line per V, between the drained and the undrained ends."""
    lines = [
        "| run | V = v B / c_v | q/s_u at w/B = 0.1 | / undrained | "
        "q/s_u at w/B = 0.15 | / undrained | max excess u / s_u | wall (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]

    def line(name: str, V: str, r: dict) -> str:
        u = r["max_excess"]
        return (
            f"| {name} | {V} | {r['q_01']:.3f} | {r['q_01_ratio']:.3f} | "
            f"{r['q_015']:.3f} | {r['q_015_ratio']:.3f} | "
            f"{'-' if u is None else f'{u:.2f}'} | {r['wall_s']:.0f} |"
        )

    lines.append(line("drained (dry)", "0", res["ends"]["drained"]))
    lines += [line("coupled", f"{r['V']:g}", r) for r in res["rows"]]
    lines.append(line("undrained", "inf", res["ends"]["undrained"]))
    return "\n".join(lines) + "\n"


def ratio_figure(
    res: dict,
    series: list[tuple[str, str, str, str]],
    labels: tuple[str, str, str],
    path: Path,
) -> None:
    """A backbone: each run's ratio to the undrained one against V (log).

    ``series`` is ``(ratio key, marker, colour, what)``: the coupled rows and
    the drained end of each; ``labels`` the x label, y label and title.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    V = np.array([r["V"] for r in res["rows"]])
    fig, ax = plt.subplots(figsize=(6, 3.8))
    for key, mark, colour, what in series:
        ax.semilogx(
            V,
            [r[key] for r in res["rows"]],
            mark,
            color=colour,
            ms=4,
            label=f"N-PFEM coupled, {what}",
        )
        ax.axhline(
            res["ends"]["drained"][key],
            color=colour,
            lw=0.8,
            ls=":",
            label=f"drained, {what}",
        )
    ax.axhline(1.0, color="k", lw=0.8, label="undrained")
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    ax.set_title(labels[2])
    ax.legend(fontsize=7)
    fig.tight_layout()
    save_png(fig, path)


def figure(res: dict, path: Path) -> None:
    """q/q_undrained against V (log), with the drained and undrained ends."""
    series = [
        ("q_01_ratio", "o-", "C0", "w/B = 0.1"),
        ("q_015_ratio", "s--", "C1", "w/B = 0.15"),
    ]
    title = (
        f"Strip footing, weightless c'-phi' clay, B/{1 / res['spacing']:g}, "
        f"step h/{res['per']:g}"
    )
    ratio_figure(res, series, ("V = v B / c_v", "q / q_undrained", title), path)


def main() -> None:
    """Run the curve; print the table; with ``--tables`` write it and the figure."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--V", type=float, nargs="+", default=list(VS))
    parser.add_argument("--spacing", type=float, default=0.1)
    parser.add_argument("--per", type=float, default=16.0)
    parser.add_argument("--tables", action="store_true", help="write the results")
    args = parser.parse_args()
    res = backbone(args.V, args.spacing, args.per)
    page = markdown(res)
    print(page)
    if args.tables:
        write_result(VALIDATION / "penetration_backbone.json", res)
        (VALIDATION / "penetration_backbone.inc").write_text(page)
        figure(res, VALIDATION / "penetration_backbone.png")


if __name__ == "__main__":
    main()
