#!/usr/bin/env python
"""Results side by side: footing bearing factors, collapse deposits and costs.

Every method through the same scenes (``--set method=``), each configuration
in its own process (``_study.run_cases`` on Dask), so
that wall time and peak memory are each run's own:

1. **Strip footing** (scene ``strip-footing``: smooth rigid footing, weightless
   soil, small-strain limit analysis, run to the detected load plateau):
   ``q/c`` against Prandtl's ``2 + pi`` (Tresca) and ``N_c(phi)`` of
   Prandtl-Reissner (Mohr-Coulomb, associated, phi = 20 and 30 deg), for
   N-PFEM, FEM-remap P1 and P2.  SPFEM is explicit and dynamic; the footing
   is quasi-static, so it has no SPFEM run.
2. **Column collapse** a = 2 (scene ``column-collapse``), to rest: the
   normalised run-out ``(L_inf - L0)/L0`` against the experimental band
   [1.2 a, 1.8 a] = [2.4, 3.6] (Lube et al. 2005 to Lajeunesse et al. 2005,
   docs/validation.md) and Lube's value at a = 2 (2.47, transition band), the
   final height ``H_inf / L0`` against ``~1.0 a^0.4 = 1.32`` (Lube et al.,
   approximate), for N-PFEM, FEM-remap P1/P2 (recovery) and SPFEM.
3. **Cost** of each run: steps (SPFEM: also its explicit substeps), median
   time per step, total wall time, peak memory of the process.

The committed results ran two configurations at a time (``--workers 2``) on
an otherwise idle 2-core machine (the date is in the record).  Writes
``results.json`` and ``results.png`` under ``--out`` (default
``docs/validation/comparison``); run folders under ``--work`` (default
``out/comparison/results``; a rerun reuses finished runs).

Usage (from the repository root)::

    python demos/studies/compare_results.py                 # full
    python demos/studies/compare_results.py --quick        # reduced (tests), in-process
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from _common import ROOT, benchmark
from _reporting import markdown_table, save_png, write_result
from _study import run_cases, study_arguments, study_folders

from skfem_npfem.laws import prandtl_nc as n_c

OUT = ROOT / "docs" / "validation" / "comparison"
WORK = ROOT / "out" / "comparison" / "results"

IMPLICIT = {
    "N-PFEM": {"method": "npfem"},
    "FEM-remap P1": {"method": "fem-remap", "element": "p1", "transfer": "recovery"},
    "FEM-remap P2": {"method": "fem-remap", "element": "p2", "transfer": "recovery"},
}
METHODS = {**IMPLICIT, "SPFEM": {"method": "spfem"}}
#: Footing materials: label -> parameters (c = 10 kPa, weightless).
SOILS = {
    "Tresca": {"material": "tresca"},
    "MC phi=20": {"material": "mohr-coulomb", "phi": 20.0},
    "MC phi=30": {"material": "mohr-coulomb", "phi": 30.0},
}
ASPECT = 2.0
BAND = (1.2 * ASPECT, 1.8 * ASPECT)  # experimental run-out envelope at a = 2
HEIGHT_LAW = ASPECT**0.4  # Lube et al. 2005, large a, approximate


def key(*labels: str) -> str:
    return "_".join(s.lower().replace(" ", "-").replace("=", "") for s in labels)


def cases(quick: bool, n: int) -> dict:
    out = {}
    soils = {"Tresca": SOILS["Tresca"]} if quick else SOILS
    footing = {"spacing": 0.125, "threads": 1}
    if quick:  # four equal steps to 0.01 b, no plateau search
        footing.update(spacing=0.25, steps=4, plateau_tol=0.0)
    for soil, sp in soils.items():
        for label, method in IMPLICIT.items():
            out[key("footing", soil, label)] = (
                "strip-footing",
                {**footing, **sp, **method},
            )
    collapse = {
        "aspect": ASPECT,
        "spacing": 0.2 / n,
        "output_every": 10**6,
        "threads": 1,
    }
    if quick:
        collapse.update(t_end=0.2, rest_fraction=0.0)
    for label, method in METHODS.items():
        out[key("collapse", label)] = ("column-collapse", {**collapse, **method})
    return out


def cost(s: dict) -> dict:
    """Steps, time per step, total wall time and peak memory of one summary."""
    m, sol = s["metrics"], s["solver"]
    explicit = m.get("explicit_steps")
    return {
        "steps": sol["steps"],
        "explicit_steps": explicit,
        "step_time_median": sol["step_time_median"],
        "wall_time": s["wall_time_total"],
        "peak_memory_mb": sol["peak_memory_mb"],
        "n_particles": sol["n_particles"],
        "stress_roughness": m["stress_roughness"],
    }


def collect(summaries: dict, quick: bool) -> dict:
    soils = ["Tresca"] if quick else list(SOILS)
    result = {"quick": quick, "footing": {}, "collapse": {}}
    for soil in soils:
        phi = SOILS[soil].get("phi", 0.0)
        rows = {}
        for label in IMPLICIT:
            s = summaries.get(key("footing", soil, label))
            if s is None:
                rows[label] = None
                continue
            m = s["metrics"]
            rows[label] = {
                "bearing_factor": m["bearing_factor"],
                "relative_error": m["relative_error"],
                "plateau_reached": m["plateau_reached"],
                **cost(s),
            }
        result["footing"][soil] = {"reference": n_c(phi), "methods": rows}
    for label in METHODS:
        s = summaries.get(key("collapse", label))
        if s is None:
            result["collapse"][label] = None
            continue
        m = s["metrics"]
        result["collapse"][label] = {
            "normalised_runout": m["normalised_runout"],
            "final_height": m["final_height"],
            "at_rest": m["at_rest"],
            "in_band": BAND[0] <= m["normalised_runout"] <= BAND[1],
            "volume_change": m["volume_change"],
            **cost(s),
        }
    result["band"] = list(BAND)
    result["lube_a2"] = 2.4675
    result["height_law"] = HEIGHT_LAW
    return result


def tables(result: dict) -> str:
    rows = []
    for soil, entry in result["footing"].items():
        for label, r in entry["methods"].items():
            if r is None:
                rows.append([soil, label, "failed"] + [None] * 7)
                continue
            rows.append(
                [
                    soil,
                    label,
                    r["bearing_factor"],
                    entry["reference"],
                    f"{100 * r['relative_error']:+.2f} %",
                    {True: "yes", False: "no (capped)", None: "off"}[
                        r["plateau_reached"]
                    ],
                    r["steps"],
                    r["wall_time"],
                    r["peak_memory_mb"],
                ]
            )
    foot = markdown_table(
        [
            "soil",
            "method",
            "q/c",
            "reference",
            "error",
            "plateau",
            "steps",
            "wall (s)",
            "peak memory (MB)",
        ],
        rows,
    )
    rows = []
    for label, r in result["collapse"].items():
        if r is None:
            rows.append([label, "failed"] + [None] * 8)
            continue
        steps = (
            r["steps"]
            if r["explicit_steps"] is None
            else (f"{r['steps']} ({r['explicit_steps']} explicit)")
        )
        rows.append(
            [
                label,
                r["normalised_runout"],
                r["final_height"],
                r["stress_roughness"],
                steps,
                1e3 * r["step_time_median"],
                r["wall_time"],
                r["peak_memory_mb"],
                r["volume_change"],
            ]
        )
    coll = markdown_table(
        [
            "method",
            "(L∞−L0)/L0",
            "H∞/L0",
            "R at rest",
            "steps",
            "ms per step",
            "wall (s)",
            "peak memory (MB)",
            "area change",
        ],
        rows,
    )
    return foot + "\n\n" + coll


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    soils = list(result["footing"])
    width = 0.8 / len(IMPLICIT)
    for k, label in enumerate(IMPLICIT):
        vals = [
            (result["footing"][s]["methods"][label] or {}).get(
                "bearing_factor", math.nan
            )
            / result["footing"][s]["reference"]
            for s in soils
        ]
        axes[0].bar(
            [i + k * width for i in range(len(soils))], vals, width, label=label
        )
    axes[0].axhline(1.0, color="k", lw=1)
    axes[0].set_xticks([i + width for i in range(len(soils))], soils)
    axes[0].set_ylabel("q/c divided by N_c")
    axes[0].set_title("strip footing")
    axes[0].legend(fontsize=8)
    labels = [k for k, v in result["collapse"].items() if v is not None]
    runout = [result["collapse"][k]["normalised_runout"] for k in labels]
    height = [result["collapse"][k]["final_height"] for k in labels]
    axes[1].bar(labels, runout)
    axes[1].axhspan(*result["band"], color="0.85", label="experiments (1.2a..1.8a)")
    axes[1].axhline(result["lube_a2"], color="k", ls="--", label="Lube et al. 2005")
    axes[1].set_title("collapse a = 2: (L∞ - L0)/L0")
    axes[1].legend(fontsize=8)
    axes[1].tick_params(axis="x", labelsize=7)
    axes[2].bar(labels, height)
    axes[2].axhline(result["height_law"], color="k", ls="--", label="~a^0.4 (Lube)")
    axes[2].set_title("collapse a = 2: H∞/L0")
    axes[2].legend(fontsize=8)
    axes[2].tick_params(axis="x", labelsize=7)
    fig.tight_layout()
    save_png(fig, path)


#: The table of the docs page, the one this study stores in its JSON (--tables).
docs_tables = benchmark("_tables")
TABLES = docs_tables.stored(
    "docs/validation/comparison/results.json", "comparison_results"
)


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    study_arguments(ap, OUT, WORK)
    ap.add_argument("--n", type=int, default=16, help="particles across L0")
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    args = ap.parse_args(argv)
    if args.tables:
        docs_tables.write(TABLES)
        return {}
    start = time.perf_counter()
    n = 6 if args.quick else args.n
    work, out, workers = study_folders(args, OUT, "quick" if args.quick else "full")
    summaries = run_cases(
        cases(args.quick, n), work, workers=workers, scheduler=args.scheduler
    )
    result = collect(summaries, args.quick)
    result["particles_across"] = n
    result["wall_time"] = time.perf_counter() - start
    result["table"] = tables(result)
    write_result(out / "results.json", result)
    plot(result, out / "results.png")
    print(result["table"])
    return result


if __name__ == "__main__":
    main()
