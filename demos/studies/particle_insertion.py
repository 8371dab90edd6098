#!/usr/bin/env python
"""A footing pushed to w = B with and without particles added where the soil stretches.

``footing-penetration`` (weightless Tresca clay, E/s_u = 100) at its default
spacing (B/20), smooth and rough, with ``refine=none``, ``refine=bodies``
(a particle at the middle of every edge stretched beyond 1.6 times its
particles' lattice spacing, before each step) and ``refine=strain`` (the
target spacing halved at the particles that carry half of the last step's
plastic power, and the edges round them split at 1.6 times it), with the
holes the alpha test opens inside the soil kept meshed (the scene's default)
and, with ``--footing-holes open``, left open.  For each
run: the bearing factor at w = 0.1 B, the load drops (``load_drops``: a step
under 80 % of the running median), the largest one-step fall of q/s_u in the
second half of the push (relative to the median load there), the particles
added, the largest stress roughness and the wall time.  The runs are one
process, one after another: the wall times compare.

The cone part runs ``cone-penetration`` at its defaults (D/12, a 6 D push)
with ``refine=none``, ``bodies`` and ``strain``: the steady N_c (the median over
the last diameter), the mean and median of N_c over the last two diameters,
the largest one-step fall there over that mean, the particles added and the
wall time (about 15 minutes each).

The collapse part runs the plane-strain ``column-collapse`` (a = 2) at
L0/22 (the default) and L0/44, each on the uniform lattice and on the graded
one (``refine=surface``: the spacing in a band of four spacings along the
free surfaces and the floor, twice it in the core), and at L0/22 refined
where it flows (``refine=strain``, ``refine_ratio`` 1.6), to rest: the
run-out, the main body's edge, the height, the largest stress roughness, the
volume change, the particle count and the wall time (about 35 minutes in
all, 20 of them the refined run).

The slope part runs the dry sand cut of the slope's run-out tests (H = 2 m
at 60 deg, phi = 30 deg, c = 0, failing as it is) to rest at H/5, H/10, H/20
and H/40, uniform and with ``refine=surface`` (a particle added at the
middle of every edge of the sliding soil stretched beyond 1.6 spacings): the
run-out from the toe, the moved volume, the particle counts and the wall time
(about 30 minutes in all, most of it the two H/40 runs).

Usage (from the repository root)::

    python demos/studies/particle_insertion.py [--out docs/validation]
        [--spacing H] [--parts footing,cone,collapse,slope]
        [--footing-refine none,bodies,strain] [--footing-holes sealed,open]
        [--cone-refine ...]
        [--collapse-refine none,surface,strain]

Writes ``<out>/particle_insertion.json`` and ``<out>/particle_insertion.inc``
(the tables of docs/validation/particle_insertion.md); a part not run keeps
its rows from the JSON, and so do the settings of a part not named in its
``--<part>-refine`` (e.g. ``--parts cone --cone-refine strain`` adds the cone's
refined row).  The footing part takes about 15 minutes.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from _common import VALIDATION, write_results
from _reporting import markdown_table
from slope_fos import RUNOUT
from soil_profiles import run

#: The insertion settings compared (the scene's default ratio): none, the
#: stretched edges round the body, and the target halved where the soil flows
#: plastically (``refine=strain``, the scene's ``refine_share``).
REFINES = ("none", "bodies", "strain")
INTERFACES = ("smooth", "rough")
#: The footing's holes inside the soil: kept meshed (the scene's default,
#: ``seal_cavities=true``) or opened by the alpha test (``false``).
HOLES = ("sealed", "open")


def largest_fall(curve: list[list[float]]) -> float:
    """The largest one-step fall of the load over w > B/2, over its median there."""
    c = np.asarray(curve)
    tail = c[:, 0] > 0.5
    q = c[:, 1]
    falls = -np.diff(q)[tail[1:]]
    return float(falls.max(initial=0.0) / np.median(q[tail]))


def cone_case(refine: str) -> dict:
    """The default cone pushed 6 D with ``refine``; its last two diameters."""
    m = run("cone-penetration", {"refine": refine})
    c = np.asarray(m["curve"])
    q = c[c[:, 0] >= c[-1, 0] - 2.0, 1]
    mean, median = float(q.mean()), float(np.median(q))
    return {
        "refine": refine,
        "cone_factor": m["cone_factor"],
        "mean_2D": mean,
        "median_2D": median,
        "largest_fall_2D": float((-np.diff(q)).max(initial=0.0) / mean),
        "cone_factor_drops": m["cone_factor_drops"],
        "inserted": m["inserted"],
        "n_particles": m["n_particles"],
        "wall_s": m["wall_s"],
    }


def cone_table(cases: list[dict]) -> str:
    """The cone part's table."""
    rows = [
        [
            c["refine"],
            f"{c['cone_factor']:.3f}",
            f"{c['mean_2D']:.3f} / {c['median_2D']:.3f}",
            f"{100 * (c['mean_2D'] / c['median_2D'] - 1):+.1f} %",
            f"{100 * c['largest_fall_2D']:.1f} %",
            c["cone_factor_drops"],
            f"{c['n_particles']} + {c['inserted']}",
            f"{c['wall_s']:.0f} s",
        ]
        for c in cases
    ]
    head = ["refine", "N_c (median, last D)", "mean / median (last 2 D)"]
    head += ["mean vs median", "largest fall (last 2 D)", "drops", "particles"]
    return markdown_table([*head, "wall"], rows)


