#!/usr/bin/env python
"""Slopes under loads: the critical k_h, F(k_h), and a strip surcharge on the crest.

A dry cohesionless slope (beta = 20 deg, phi = 40 deg, H = 10 m) by limit
analysis at spacings H/10, H/20 and H/40: its critical k_h (one program,
gravity dead and k_h the multiplier) against the infinite slope's
``tan(phi - beta)``, and its factor of safety under k_h = 0.1 (out of the
face) and -0.1 (into it) against
``tan(phi) (cos beta - k_h sin beta) / (sin beta + k_h cos beta)``.  Then
Griffiths & Lane's 2:1 c-phi slope (c' = 10 kPa, phi' = 20 deg), which has no
closed form: its critical k_h at the same spacings, and the factor of safety
at that k_h (1 if the two programs agree); and Loukidis, Bandini & Salgado's
(2003) example 1, a dry 1V:3H c-phi slope (H = 25 m, c' = 25 kPa, phi' = 30
deg, gamma = 20 kN/m^3), whose critical k_h is published (0.432 by their
log-spiral analysis, between their limit-analysis bounds 0.423 and 0.454).
Last, a 2 m strip on the crest of
a Tresca slope (s_u = 30 kPa, H = 5 m at 30 deg): its collapse pressure 8, 2
and 0 m behind the crest's edge at spacings 0.5 and 0.25 m, the far one
against Prandtl's (2 + pi) s_u; and at the edge of the same slope made next
to weightless, at 15 and 30 deg, against the exact (2 + pi - 2 beta) s_u, as
a flexible strip and (30 deg) as a rigid smooth and rough footing.

Usage (from the repository root)::

    python demos/studies/slope_loads.py [--out docs/validation]

Writes ``<out>/slope_loads.json`` and ``<out>/slope_loads.md``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from pathlib import Path

from _common import VALIDATION
from slope_fos import SLOPE

import skfem_npfem as npfem

BETA, PHI = 20.0, 40.0
SAND = {"analysis": "limit", "refine": "none", "c": 0.0, "phi": PHI, "angle": BETA}
#: Griffiths & Lane's 2:1 c-phi slope (the slope_fos study's).
CPHI = SLOPE
SPACINGS = (1.0, 0.5, 0.25)
#: Loukidis et al.'s (2003) example 1: its published critical k_h and bounds.
LOUKIDIS = {
    "analysis": "limit",
    "refine": "none",
    "height": 25.0,
    "angle": math.degrees(math.atan(1.0 / 3.0)),
    "c": 25.0e3,
    "phi": 30.0,
    "rho": 20.0e3 / 9.81,
    "foundation_depth": 25.0,
}
LOUKIDIS_KC, LOUKIDIS_BOUNDS = 0.432, (0.423, 0.454)
#: A stable Tresca slope (gamma H / s_u = 3.3) with a 2 m strip on its crest.
CLAY = {
    "analysis": "limit",
    "refine": "none",
    "material": "tresca",
    "c": 3.0e4,
    "height": 5.0,
    "angle": 30.0,
    "foundation_depth": 5.0,
    "crest_length": 15.0,
    "toe_length": 10.0,
    "rho": 2000.0,
    "surcharge_width": 2.0,
}
OFFSETS = (8.0, 2.0, 0.0)
STRIP_SPACINGS = (0.5, 0.25)
#: The strip at the crest's edge of a (next to) weightless slope at these
#: angles: gamma H / s_u = 2e-3, against the exact (2 + pi - 2 beta) s_u.
EDGE_ANGLES = (15.0, 30.0)
LIGHT = {**CLAY, "rho": 1.0, "surcharge_offset": 0.0}


def edge_factor(beta: float) -> float:
    """The weightless Tresca collapse pressure / s_u of a strip at the edge.

    Prandtl's field with its fan narrowed from pi/2 to pi/2 - beta by the
    slope's face: ``2 + pi - 2 beta``.
    """
    return 2.0 + math.pi - 2.0 * math.radians(beta)


def infinite_slope_F(kh: float) -> float:
    """The dry cohesionless infinite slope's F under k_h (out of the face)."""
    b = math.radians(BETA)
    return (
        math.tan(math.radians(PHI))
        * (math.cos(b) - kh * math.sin(b))
        / (math.sin(b) + kh * math.cos(b))
    )


