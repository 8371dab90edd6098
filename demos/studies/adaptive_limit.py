#!/usr/bin/env python
"""Adaptive limit analysis against uniform lattices: accuracy for the wall time.

Three collapse problems by limit analysis, each on uniform lattices of halving
spacing and adaptively (``refine=strain``: the spacing halved where the
mechanism's plastic power concentrates, until the result changes by less
than ``refine_tol``), from the coarsest lattice:

1. **The Tresca vertical cut** (``slope``, angle 90 deg, H = 10 m, 10 m of
   foundation): ``gamma H F / c`` against 3.7764, the middle of Kammoun et al.'s
   (2010) bounds 3.7752-3.7776.
2. **Griffiths & Lane's 2:1 c-phi slope** (c' = 10 kPa, phi' = 20 deg): its
   factor of safety against the value extrapolated from the uniform lattices
   (Richardson's extrapolation from the three finest, with the order they
   show).
3. **N_c at phi = 40 deg** (``strip-footing``, smooth, weightless): against
   Prandtl's exact 75.31.

Then ``strip-footing --set analysis=limit`` as a user runs it, at the scene's
own lattice (B/25), uniform (``refine=none``) and at the default
(``refine=strain``): Tresca smooth and rough, phi = 20 deg rough and phi = 30
deg smooth, against Prandtl's exact N_c of a weightless soil (the same for a
smooth and a rough footing).

Every run is one process, one after another, on the same machine: the wall
times compare.

Usage (from the repository root)::

    python demos/studies/adaptive_limit.py [--out docs/validation] [--quick]

``--quick`` leaves out the finest uniform lattice of each.  Writes
``<out>/adaptive_limit.json`` and ``<out>/adaptive_limit.inc`` (the tables of
docs/validation/adaptive_limit.md).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from _common import VALIDATION, write_results
from slope_fos import SLOPE
from soil_profiles import run

from skfem_npfem.laws import prandtl_nc

#: The Tresca vertical cut (the test's): gamma H / c = 2 at F = 1.
CUT = {
    "analysis": "limit",
    "material": "tresca",
    "angle": 90.0,
    "height": 10.0,
    "foundation_depth": 10.0,
    "crest_length": 15.0,
    "toe_length": 15.0,
    "c": 1.0e4,
    "rho": 2.0e4 / 9.81,
}
CUT_REF = 3.7764
FOOTING = {"analysis": "limit", "material": "mohr-coulomb", "phi": 40.0, "c": 1.0e3}
#: Adaptive settings measured: the defaults, then a tighter tolerance.
ADAPTIVE = (
    {"refine": "strain"},
    {"refine": "strain", "refine_tol": 0.001, "refine_cycles": 5},
)


#: The footing's own limit analyses: (label, parameters, phi).
DEFAULT_FOOTINGS = (
    ("Tresca, smooth", {}, 0.0),
    ("Tresca, rough", {"interface": "rough"}, 0.0),
    (
        "phi = 20, rough",
        {"material": "mohr-coulomb", "phi": 20.0, "c": 1.0e3, "interface": "rough"},
        20.0,
    ),
    ("phi = 30, smooth", {"material": "mohr-coulomb", "phi": 30.0, "c": 1.0e3}, 30.0),
)


def defaults() -> list[dict]:
    """The footing at its own lattice: uniform, then the default refinement."""
    rows = []
    for label, over, phi in DEFAULT_FOOTINGS:
        for refine in ("none", "strain"):
            base = {"analysis": "limit", **over, "refine": refine}
            m = run("strip-footing", base)
            rows.append(
                {
                    "case": label,
                    "refine": refine,
                    "value": m["bearing_factor"],
                    "reference": prandtl_nc(phi),
                    "particles": m["n_particles"],
                    "wall_s": m["wall_s"],
                }
            )
            print(label, refine, m["bearing_factor"], f"{m['wall_s']:.1f} s")
    return rows


def defaults_table(rows: list[dict]) -> str:
    """The footing's defaults as a markdown table."""
    lines = [
        "| footing | refine | particles | N_c | Prandtl | error | wall (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['case']} | {r['refine']} | {r['particles']} | {r['value']:.4f} | "
            f"{r['reference']:.4f} | {r['value'] / r['reference'] - 1:+.2%} | "
            f"{r['wall_s']:.1f} |"
        )
    return "\n".join(lines).replace("%", " %")