#: The collapse part's lattices: L0 / spacing.
COLLAPSE_RESOLUTIONS = (22, 44)


#: The collapse's settings: uniform, graded, refined where it flows (the
#: footing's split ratio, 1.6).
COLLAPSE_REFINES = ("none", "surface", "strain")


def collapse_case(n: int, refine: str) -> dict:
    """The plane-strain column at L0/n with ``refine``, to rest."""
    over = {"spacing": 0.2 / n, "refine": refine}
    if "strain" in refine:
        over["refine_ratio"] = 1.6
    m = run("column-collapse", over)
    keys = ("runout", "runout_main_body", "final_height", "at_rest", "n_particles")
    keys += ("stress_roughness_max", "volume_change", "wall_s", "inserted")
    return {"resolution": n, "refine": refine, **{k: m[k] for k in keys}}


def added(n_final: int, inserted: int) -> str:
    """A particle count at the end, with the particles added during the run."""
    return f"{n_final} ({inserted} added)" if inserted else str(n_final)


def collapse_table(cases: list[dict]) -> str:
    """The collapse part's table, each run-out against the uniform L0/44 run."""
    ref = {c["resolution"]: c for c in cases if c["refine"] == "none"}
    fine = ref.get(max(COLLAPSE_RESOLUTIONS), {}).get("runout")
    rows = []
    for c in cases:
        err = "" if fine is None else f" ({100 * (c['runout'] / fine - 1):+.2f} %)"
        rows.append(
            [
                f"L0/{c['resolution']}",
                c["refine"],
                added(c["n_particles"], c.get("inserted") or 0),
                f"{c['runout']:.4f}{err}",
                f"{c['runout_main_body']:.4f}",
                f"{c['final_height']:.3f}",
                f"{c['stress_roughness_max']:.3f}",
                f"{100 * c['volume_change']:+.2f} %",
                f"{c['wall_s']:.0f} s",
            ]
        )
    head = ["spacing", "refine", "particles", "run-out, m (vs uniform L0/44)"]
    head += ["main body, m", "H/L0", "R max", "volume", "wall"]
    return markdown_table(head, rows)


#: The slope part's dry sand cut (the slope study's run-out case), H = 2 m.
SAND_CUT = {k: v for k, v in RUNOUT.items() if k != "spacing"}
#: The slope part's lattices: H / spacing.
SLOPE_RESOLUTIONS = (5, 10, 20, 40)


def slope_case(n: int, refine: str) -> dict:
    """The dry sand cut at H/n with ``refine`` (none or surface), to rest."""
    m = run("slope", {**SAND_CUT, "spacing": 2.0 / n, "refine": refine})
    keys = ("runout", "moved_volume", "crest_settlement", "at_rest", "n_particles")
    keys += ("inserted", "mass_change", "volume_change", "wall_s")
    return {"resolution": n, "refine": refine, **{k: m[k] for k in keys}}