def metrics(over: dict) -> dict:
    """A limit run's metrics (its AlmostSolved notes kept in the metrics)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return npfem.run_scene("slope", over)["metrics"]


def sand_row(h: float) -> dict:
    """The cohesionless slope at spacing ``h``."""
    t0 = time.perf_counter()
    base = metrics({**SAND, "spacing": h})
    out = {"spacing": h, "critical_kh": base["critical_kh"], "F": {}}
    for kh in (0.0, 0.1, -0.1):
        m = base if kh == 0.0 else metrics({**SAND, "spacing": h, "kh": kh})
        out["F"][f"{kh:g}"] = m["factor_of_safety"]
    out["wall_s"] = time.perf_counter() - t0
    return out


def cphi_row(h: float) -> dict:
    """The c-phi slope at spacing ``h``: k_c and F at k_c."""
    t0 = time.perf_counter()
    kc = metrics({**CPHI, "spacing": h})["critical_kh"]
    F = metrics({**CPHI, "spacing": h, "kh": kc})["factor_of_safety"]
    return {
        "spacing": h,
        "critical_kh": kc,
        "F_at_critical_kh": F,
        "wall_s": time.perf_counter() - t0,
    }


def loukidis_row(h: float) -> dict:
    """Loukidis et al.'s slope at spacing ``h`` (m): k_c and F."""
    t0 = time.perf_counter()
    m = metrics({**LOUKIDIS, "spacing": h})
    return {
        "spacing": h,
        "critical_kh": m["critical_kh"],
        "F": m["factor_of_safety"],
        "wall_s": time.perf_counter() - t0,
    }


def strip_row(h: float) -> dict:
    """The strip's collapse pressure / s_u at each offset, spacing ``h``."""
    t0 = time.perf_counter()
    q = [
        metrics({**CLAY, "spacing": h, "surcharge_offset": off})["surcharge_collapse"]
        / CLAY["c"]
        for off in OFFSETS
    ]
    return {"spacing": h, "collapse_over_su": q, "wall_s": time.perf_counter() - t0}


def rough_edge_factor(beta: float) -> float:
    """An upper bound of a rough rigid strip at the edge / s_u (weightless).

    The footing's wedge moves straight down and pushes Prandtl's fans on both
    sides, the one toward the slope narrowed by ``beta``: ``2 + pi - beta``.
    """
    return 2.0 + math.pi - math.radians(beta)


def edge_row(h: float) -> dict:
    """The light slope's edge strip / s_u at each angle, spacing ``h``."""
    t0 = time.perf_counter()
    q = [
        metrics({**LIGHT, "spacing": h, "angle": b})["surcharge_collapse"] / CLAY["c"]
        for b in EDGE_ANGLES
    ]
    return {"spacing": h, "collapse_over_su": q, "wall_s": time.perf_counter() - t0}


#: The strip at the 30 deg edge as a rigid footing, against the flexible one.
FOOTING_KINDS = ("flexible", "smooth", "rough")
RIGID_SPACINGS = (0.5, 0.25, 0.125)


def rigid_row(h: float) -> dict:
    """The 30 deg edge strip / s_u as each kind of footing, spacing ``h``."""
    t0 = time.perf_counter()
    q = [
        metrics({**LIGHT, "spacing": h, "angle": 30.0, "surcharge_footing": kind})[
            "surcharge_collapse"
        ]
        / CLAY["c"]
        for kind in FOOTING_KINDS
    ]
    return {"spacing": h, "collapse_over_su": q, "wall_s": time.perf_counter() - t0}


