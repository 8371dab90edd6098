#!/usr/bin/env python
"""Partially drained cone penetration: the backbone curve of the coupled cone.

Runs ``cone-penetration`` with the weightless effective-stress clay of the
CPTu study (c' = 0, phi' = 25 deg, psi = 0, p'_0 = sigma0 = 50 kPa, nu' = 0.3,
I_r = G/s_u = 100) with ``drainage=coupled`` at normalised velocities

    V = v D / c_h,   c_h = k M / gamma_w,   M = 2 G (1 - nu') / (1 - 2 nu')

(speed v = 2 cm/s; V set through the conductivity ``k``), and the same clay
drained (a water table far above: the weightless soil's static pore pressure
is uniform, so drained is the dry soil with effective stresses) and undrained,
on the same lattice with the same steps.  Each run pushes the cone ``push`` x D
from 4 D deep in a 10 D radius, 3 D of soil under the tip's last position,
spacing D/n, the cone moving spacing/``per`` a step.  It tabulates the cone
factor N = (q_c - sigma_0)/s_u: the scene's ``cone_factor`` (the median over
the last diameter) and the mean over the last diameter, and each over the
undrained run's.

Usage (from the repository root)::

    python demos/studies/cone_backbone.py [--n 8] [--per 4] [--push 3]
        [--V 0.01 0.1 1 10 100] [--tables]

``--tables`` writes ``docs/validation/cone_backbone.json``, the table
``docs/validation/cone_backbone.inc`` and the figure
``docs/validation/cone_backbone.png`` (included by
docs/validation/penetration_backbone.md).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _common import VALIDATION
from _reporting import write_result
from penetration_backbone import ratio_figure, with_ratios

import skfem_npfem as npfem
from skfem_npfem.constants import GRAVITY

D = 0.0357
SPEED = 0.02
RHO_W = 1000.0
#: The clay (its undrained strength s_u = p'_0 sin(phi') = 21.1 kPa, G = 100 s_u).
CLAY = {"material": "mohr-coulomb", "phi": 25.0, "nu": 0.3}
#: The CPTu study's domain: 4 D deep at the start, 10 D wide, 3 D under the tip.
DOMAIN = {"depth": 4 * D, "domain_below": 3.0, "domain_radius": 10.0}
VS = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0)


def conductivity(V: float, su: float, nu: float = 0.3) -> float:
    """The ``k`` (m/s) giving ``V = v D / c_h`` at the study's speed."""
    G = 100.0 * su
    M = 2 * G * (1 - nu) / (1 - 2 * nu)
    return SPEED * D / V * RHO_W * GRAVITY / M


def run(over: dict, n: int, per: float, push: float) -> dict:
    """N at the end of one push (the cone moves spacing/per a step)."""
    h = D / n
    values = {
        **CLAY,
        **DOMAIN,
        "spacing": h,
        "dt": h / per / SPEED,
        "penetration": push * D,
        **over,
    }
    t0 = time.perf_counter()
    m = npfem.run_scene("cone-penetration", values)["metrics"]
    curve = np.asarray(m["curve"])
    last = curve[curve[:, 0] >= curve[-1, 0] - 1.0 - 1e-9, 1]
    return {
        "N": m["cone_factor"],
        "N_mean": float(last.mean()),
        "V": m.get("normalised_velocity"),
        "su": m["undrained_strength"],
        "u2": m.get("shoulder_excess_pore_pressure"),
        "curve": m["curve"],
        "wall_s": time.perf_counter() - t0,
    }


def backbone(vs, n: int, per: float, push: float) -> dict:
    """The drained and undrained ends and the coupled rows at each V."""
    ends = {
        "drained": run({"drainage": "drained", "water_level": 100.0}, n, per, push),
        "undrained": run({"drainage": "undrained"}, n, per, push),
    }
    su = ends["undrained"]["su"]
    rows = []
    for V in vs:
        r = run({"drainage": "coupled", "k": conductivity(V, su)}, n, per, push)
        rows.append(r)
        print(f"V = {V:g}: N = {r['N']:.2f} (mean {r['N_mean']:.2f})", flush=True)
    keys = {"N": "ratio", "N_mean": "ratio_mean"}
    with_ratios([*rows, *ends.values()], ends["undrained"], keys)
    return {"n": n, "per": per, "push": push, "ends": ends, "rows": rows}


def markdown(res: dict) -> str:
    """One line per V, between the drained and the undrained ends."""
    lines = [
        "| run | V = v D / c_h | N (median, last D) | / undrained | "
        "N (mean, last D) | / undrained | u2 / s_u | wall (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]

    def line(name: str, V: str, r: dict) -> str:
        u = r["u2"]
        return (
            f"| {name} | {V} | {r['N']:.2f} | {r['ratio']:.3f} | "
            f"{r['N_mean']:.2f} | {r['ratio_mean']:.3f} | "
            f"{'-' if u is None else f'{u:.2f}'} | {r['wall_s']:.0f} |"
        )

    lines.append(line("drained", "0", res["ends"]["drained"]))
    lines += [line("coupled", f"{r['V']:.3g}", r) for r in res["rows"]]
    lines.append(line("undrained", "inf", res["ends"]["undrained"]))
    return "\n".join(lines) + "\n"


def figure(res: dict, path) -> None:
    """N/N_undrained against V (log), with the drained and undrained ends."""
    series = [
        ("ratio", "o-", "C0", "median over the last D"),
        ("ratio_mean", "s--", "C1", "mean over the last D"),
    ]
    title = (
        f"Cone, c'-phi' clay with p'_0 = 50 kPa, D/{res['n']}, step h/{res['per']:g}"
    )
    ratio_figure(res, series, ("V = v D / c_h", "N / N_undrained", title), path)


def main() -> None:
    """Run the curve; print the table; with ``--tables`` write it and the figure."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--V", type=float, nargs="+", default=list(VS))
    parser.add_argument("--n", type=int, default=8)
    parser.add_argument("--per", type=float, default=4.0)
    parser.add_argument("--push", type=float, default=3.0)
    parser.add_argument("--tables", action="store_true", help="write the results")
    args = parser.parse_args()
    res = backbone(args.V, args.n, args.per, args.push)
    page = markdown(res)
    print(page)
    if args.tables:
        write_result(VALIDATION / "cone_backbone.json", res)
        (VALIDATION / "cone_backbone.inc").write_text(page)
        figure(res, VALIDATION / "cone_backbone.png")


if __name__ == "__main__":
    main()
