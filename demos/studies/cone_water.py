#!/usr/bin/env python
"""The cone in an effective-stress clay: undrained, drained, and its Tresca twin.

Runs ``cone-penetration`` with a weightless Mohr-Coulomb clay (c' = 0,
phi' = 25 deg, psi = 0, p'_0 = sigma0 = 50 kPa, nu' = 0.3) undrained and
drained, and the same scene with a Tresca soil of the clay's undrained
strength s_u = c' cos phi' + p'_0 sin phi' and the same shear modulus
(I_r = G/s_u = 100), at each spacing D/n pushed ``push`` x D with the cone
moving a spacing a step.  Tabulates N_c = (q_c - sigma_0)/s_u of each, the
undrained N_c against the Tresca twin's and Teh & Houlsby's 1.25 + 1.84 ln I_r,
and the excess pore pressure at the shoulder (u2) and its largest value, / s_u.

Usage (from the repository root)::

    python demos/studies/cone_water.py [--n 6 8] [--push 3 4] [--out docs/validation]

Writes ``<out>/cone_water.json`` and prints the markdown table.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from _common import VALIDATION

import skfem_npfem as npfem
from skfem_npfem.laws import teh_houlsby_nc

D = 0.0357
PHI, P0 = 25.0, 5.0e4
CLAY = {"material": "mohr-coulomb", "phi": PHI, "nu": 0.3}
CASES = {
    "undrained": {**CLAY, "drainage": "undrained"},
    "drained": {**CLAY, "drainage": "drained", "water_level": 100.0},
    "tresca": {},
}


def run_row(n: int, push: float) -> dict:
    """The three cases at D/n pushed ``push`` D."""
    h = D / n
    base = {"spacing": h, "dt": h / 0.02, "penetration": push * D}
    row: dict = {"n": n, "push": push}
    su = None
    for name, over in CASES.items():
        if name == "tresca":
            over = {"su": su}
        t0 = time.perf_counter()
        m = npfem.run_scene("cone-penetration", {**base, **over})["metrics"]
        su = m.get("undrained_strength", su)
        row[name] = {
            "N_c": m["cone_factor"],
            "range": m["cone_factor_range"],
            "u2": m.get("shoulder_excess_pore_pressure"),
            "u_max": m.get("max_excess_pore_pressure"),
            "wall_s": time.perf_counter() - t0,
        }
    row["su"] = su
    return row


def markdown(rows: list[dict]) -> str:
    """One line per spacing and push."""
    ref = teh_houlsby_nc(100.0)
    lines = [
        "| D/n, push | N_c undrained | Tresca twin | vs twin | vs Teh & Houlsby "
        "| Δu2/s_u | Δu_max/s_u | N_c drained |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        u, t, d = r["undrained"], r["tresca"], r["drained"]
        lines.append(
            f"| D/{r['n']}, {r['push']:g} D | {u['N_c']:.2f} | {t['N_c']:.2f} | "
            f"{u['N_c'] / t['N_c'] - 1:+.1%} | {u['N_c'] / ref - 1:+.1%} | "
            f"{u['u2']:.2f} | {u['u_max']:.2f} | {d['N_c']:.2f} |"
        )
    return "\n".join(lines).replace("%", " %")


def main() -> None:
    """Run the rows, write the JSON, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, nargs="+", default=[6, 8])
    parser.add_argument("--push", type=float, nargs="+", default=[3.0, 4.0])
    parser.add_argument("--out", type=Path, default=VALIDATION)
    args = parser.parse_args()
    rows = [run_row(n, w) for n, w in zip(args.n, args.push, strict=True)]
    (args.out / "cone_water.json").write_text(json.dumps(rows, indent=1) + "\n")
    print(markdown(rows))


if __name__ == "__main__":
    main()