def row(label: str, value: float, n: int, wall: float, history=None) -> dict:
    """One table row."""
    return {
        "label": label,
        "value": value,
        "particles": n,
        "wall_s": wall,
        "history": history,
    }


def series(scene, base, spacings, value, count, labels) -> list[dict]:
    """Uniform lattices at ``spacings``, then the adaptive runs from the first."""
    rows = []
    for h, lab in zip(spacings, labels, strict=True):
        m = run(scene, {**base, "spacing": h, "refine": "none"})
        rows.append(row(lab, value(m), count(m), m["wall_s"]))
        print(scene, lab, rows[-1]["value"], f"{m['wall_s']:.1f} s", flush=True)
    for over in ADAPTIVE:
        m = run(scene, {**base, "spacing": spacings[0], **over})
        hist = m["refine_history"]
        tag = "adaptive" if len(over) == 1 else "adaptive, tol 1e-3"
        rows.append(row(tag, value(m), int(hist[-1][0]), m["wall_s"], hist))
        print(scene, tag, rows[-1]["value"], f"{m['wall_s']:.1f} s", flush=True)
    return rows


def richardson(values: list[float]) -> tuple[float, float]:
    """The limit of three values at halving spacings, and the order they show."""
    a, b, c = values[-3:]
    ratio = (a - b) / (b - c)
    p = math.log2(ratio)
    return c - (b - c) / (ratio - 1.0), p


def table(rows: list[dict], ref: float, what: str) -> str:
    """A markdown table of a series against ``ref``."""
    lines = [
        f"| lattice | particles | {what} | error | wall (s) |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['label']} | {r['particles']} | {r['value']:.4f} | "
            f"{r['value'] / ref - 1:+.2%} | {r['wall_s']:.1f} |"
        )
    return "\n".join(lines).replace("%", " %")


def main() -> None:
    """Run the three series; write the JSON and the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=VALIDATION)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    n = 3 if args.quick else 4
    slope_h = (1.0, 0.5, 0.25, 0.125)[:n]
    slope_lab = ("H/10", "H/20", "H/40", "H/80")[:n]
    # The footing's finest uniform lattice is B/140 (about half the cell area
    # of B/100; a whole number of spacings across the footing, whose edge a
    # particle must sit on: B/141 was 0.19 % below B/100).
    foot_h = (0.04, 0.02, 0.01, 1.0 / 140.0)[:n]
    foot_lab = ("B/25", "B/50", "B/100", "B/140")[:n]
    count = lambda m: m["n_particles"]  # noqa: E731
    cut = series(
        "slope",
        CUT,
        slope_h,
        lambda m: m["factor_of_safety"] * 20.0,  # gamma H / c = 20
        count,
        slope_lab,
    )
    gl = series(
        "slope",
        SLOPE,
        slope_h,
        lambda m: m["factor_of_safety"],
        count,
        slope_lab,
    )
    nc = series(
        "strip-footing",
        FOOTING,
        foot_h,
        lambda m: m["bearing_factor"],
        count,
        foot_lab,
    )
    gl_ref, gl_order = richardson([r["value"] for r in gl[:n]])
    own = defaults()
    report = {
        "vertical_cut": {"reference": CUT_REF, "rows": cut},
        "griffiths_lane": {"reference": gl_ref, "order": gl_order, "rows": gl},
        "nc_phi40": {"reference": prandtl_nc(40.0), "rows": nc},
        "footing_defaults": own,
    }
    text = "\n\n".join(
        [
            table(cut, CUT_REF, "gamma H F / c"),
            table(gl, gl_ref, "F"),
            table(nc, prandtl_nc(40.0), "N_c"),
        ]
    )
    text += (
        f"\n\nGriffiths & Lane's reference: {gl_ref:.4f}, extrapolated from the "
        f"three finest uniform lattices (observed order {gl_order:.2f}).\n"
        f"\n{defaults_table(own)}\n"
    )
    write_results(
        args.out / "adaptive_limit.json", json.dumps(report, indent=1) + "\n", text
    )


if __name__ == "__main__":
    main()