def page(
    sand: list[dict],
    cphi: list[dict],
    loukidis: list[dict],
    strips: list[dict],
    edges: list[dict],
    rigid: list[dict],
) -> str:
    """The markdown page."""
    kc = math.tan(math.radians(PHI - BETA))
    amplification = math.sin(math.radians(2 * PHI)) / math.sin(
        math.radians(2 * (PHI - BETA))
    )
    ratios = [
        (r["critical_kh"] / kc - 1) / (r["F"]["0"] / infinite_slope_F(0.0) - 1)
        for r in sand
    ]
    lines = [
        "# Slopes under loads: critical k_h, F(k_h) and a crest surcharge",
        "",
        "Generated by `python demos/studies/slope_loads.py` on a shared 2-core "
        "machine (`slope` with `analysis=limit` on uniform lattices, `refine=none`; "
        "`kh` a horizontal body force "
        "of k_h times the weight toward +x, out of the slope's face; "
        "`critical_kh` one limit analysis with gravity as the dead load).",
        "",
        f"Dry cohesionless slope, beta = {BETA:g} deg, phi = {PHI:g} deg, "
        "H = 10 m.  Reference: the infinite slope, whose layer parallel to the "
        "face slides when its weight and k_h times its weight lean phi from "
        "the slip plane's normal: k_h,crit = tan(phi - beta) = "
        f"{kc:.4f}, F(k_h) = tan(phi) (cos beta - k_h sin beta) / (sin beta + "
        "k_h cos beta).",
        "",
        "| spacing | critical k_h | error | F(0) | error | F(0.1) | error | "
        "F(-0.1) | error | wall (s) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sand:
        cells = [f"H/{10 / r['spacing']:g}", f"{r['critical_kh']:.4f}"]
        cells.append(f"{r['critical_kh'] / kc - 1:+.2%}")
        for kh in ("0", "0.1", "-0.1"):
            F = r["F"][kh]
            cells += [f"{F:.4f}", f"{F / infinite_slope_F(float(kh)) - 1:+.2%}"]
        cells.append(f"{r['wall_s']:.0f}")
        lines.append("| " + " | ".join(cells) + " |")
    lines += [
        "",
        "The error of k_h,crit is larger than that of F: were the lattice "
        "to mobilise a friction angle phi_m for phi, F would err by "
        "tan(phi_m) / tan(phi) - 1 and k_h,crit = tan(phi_m - beta) by about "
        f"sin(2 phi) / sin(2 (phi - beta)) = {amplification:.2f} times as much "
        f"(measured: {min(ratios):.1f} to {max(ratios):.1f} times).",
        "",
        "Griffiths & Lane's 2:1 slope (c' = 10 kPa, phi' = 20 deg, "
        "gamma = 20 kN/m^3, H = 10 m; F = 1.38 by Bishop & Morgenstern): its "
        "critical k_h, and the factor of safety of the strength reduction "
        "under that k_h, which is 1 when the two programs agree.",
        "",
        "| spacing | critical k_h | F at that k_h | wall (s) |",
        "|---|---|---|---|",
    ]
    for r in cphi:
        lines.append(
            f"| H/{10 / r['spacing']:g} | {r['critical_kh']:.4f} | "
            f"{r['F_at_critical_kh']:.4f} | {r['wall_s']:.0f} |"
        )
    lo, hi = LOUKIDIS_BOUNDS
    lines += [
        "",
        "Loukidis, Bandini & Salgado's (2003) example 1: a dry slope 25 m high "
        "at 1V:3H (c' = 25 kPa, phi' = 30 deg, gamma = 20 kN/m^3; here on 25 m "
        f"of the same soil). Published critical k_h: {LOUKIDIS_KC} by their "
        f"log-spiral analysis, between their limit-analysis bounds {lo} and {hi}.",
        "",
        "| spacing | critical k_h | vs 0.432 | within the bounds | F(0) | wall (s) |",
        "|---|---|---|---|---|---|",
    ]
    for r in loukidis:
        kc = r["critical_kh"]
        lines.append(
            f"| H/{25 / r['spacing']:g} | {kc:.4f} | {kc / LOUKIDIS_KC - 1:+.2%} | "
            f"{'yes' if lo <= kc <= hi else 'no'} | {r['F']:.4f} | "
            f"{r['wall_s']:.0f} |"
        )
    prandtl = 2 + math.pi
    lines += [
        "",
        "A strip surcharge 2 m wide on the crest of a Tresca slope (s_u = 30 kPa, "
        "gamma = 19.6 kN/m^3, H = 5 m at 30 deg on 5 m of the same clay; F = 1.75 "
        "alone): its collapse pressure (`surcharge_collapse`, gravity held) over "
        "s_u, with its near edge 8, 2 and 0 m behind the crest's edge.  Far from "
        "the crest it is a strip on level ground, whose collapse pressure is "
        f"Prandtl's (2 + pi) s_u = {prandtl:.4f} s_u (the weight does no work on "
        "an isochoric mechanism under a level surface).",
        "",
        "| spacing | "
        + " | ".join(f"{off:g} m behind" for off in OFFSETS)
        + " | far vs Prandtl | wall (s) |",
        "|---" * (len(OFFSETS) + 3) + "|",
    ]
    for r in strips:
        q = r["collapse_over_su"]
        lines.append(
            f"| {r['spacing']:g} m | "
            + " | ".join(f"{v:.3f}" for v in q)
            + f" | {q[0] / prandtl - 1:+.2%} | {r['wall_s']:.0f} |"
        )
    lines += [
        "",
        "The same strip at the crest's edge (0 m behind) of the same slope made "
        "next to weightless (rho = 1 kg/m^3: gamma H / s_u = 2e-3) at two "
        "angles.  Reference: the exact collapse pressure of a weightless Tresca "
        "soil, Prandtl's field with its fan narrowed by the face's angle beta, "
        "(2 + pi - 2 beta) s_u (the weightless limit of the charts of footings "
        "near slopes).",
        "",
        "| spacing | "
        + " | ".join(
            f"beta = {b:g} deg (exact {edge_factor(b):.4f})" for b in EDGE_ANGLES
        )
        + " | wall (s) |",
        "|---" * (len(EDGE_ANGLES) + 2) + "|",
    ]
    for r in edges:
        cells = [
            f"{q:.4f} ({q / edge_factor(b) - 1:+.2%})"
            for q, b in zip(r["collapse_over_su"], EDGE_ANGLES, strict=True)
        ]
        lines.append(
            f"| {r['spacing']:g} m | " + " | ".join(cells) + f" | {r['wall_s']:.0f} |"
        )
    exact, rough = edge_factor(30.0), rough_edge_factor(30.0)
    lines += [
        "",
        "The 30 deg edge strip as a rigid footing (`surcharge_footing`: its "
        "particles move down as one, smooth, or also held horizontally, rough) "
        "beside the flexible strip, over s_u.  The smooth footing has the "
        f"flexible strip's exact load, {exact:.4f}.  A rough one cannot slide "
        "toward the slope: its wedge moves straight down and pushes the soil "
        "on both sides, Prandtl's two fans, one narrowed by beta, which gives "
        f"the upper bound 2 + pi - beta = {rough:.4f}; the rough column is "
        "against that bound.  A rigid footing's edges concentrate the shear in "
        "the elements next to them, so both converge from above and more "
        "slowly than the uniform pressure.",
        "",
        "| spacing | flexible (vs exact) | smooth (vs exact) | rough (vs bound) | "
        "wall (s) |",
        "|---" * (len(FOOTING_KINDS) + 2) + "|",
    ]
    for r in rigid:
        refs = (exact, exact, rough)
        cells = [
            f"{q:.4f} ({q / ref - 1:+.2%})"
            for q, ref in zip(r["collapse_over_su"], refs, strict=True)
        ]
        lines.append(
            f"| {r['spacing']:g} m | " + " | ".join(cells) + f" | {r['wall_s']:.0f} |"
        )
    return "\n".join(lines).replace("%", " %") + "\n"


def main() -> None:
    """Run both slopes at every spacing; write the JSON and the page."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=VALIDATION)
    args = parser.parse_args()
    sand = [sand_row(h) for h in SPACINGS]
    cphi = [cphi_row(h) for h in SPACINGS]
    loukidis = [loukidis_row(2.5 * h) for h in SPACINGS]
    strips = [strip_row(h) for h in STRIP_SPACINGS]
    edges = [edge_row(h) for h in STRIP_SPACINGS]
    rigid = [rigid_row(h) for h in RIGID_SPACINGS]
    text = page(sand, cphi, loukidis, strips, edges, rigid)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    report = {"sand": sand, "c_phi": cphi, "loukidis": loukidis, "strip": strips}
    report["edge"] = edges
    report["rigid"] = rigid
    report |= {"beta": BETA, "phi": PHI, "edge_angles": list(EDGE_ANGLES)}
    (args.out / "slope_loads.json").write_text(json.dumps(report, indent=1) + "\n")
    (args.out / "slope_loads.md").write_text(text)


if __name__ == "__main__":
    main()