def slope_table(cases: list[dict]) -> str:
    """The slope part's table, each run-out against the finest uniform run."""
    fine = max(
        (c for c in cases if c["refine"] == "none"), key=lambda c: c["resolution"]
    )
    rows = []
    for c in cases:
        err = 100 * (c["runout"] / fine["runout"] - 1)
        rows.append(
            [
                f"H/{c['resolution']}",
                c["refine"],
                f"{c['n_particles']} + {c['inserted']}",
                f"{c['runout']:.3f} ({err:+.1f} %)",
                f"{c['moved_volume']:.3f}",
                f"{c['crest_settlement']:.3f}",
                f"{100 * c['volume_change']:+.1f} %",
                f"{c['wall_s']:.0f} s",
            ]
        )
    head = ["spacing", "refine", "particles (+ added)"]
    head += [f"run-out, m (vs uniform H/{fine['resolution']})", "moved, m^2"]
    head += ["crest settlement, m", "volume", "wall"]
    return markdown_table(head, rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=VALIDATION)
    ap.add_argument("--spacing", type=float, default=0.05)
    ap.add_argument("--parts", default="footing,cone,collapse,slope")
    for part, default in (
        ("cone", "none,bodies,strain"),
        ("footing", "none,bodies,strain"),
        ("collapse", "none,surface,strain"),
    ):
        ap.add_argument(
            f"--{part}-refine",
            default=default,
            help=f"the {part}'s refine settings to run (the others kept from the JSON)",
        )
    ap.add_argument(
        "--footing-holes",
        default="sealed",
        help="the footing's seal_cavities settings to run: sealed (true, the "
        "default) and/or open (false); the others kept from the JSON",
    )
    args = ap.parse_args()
    parts = args.parts.split(",")
    path = args.out / "particle_insertion.json"
    old = json.loads(path.read_text()) if path.exists() else {}
    cone = {c["refine"]: c for c in old.get("cone", [])}
    for refine in args.cone_refine.split(",") if "cone" in parts else ():
        cone[refine] = cone_case(refine)
        print(cone[refine], flush=True)
        if path.exists():  # another process may have run the other case
            cone = {
                c["refine"]: c for c in json.loads(path.read_text()).get("cone", [])
            } | {refine: cone[refine]}
    cone = [cone[r] for r in REFINES if r in cone]
    collapse = {(c["resolution"], c["refine"]): c for c in old.get("collapse", [])}
    for refine in args.collapse_refine.split(",") if "collapse" in parts else ():
        # strain at L0/22 only: the flowing deposit is nearly all marked, and
        # at L0/22 it ends with about four times the particles (L0/44 would
        # run for hours).
        for n in (
            COLLAPSE_RESOLUTIONS[:1] if "strain" in refine else COLLAPSE_RESOLUTIONS
        ):
            collapse[n, refine] = collapse_case(n, refine)
            print(collapse[n, refine], flush=True)
    collapse = [
        collapse[n, r]
        for n in COLLAPSE_RESOLUTIONS
        for r in COLLAPSE_REFINES
        if (n, r) in collapse
    ]
    slope = old.get("slope", [])
    if "slope" in parts:
        slope = []
        for refine in ("none", "surface"):
            for n in SLOPE_RESOLUTIONS:
                slope.append(slope_case(n, refine))
                print(slope[-1], flush=True)
    cases = {(c["interface"], c["refine"], c["holes"]): c for c in old.get("cases", [])}
    # Each setting sealed and open one after the other: their wall times compare.
    for interface, refine in (
        (i, r)
        for i in (INTERFACES if "footing" in parts else ())
        for r in args.footing_refine.split(",")
    ):
        for holes in args.footing_holes.split(","):
            over = {"spacing": args.spacing, "interface": interface, "refine": refine}
            seal = {"seal_cavities": holes == "sealed"}
            m = run("footing-penetration", {**over, **seal})
            case = {
                **over,
                "holes": holes,
                "bearing_factor": m["bearing_factor"],
                "final_bearing_factor": m["final_bearing_factor"],
                "load_drops": m["load_drops"],
                "largest_fall": largest_fall(m["curve"]),
                "inserted": m["inserted"],
                "n_particles": m["n_particles"],
                "stress_roughness_max": m["stress_roughness_max"],
                "wall_s": m["wall_s"],
            }
            cases[interface, refine, holes] = case
            print(case, flush=True)
    cases = [
        cases[i, r, h]
        for h in HOLES
        for i in INTERFACES
        for r in REFINES
        if (i, r, h) in cases
    ]
    rows = []
    for case in cases:
        rows.append(
            [
                case["holes"],
                case["interface"],
                case["refine"],
                f"{case['bearing_factor']:.3f}",
                f"{case['final_bearing_factor']:.3f}",
                case["load_drops"],
                f"{100 * case['largest_fall']:.1f} %",
                f"{case['n_particles']} + {case['inserted']}",
                f"{case['stress_roughness_max']:.3f}",
                f"{case['wall_s']:.0f} s",
            ]
        )
    table = markdown_table(
        [
            "holes inside the soil",
            "interface",
            "refine",
            "q/s_u at w = 0.1 B",
            "q/s_u at w = B",
            "load drops",
            "largest fall (w > B/2)",
            "particles (+ added)",
            "R max",
            "wall",
        ],
        rows,
    )
    result = {"spacing": args.spacing, "cases": cases, "cone": cone}
    text = json.dumps({**result, "collapse": collapse, "slope": slope}, indent=1)
    page = table + "\n"
    if cone:
        page += (
            "\n**The cone** (defaults: D/12, pushed 6 D)\n\n" + cone_table(cone) + "\n"
        )
    if collapse:
        page += (
            "\n**The column** (plane strain, a = 2, to rest)\n\n"
            + collapse_table(collapse)
            + "\n"
        )
    if slope:
        page += (
            "\n**The sand cut's run-out** (H = 2 m, 60 deg, phi = 30 deg, to rest)\n\n"
            + slope_table(slope)
            + "\n"
        )
    write_results(path, text, page)


if __name__ == "__main__":
    main()
