"""Tables built at docs-build time from the JSON the demos and benchmarks commit.

A page asks for a table by name::

    ```{results-table} collapse-refinement
    ```

and the builder of that name reads its JSON (``docs/validation/...`` or
``benchmarks/results/...``) and returns Markdown, which the directive parses
in place.  Rerunning a demo therefore updates the tables of the pages; the
prose around them stays hand-written.  ``{json-markdown}`` inserts a Markdown
table that a demo stored in its JSON (``:key: table``).
"""

from __future__ import annotations

import functools
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import ClassVar

from docutils import nodes
from sphinx.util.docutils import SphinxDirective

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
NNBSP = "\u202f"  # thousands separator, as in 1 035
MINUS = "\u2212"

#: name -> (builder, JSON files it reads, relative to the repository root)
BUILDERS: dict[str, tuple[Callable[[], str], tuple[str, ...]]] = {}


def table(*sources: str):
    """Register a builder under its function name (underscores become dashes)."""

    def register(fn: Callable[[], str]) -> Callable[[], str]:
        BUILDERS[fn.__name__.replace("_", "-")] = (fn, sources)
        return fn

    return register


def load(rel: str):
    """A committed JSON file, by its path from the repository root."""
    return json.loads((ROOT / rel).read_text(encoding="utf-8"))


# ---------------------------------------------------------------------------
# Number formats (the conventions of the hand-written pages).


def num(x, digits: int = 3) -> str:
    """Fixed decimals, a real minus sign, "—" for a missing value."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    return f"{x:.{digits}f}".replace("-", MINUS)


def sig(x, digits: int = 3) -> str:
    """Significant digits (``%g``)."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    return f"{x:.{digits}g}".replace("-", MINUS)


def pct(x, digits: int = 1, sign: bool = True) -> str:
    """A fraction as a signed percentage: ``-0.035`` -> ``−3.5 %``."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    s = f"{100 * x:+.{digits}f} %" if sign else f"{100 * x:.{digits}f} %"
    return s.replace("-", MINUS)


def count(n) -> str:
    """An integer with a narrow space every three digits."""
    return f"{int(n):,}".replace(",", NNBSP)


def sci(x, digits: int = 2) -> str:
    """Scientific notation, ``3.26e-02``."""
    return "—" if x is None else f"{x:.{digits}e}"


def md(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table."""
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def statuses(counts: dict) -> str:
    """``{"Solved": 171, "AlmostSolved": 1}`` -> ``171 Solved, 1 AlmostSolved``."""
    order = sorted(counts.items(), key=lambda kv: (kv[0] != "Solved", kv[0]))
    return ", ".join(f"{n} {s}" for s, n in order)


# ---------------------------------------------------------------------------
# Verification: the footing plateau (demos/studies/footing_plateau.py).


@table("docs/validation/footing_plateau.json")
def footing_plateau() -> str:
    """Bearing factors at the detected plateau, phi = 0..45 deg, block 5 b and 15 b."""
    rows = load("docs/validation/footing_plateau.json")["rows"]
    wide = {(r["phi"], r["footing"]): r for r in rows if r["domain"] != 5}
    out = []
    for r in rows:
        if r["domain"] != 5:
            continue
        w = wide.get((r["phi"], r["footing"]))
        old = r["bearing_factor_at_0.01m"] / r["reference"] - 1
        out.append(
            [
                f"{r['phi']:g}°",
                r["footing"],
                num(r["bearing_factor"]),
                num(r["reference"]),
                pct(r["relative_error"], 2).replace(" ", ""),
                pct(old, 1).replace(" ", ""),
                pct(r["vs_rigid_plastic"], 2).replace(" ", ""),
                r["steps"],
                num(r["final_settlement"]),
                num(r["wall_time"], 1),
                pct(w["relative_error"], 2).replace(" ", "") if w else "—",
            ]
        )
    return md(
        [
            "φ",
            "footing",
            "N = q/c (block 5 b, default)",
            "N_c exact",
            "error",
            "at 0.01 m",
            "N/N_rp − 1",
            "steps",
            "settlement (m)",
            "wall (s)",
            "error, block 15 b",
        ],
        out,
    )


VERIFICATION = "docs/validation/verification.json"


@table(VERIFICATION)
def elastic_column() -> str:
    """Static elastic column: stress and settlement errors (verification_tables.py)."""
    out = []
    for c in load(VERIFICATION)["columns"]:
        o = c["overrides"]
        out.append(
            [
                f"{o['dim']}D, spacing {o['spacing']:g} ({count(c['n_particles'])})",
                pct(c["sigma_v_rel_l2"], 2, sign=False),
                pct(c["sigma_h_rel_l2"], 2, sign=False),
                sci(abs(c["settlement_error"]), 1),
            ]
        )
    return md(["case", "σ_v rel. L2", "σ_h rel. L2", "settlement error"], out)


@table(VERIFICATION)
def column_period() -> str:
    """Sudden gravity: the top's period against 4H/c_p (verification_tables.py)."""
    p = load(VERIFICATION)["period"]
    row = [
        f"{p['period']:.5f}",
        f"{p['period_exact']:.5f}",
        pct(p["period_error"], 2),
        pct(p["trapezoidal_elongation"], 2),
    ]
    return md(
        ["period (s)", "4H/c_p (s)", "error", "trapezoidal rule's own elongation"],
        [row],
    )


@table(VERIFICATION)
def prandtl() -> str:
    """The Prandtl footing against 2 + pi (verification_tables.py)."""
    out = []
    for f in load(VERIFICATION)["footings"]:
        o = f["overrides"]
        names = {"tresca": "Tresca", "drucker-prager": "Drucker–Prager (φ = 0)"}
        kind = [names.get(o.get("material", "tresca")), o.get("footing", "smooth")]
        out.append(
            [
                f"{f['elements_across']} ({count(f['n_particles'])})",
                ", ".join(kind),
                f"{f['bearing_factor']:.4f}",
                pct(f["relative_error"], 3),
                "yes" if f["plateau_reached"] else "no",
                f["steps"],
            ]
        )
    return md(
        [
            "elements across the half-footing (particles)",
            "soil, footing",
            "q/c",
            "error vs 2 + π",
            "plateau",
            "steps",
        ],
        out,
    )


# ---------------------------------------------------------------------------
# Validation: the column collapse (demos/studies/collapse_validation.py).

#: The record before the stabilisation (particle masses, beta = 0), compact:
#: the summary rows of the study, without its per-case records.
COLLAPSE = "docs/validation/collapse_validation_before.json"
#: The study with today's defaults (stabilisation beta = 30, volume
#: correction kappa = 0.05), as the study writes it.
COLLAPSE_NOW = "docs/validation/collapse_validation.json"


def _measures(path: str) -> tuple[str, str, str]:
    """Labels of the primary and the second run-out measure, and the second's key.

    The scene's run-out was the main body's front when COLLAPSE was measured
    and is the 99 % mass front since; the other one is the second measure.
    """
    if path == COLLAPSE:
        return "main body", "99 % mass front", "front_q99_normalised"
    return "99 % mass front (scene)", "main body", "runout_main_body_normalised"


def _lube(r: dict) -> tuple[str, str]:
    lube = r["lube"]
    if lube.get("low") is not None and lube.get("high") is not None:
        law = f"{lube['low']:.2f}–{lube['high']:.2f}"
        lo, hi = r["ratio_lube_range"]
        return law, f"{lo:.2f}–{hi:.2f}"
    return f"{lube['value']:.2f}", f"{r['ratio_lube']:.2f}"


@table(COLLAPSE)
def collapse_sweep(path: str = COLLAPSE) -> str:
    """The primary aspect-ratio sweep against the experimental laws."""
    first, second, key = _measures(path)

    def rough(r: dict) -> list[str]:  # measured since the stabilisation
        if path == COLLAPSE:
            return []
        return [num(r.get("stress_roughness_max")), num(r.get("stress_roughness"))]

    out = []
    for r in load(path)["sweep"]:
        law, ratio = _lube(r)
        out.append(
            [
                f"{r['aspect']:g}",
                r["N"],
                count(r["particles"]),
                r["steps"],
                f"**{num(r['normalised_runout'])}**",
                num(r.get(key)),
                num(r["normalised_runout_tip"]),
                law,
                num(r["lajeunesse"]["value"], 2),
                ratio,
                num(r["ratio_lajeunesse"], 2),
                num(r["final_height_L0"]),
                num(r["final_height_H0"]),
                num(r["collapse_time"]),
                num(r["collapse_time_normalised"], 2),
                pct(r["volume_change"]),
                f"{r['wall_time']:.0f}",
                num(r["step_time_median"], 2),
                *rough(r),
            ]
        )
    return md(
        [
            "a",
            "N",
            "particles",
            "steps",
            f"(L∞−L0)/L0 {first}",
            second,
            "farthest particle",
            "Lube law",
            "Lajeunesse law",
            "ratio to Lube",
            "ratio to Lajeunesse",
            "H∞/L0",
            "H∞/H0",
            "t_c (s)",
            "t_c/√(H0/g)",
            "mesh-area change",
            "wall (s)",
            "median s/step",
            *([] if path == COLLAPSE else ["R max", "R at rest"]),
        ],
        out,
    )


@table(COLLAPSE)
def collapse_other_resolutions(path: str = COLLAPSE) -> str:
    """The sweeps at the other resolutions (a = 2 is the refinement table)."""
    first, second, key = _measures(path)
    data = load(path)
    rows = [r for s in data["other_sweeps"].values() for r in s["sweep"]]
    rows.sort(key=lambda r: (r["aspect"], r["N"]))
    out, done2 = [], False
    for r in rows:
        if r["aspect"] == 2:
            if not done2:
                ns = sorted(int(k) for k in data["other_sweeps"])
                ns = " / ".join(str(n) for n in ns)
                out.append(["2", ns, "see refinement", "", "", "", "", ""])
                done2 = True
            continue
        out.append(
            [
                f"{r['aspect']:g}",
                r["N"],
                count(r["particles"]),
                num(r["normalised_runout"]),
                num(r.get(key)),
                num(r["normalised_runout_tip"]),
                num(r["final_height_L0"]),
                pct(r["volume_change"]),
            ]
        )
    return md(
        [
            "a",
            "N",
            "particles",
            first,
            second,
            "farthest particle",
            "H∞/L0",
            "mesh-area change",
        ],
        out,
    )


@table(COLLAPSE)
def collapse_refinement(path: str = COLLAPSE) -> str:
    """The refinement series at a = 2."""
    first = _measures(path)[0]
    out = []
    for r in load(path)["refinement"]:
        lo, hi = r["runout_late_range_normalised"]
        out.append(
            [
                r["N"],
                num(1e3 * r["spacing"], 2),
                count(r["particles"]),
                r["steps"],
                num(r["normalised_runout"]),
                f"{lo:.2f}–{hi:.2f}",
                num(r["front_q99_normalised"]),
                num(r["front_q95_normalised"]),
                num(r["normalised_runout_tip"]),
                num(r["final_height_L0"]),
                num(r["collapse_time_normalised"], 2),
                pct(r["volume_change"]),
                f"{r['wall_time']:.0f}",
                num(r["step_time_median"], 2),
            ]
        )
    return md(
        [
            "N",
            "spacing (mm)",
            "particles",
            "steps",
            first,
            f"{first} over the last 10 % of the run",
            "99 % mass front",
            "95 % mass front",
            "farthest particle",
            "H∞/L0",
            "t_c/√(H0/g)",
            "mesh-area change",
            "wall (s)",
            "median s/step",
        ],
        out,
    )


def _variant(label: str) -> str:
    key, _, value = label.partition("=")
    v = float(value)
    names = {
        "dt": f"Δt = {1e3 * v:g} ms",
        "alpha": f"α = {v:g}",
        "E": f"E = {v / 1e6:g} MPa",
        "floor_friction": f"floor friction {v:g}°",
        "rest_fraction": f"rest fraction {v:g} (run longer)",
    }
    return names.get(key, label)


@table(COLLAPSE)
def collapse_sensitivity(path: str = COLLAPSE) -> str:
    """The N = 12, a = 2 case against its variants."""
    first, second, key = _measures(path)
    data = load(path)
    base = next(r for r in data["sweep"] if r["aspect"] == 2)
    s = data["setup"]
    label = (
        f"baseline (Δt = {1e3 * s['dt']:g} ms, α = {s['alpha']:g}, "
        f"E = {s['E'] / 1e6:g} MPa, floor {s['floor_friction_deg']:g}°)"
    )
    out = []
    variants = [(_variant(v["variant"]), v) for v in data["variants"]]
    for name, r in [(label, base), *variants]:
        out.append(
            [
                name,
                r["steps"],
                num(r["normalised_runout"]),
                num(r.get(key)),
                num(r["normalised_runout_tip"]),
                num(r["final_height_L0"]),
                pct(r["volume_change"]),
                statuses(r["status_counts"]),
            ]
        )
    return md(
        [
            "variant",
            "steps",
            first,
            second,
            "farthest particle",
            "H∞/L0",
            "mesh-area change",
            "statuses",
        ],
        out,
    )


def _fit_row(label: str, measure: str, fit: dict | None, primary: bool) -> list[str]:
    def gate(ok: bool) -> str:
        return "pass" if ok else "**fail**"

    small, large = (fit or {}).get("small_a"), (fit or {}).get("large_a")
    cells = [label, measure]
    if small:
        cells += [
            f"{small['slope_through_origin']:.2f} ({gate(small['pass'])})",
            " / ".join(f"{x:.2f}" for x in small["pointwise_slopes"]),
        ]
    else:
        cells += ["—", "—"]
    if large and len(large["aspects"]) >= 3:
        loc = large.get("local_exponents")
        cells += [
            f"{large['exponent']:.3f} ({gate(large['pass'])})",
            " / ".join(f"{x:.2f}" for x in loc) if loc else "—",
            f"{large['prefactor']:.2f}",
        ]
    elif large:
        only = ", ".join(f"{a:g}" for a in large["aspects"])
        cells += [
            f"{large['exponent']:.2f} from a = {only} only ({gate(large['pass'])})",
            "—",
            f"{large['prefactor']:.2f}",
        ]
    else:
        cells += ["— (too few aspect ratios)", "—", "—"]
    if primary:
        cells = [f"**{c}**" if i < 2 or "pass" in c else c for i, c in enumerate(cells)]
    return cells


@table(COLLAPSE)
def collapse_fits(path: str = COLLAPSE) -> str:
    """Small-a slope and large-a exponent per resolution and run-out measure."""
    data = load(path)
    n0 = data["setup"]["particles_across_sweep"]
    sweeps = [(n0, data["fits"], data["fits_alternative_measures"])]
    for n, s in sorted(data["other_sweeps"].items(), key=lambda kv: int(kv[0])):
        sweeps.append((int(n), s["fits"], s.get("fits_alternative", {})))
    out = []
    for n, fits, alt in sweeps:
        out.append(_fit_row(f"N = {n}", _measures(path)[0], fits, n == n0))
        for key, measure in (
            ("front_q99_normalised", "99 % mass front"),
            ("normalised_runout_tip", "farthest particle"),
        ):
            if key in alt:
                out.append(_fit_row(f"N = {n}", measure, alt[key], False))
    return md(
        [
            "sweep",
            "measure",
            "small-a slope (gate 0.90–2.25)",
            "point slopes a = 0.5 / 1",
            "large-a exponent, a = 2–8 (gate 0.55–0.85)",
            "local exponent 2→4 / 4→8",
            "prefactor",
        ],
        out,
    )


# The rerun with today's defaults: the same tables from COLLAPSE_NOW (named
# collapse-now-sweep, ...), and what changed against COLLAPSE.
for _builder in (
    collapse_sweep,
    collapse_other_resolutions,
    collapse_refinement,
    collapse_sensitivity,
    collapse_fits,
):
    _name = _builder.__name__.replace("collapse_", "collapse-now-").replace("_", "-")
    BUILDERS[_name] = (functools.partial(_builder, COLLAPSE_NOW), (COLLAPSE_NOW,))


def _all_rows(data: dict) -> dict[tuple[float, int, str | None], dict]:
    """Every case of a collapse study by (aspect, N, variant)."""
    rows = list(data["sweep"]) + list(data["refinement"]) + list(data["variants"])
    rows += [r for s in data["other_sweeps"].values() for r in s["sweep"]]
    return {(r["aspect"], r["N"], r.get("variant")): r for r in rows}


@table(COLLAPSE, COLLAPSE_NOW)
def collapse_before_after() -> str:
    """Each case of the primary sweep and the refinement, before -> now."""
    before, now = _all_rows(load(COLLAPSE)), _all_rows(load(COLLAPSE_NOW))
    keys = sorted(k for k in now if k in before and k[2] is None)

    def pair(a, b, f) -> str:
        return f"{f(a)} → {f(b)}"

    out = []
    for key in keys:
        b, n = before[key], now[key]
        lube = b["lube"]["value"]  # Lube's value at this aspect (1.2a to a = 2.3)
        out.append(
            [
                f"{key[0]:g}",
                key[1],
                count(n["particles"]),
                pair(b["normalised_runout"], n.get("runout_main_body_normalised"), num),
                pair(b["front_q99_normalised"], n["front_q99_normalised"], num),
                pair(
                    b["front_q99_normalised"] / lube,
                    n["front_q99_normalised"] / lube,
                    lambda x: num(x, 2),
                ),
                pair(b["final_height_L0"], n["final_height_L0"], num),
                pair(b["volume_change"], n["volume_change"], pct),
                num(n.get("stress_roughness_max")),
                num(n.get("stress_roughness")),
                pair(b["step_time_median"], n["step_time_median"], lambda x: num(x, 3)),
                pair(
                    b["ipm_iterations_mean"],
                    n["ipm_iterations_mean"],
                    lambda x: num(x, 1),
                ),
            ]
        )
    return md(
        [
            "a",
            "N",
            "particles",
            "main body",
            "99 % mass front",
            "99 % front / Lube",
            "H∞/L0",
            "mesh-area change",
            "R max (now)",
            "R at rest (now)",
            "median s/step",
            "IPM it. (mean)",
        ],
        out,
    )


@table("docs/validation/area_budget.json")
def area_budget() -> str:
    """Where the collapse's mesh area goes (demos/studies/area_budget.py)."""
    out = []
    for r in load("docs/validation/area_budget.json")["runs"]:
        dt = r["overrides"].get("dt")
        label = f"{1e3 * dt:g} ms" if dt else "default"
        out.append(
            [
                label,
                r["steps"],
                pct(r["area_change"]),
                pct(r["linear"]),
                pct(r["linear_apex"]),
                pct(r["expanding"], 0),
                pct(r["quadratic"]),
                pct(r["remesh"]),
            ]
        )
    return md(
        [
            "Δt",
            "steps",
            "area change (final positions)",
            "linear (dilatation)",
            "of which at p < 0.01 ρgH0",
            "expanding elements only",
            "quadratic",
            "remesh",
        ],
        out,
    )


# ---------------------------------------------------------------------------
# Baselines (demos/studies/compare_*.py).


@table("docs/validation/comparison/locking.json")
def locking() -> str:
    """Cook's membrane: u_y(C) over the reference, per nu, method and mesh."""
    data = load("docs/validation/comparison/locking.json")
    out = []
    for case in data["cases"]:
        for method, res in case["methods"].items():
            out.append(
                [f"{case['nu']:g}", f"{case['reference']['value']:.4f}", method]
                + [f"{x:.4f}" for x in res["ratio"]]
            )
    return md(
        ["ν", "reference u_y(C)", "method"] + [f"n = {n}" for n in data["meshes"]], out
    )


MAPPING_NAMES = {
    "npfem": "N-PFEM",
    "fem-p1-nearest": "FEM-remap P1 nearest",
    "fem-p1-recovery": "FEM-remap P1 recovery",
    "fem-p2-nearest": "FEM-remap P2 nearest",
    "fem-p2-recovery": "FEM-remap P2 recovery",
}


@table("docs/validation/comparison/mapping.json")
def mapping() -> str:
    """Stress drift from remeshing: at rest and under rigid motion."""
    data = load("docs/validation/comparison/mapping.json")
    rest, rigid = data["at_rest"], data["rigid_motion"]
    n = rest["n_remesh"]
    out = []
    for key, name in MAPPING_NAMES.items():
        a, b = rest.get(key, {}), rigid.get(key, {})
        per = a.get("drift_per_transfer", a.get("drift", math.nan) / n)
        out.append(
            [
                name,
                sci(a.get("drift")),
                sci(per),
                sci(b.get("p_drift")),
                sci(b.get("q_drift")),
                sci(b.get("max_drift")),
            ]
        )
    return md(
        [
            "method",
            f"at rest: drift after {n} remeshes",
            "per remesh",
            "rigid motion: p drift",
            "q drift",
            "max",
        ],
        out,
    )


# ---------------------------------------------------------------------------
# Performance (benchmarks/results/*.json, written by benchmarks/*.py).

RESULTS = "benchmarks/results"


@table(f"{RESULTS}/dt_sweep.json")
def dt_sweep() -> str:
    """The default collapse to rest against the time step (benchmarks/dt_sweep.py)."""
    out = []
    for r in load(f"{RESULTS}/dt_sweep.json")["runs"]:
        key, _, value = r["config"].partition("=")
        if key == "dt":
            label = f"Δt = {1e3 * float(value):g} ms"
        else:
            label = f"adaptive, `max_displacement={value}`"
        out.append(
            [
                label,
                num(r["normalised_runout"]),
                num(r["final_height"]),
                num(r["collapse_time"]),
                num(r["sigma_yy_base"]),
                pct(r["volume_change"]),
                r["steps"],
                f"{r['wall_s']:.0f}",
            ]
        )
    return md(
        [
            "time step",
            "(L∞−L0)/L0",
            "H∞/L0",
            "collapse time (s)",
            "σ_yy at the base",
            "volume change",
            "steps",
            "wall (s)",
        ],
        out,
    )


def _suite_summaries(name: str) -> dict:
    """Per (case, backend, preset) statistics of a suite report (suite.py's own)."""
    bench = str(ROOT / "benchmarks")
    if bench not in sys.path:
        sys.path.insert(0, bench)
    import suite  # benchmarks/suite.py: the report's own statistics

    return suite.summaries(load(f"{RESULTS}/{name}.json"))


def _s(summary: dict | None) -> str:
    return sig(summary["median_s"]) if summary else "—"


#: The suite-format reports pooled by the time-per-step table.
SUITE_REPORTS = (
    "suite",
    "suite_16k_default",
    "suite_refinement",
    "suite_16k",
    "threads",
    "cnr",
    "crossover_2d",
    "cylinder3d",
)


#: Case names of benchmarks/suite.py as the performance page says them.
CASE_LABELS = {
    "collapse-1k": "2D collapse 1k",
    "collapse-2k": "2D collapse 2k",
    "collapse-4k": "2D collapse 4k",
    "collapse-16k": "2D collapse 16k",
    "block3d-3k": "3D DP block 3k",
    "block3d-10k": "3D DP block 10k",
    "block3d-11k": "3D DP block 11k",
    "cylinder3d-4k": "3D quarter-cylinder collapse 4k",
    "cylinder3d-10k": "3D quarter-cylinder collapse 10k",
    "footing-1.6k": "footing 1.6k",
    "footing-4.8k": "footing 4.8k",
}


def _pooled() -> dict[tuple[str, str, str], dict]:
    """Newest clean measurement per (case, backend, preset) over the reports.

    A measurement is clean when its statistics use only steps during which no
    other process held a core (``only_clean``, at least two such steps); a
    clean one wins over any other, and among equals the newest report wins
    (the library got faster over the reports, and its defaults changed).
    """
    best: dict[tuple[str, str, str], tuple[tuple, dict]] = {}
    for name in SUITE_REPORTS:
        report = load(f"{RESULTS}/{name}.json")
        date = report["machine"]["date"]
        for key, sm in _suite_summaries(name).items():
            if not sm:
                continue
            clean = bool(sm["only_clean"] and sm["steps_clean"] >= 2)
            rank = (clean, date)
            if key not in best or rank > best[key][0]:
                best[key] = (rank, {**sm, "report": name})
    return {k: v for k, (_, v) in best.items()}


@table(*(f"{RESULTS}/{n}.json" for n in SUITE_REPORTS))
def time_per_step() -> str:
    """Seconds per step per case and backend, pooled over the suite reports."""
    bench = str(ROOT / "benchmarks")
    if bench not in sys.path:
        sys.path.insert(0, bench)
    import suite

    pool = _pooled()
    cases = [c for c in suite.CASES if any(k[0] == c for k in pool)]
    out = []
    for case in cases:

        def get(backend: str, preset: str, case: str = case) -> dict | None:
            return pool.get((case, backend, preset))

        faer = [s for s in (get("faer", "high"), get("faer (1 thr.)", "high")) if s]
        high = {
            "qdldl": get("qdldl", "high"),
            "faer": min(faer, key=lambda s: s["median_s"]) if faer else None,
            "mkl": get("mkl", "high"),
        }
        fast = [s for b in ("qdldl", "faer", "mkl") if (s := get(b, "fast"))]
        fastest = min(fast, key=lambda s: s["median_s"]) if fast else None
        any_s = next(s for s in (*high.values(), fastest) if s)
        winner = min((s["median_s"], b) for b, s in high.items() if s)[1]
        cells = [f"**{_s(s)}**" if b == winner else _s(s) for b, s in high.items()]
        ref = suite.REFERENCE.get(case, {})
        target = suite.TARGET.get(case)
        best_s = high[winner]["median_s"]
        out.append(
            [
                CASE_LABELS.get(case, case),
                count(any_s["particles"]),
                f"{any_s['variables'] / 1e3:.1f}k",
                *cells,
                _s(fastest) + (f" ({fastest['linear_solvers'][0]})" if fastest else ""),
                _s(get("mkl", "high-nocnr")),
                " / ".join(f"{v:g} ({b})" for b, v in ref.items()) or "—",
                f"≤ {target:g}" if target else "—",
                ("yes" if best_s <= target else "no") if target else "—",
            ]
        )
    return md(
        [
            "case",
            "particles",
            "variables",
            "qdldl",
            "faer",
            "MKL Pardiso",
            "fast preset (best backend)",
            "MKL, `reproducible=False`",
            "reference (straightforward implementation)",
            "target",
            "met",
        ],
        out,
    )


@table(f"{RESULTS}/presets_step.json")
def presets_step() -> str:
    """One step with the high and fast presets against a tight (1e-10) solve."""
    out = []
    for c in load(f"{RESULTS}/presets_step.json")["cases"]:
        backend = c["reference"]["backend"]
        rows = {r["preset"]: r for r in c["rows"] if r["backend"] == backend}
        hi, fa = rows.get("high"), rows.get("fast")
        if not (hi and fa):
            continue

        def err(r: dict) -> str:
            if "du_rel" not in r:  # the solve failed; the report says why
                return f"failed ({r['status']})"
            return f"{sci(r['du_rel'], 1)} / {sci(r['sigma_rel'], 1)}"

        out.append(
            [
                CASE_LABELS.get(c["case"], c["case"]),
                backend,
                err(hi),
                err(fa),
                f"{hi['iterations']} → {fa['iterations']}",
                f"{sig(hi.get('solve_s'))} → {sig(fa.get('solve_s'))}",
            ]
        )
    return md(
        [
            "one step of",
            "backend",
            "high: Δu / σ error (rel. L2)",
            "fast: Δu / σ error",
            "IPM iterations high → fast",
            "solve (s) high → fast",
        ],
        out,
    )


@table(f"{RESULTS}/threads.json")
def threads() -> str:
    """Seconds per step against the solver's thread count (threads.json)."""
    sm = _suite_summaries("threads")
    cases = list(dict.fromkeys(k[0] for k in sm))
    cols = [
        ("faer (1 thr.)", "faer 1 thread"),
        ("faer (2 thr.)", "faer 2 threads"),
        ("faer", "faer automatic"),
        ("mkl (1 thr.)", "MKL 1 thread"),
        ("mkl (2 thr.)", "MKL 2 threads"),
        ("mkl", "MKL automatic"),
    ]
    out = [[c] + [_s(sm.get((c, b, "high"))) for b, _ in cols] for c in cases]
    return md(["case"] + [label for _, label in cols], out)


@table(f"{RESULTS}/cnr.json")
def cnr() -> str:
    """MKL Pardiso with and without conditional numerical reproducibility."""
    sm = _suite_summaries("cnr")
    out = []
    for case in dict.fromkeys(k[0] for k in sm):
        hi, nohi = sm.get((case, "mkl", "high")), sm.get((case, "mkl", "high-nocnr"))
        fa, nofa = sm.get((case, "mkl", "fast")), sm.get((case, "mkl", "fast-nocnr"))
        ratio = f"{nohi['median_s'] / hi['median_s']:.2f}" if hi and nohi else "—"
        out.append([case, _s(hi), _s(nohi), ratio, _s(fa), _s(nofa)])
    return md(
        [
            "case",
            "MKL, reproducible (default)",
            "`reproducible=False`",
            "ratio",
            "fast preset",
            "fast, `reproducible=False`",
        ],
        out,
    )


@table(f"{RESULTS}/full_2k_cnr.json")
def full_runs() -> str:
    """Whole 2k collapse runs to rest with the MKL settings (presets.py)."""
    names = {
        "default": "MKL, defaults",
        "nocnr": "`reproducible=False`",
        "fast": "`accuracy=fast`",
        "fast-nocnr": "both",
    }
    out = []
    for r in load(f"{RESULTS}/full_2k_cnr.json")["runs"]:
        m = r["metrics"]
        out.append(
            [
                names.get(r["variant"], r["variant"]),
                "/".join(r["linear_solvers"]),
                count(r["n_particles"]),
                r["steps"],
                f"{r['wall_s']:.1f}",
                num(r.get("step_time_median", r["wall_s"] / r["steps"])),
                num(m.get("normalised_runout")),
                num(m.get("final_height")),
            ]
        )
    return md(
        [
            "run",
            "backend",
            "particles",
            "steps",
            "wall (s)",
            "s/step",
            "(L∞−L0)/L0",
            "H∞/L0",
        ],
        out,
    )


#: Rows of the reference implementation's times per step (suite.json's
#: ``reference_s_per_step`` and ``targets_s_per_step``), as the page names them.
REFERENCE_ROWS = {
    "collapse-1k": "collapse 1k",
    "collapse-4k": "collapse 4k",
    "collapse-16k": "collapse 16k",
    "block3d-3k": "3D, 3.4k particles (block3d-3k, cylinder3d-4k)",
    "block3d-11k": "3D, 10.7k particles (block3d-11k, cylinder3d-10k)",
}


def _seconds(x) -> str:
    """A time per step as the reference quotes it: 0.2, 9.0, 17, 75."""
    return "—" if x is None else (f"{x:.1f}" if x < 10 else f"{x:.0f}")


@table(f"{RESULTS}/suite.json")
def reference_timings() -> str:
    """The reference implementation's s/step per backend, and the suite's targets."""
    data = load(f"{RESULTS}/suite.json")
    refs, targets = data["reference_s_per_step"], data["targets_s_per_step"]
    out = []
    for case, label in REFERENCE_ROWS.items():
        ref = refs.get(case, {})
        cells = [_seconds(ref.get(b)) for b in ("qdldl", "faer", "mkl")]
        out.append([label, *cells, _seconds(targets.get(case))])
    return md(["case", "qdldl", "faer", "MKL Pardiso", "target (best backend)"], out)


AXI_VS_3D = tuple(f"{RESULTS}/cylinder_axi_vs_3d_{n}.json" for n in (6, 8))


@table(*AXI_VS_3D)
def cylinder_axi_vs_3d() -> str:
    """The seed column to rest, 3D quarter against axisymmetric section (reduced)."""

    def wall(x: float) -> str:
        return f"{x:.0f}" if x >= 100 else f"{x:.1f}"

    out = []
    for rel in AXI_VS_3D:
        d = load(rel)
        for key, model in (("quarter_cylinder", "3D quarter"), ("axisymmetric", "axi")):
            r = d[key]
            axi = key == "axisymmetric"
            step = r["step_time_median_s"]
            out.append(
                [
                    f"r0/{d['divisions']}",
                    model,
                    count(r["n_particles"]),
                    r["steps"],
                    wall(r["wall_time_t3_s"]),
                    wall(r["wall_time_s"]),
                    sig(step, 3 if step >= 1 else 2),
                    num(r["ipm_iterations_mean"], 1),
                    f"{r['peak_memory_mb']:.0f}",
                    num(r["normalised_runout_t3"]),
                    num(r["normalised_runout"]),
                    num(r["final_height"]),
                    f"{d['speedup_to_t3']:.0f}×" if axi else "",
                    pct(d["runout_t3_relative_difference"]) if axi else "",
                ]
            )
    return md(
        [
            "spacing",
            "model",
            "particles",
            "steps",
            "wall to t̄ = 3 (s)",
            "whole run (s)",
            "s/step (median)",
            "IPM it. (mean)",
            "peak MB",
            "(r − r0)/r0 at t̄ = 3",
            "at rest",
            "h∞/r0",
            "speed-up to t̄ = 3",
            "run-out difference at t̄ = 3 (axi vs 3D)",
        ],
        out,
    )


# ---------------------------------------------------------------------------
# Verification and validation summary: every check against an independent
# reference, in one table (docs/verification.md opens with it).

#: The committed result files the summary reads, by role (paths from the
#: repository root).  When results are moved or consolidated, adjust them here.
VV_SOURCES: dict[str, str] = {
    "verification": "docs/validation/verification.json",
    "footing_plateau": "docs/validation/footing_plateau.json",
    "collapse": "docs/validation/collapse_validation.json",
    "seed_column": "docs/seed_column/seed_column.json",
    "locking": "docs/validation/comparison/locking.json",
}


def _measured_on(data: dict) -> str:
    """The date (and machine, if recorded) of a result file, for the table."""
    meta = data.get("meta") or data.get("machine") or {}
    date = str(meta.get("date", ""))[:10]
    return date or "—"


def _vv_row(
    check: str,
    reference: str,
    ref_value: float,
    value: float,
    tol: float | None,
    shows: str,
    measured: str,
    digits: int = 4,
    error: float | None = None,
) -> list[str]:
    """One row: reference value, library value, relative error, tolerance, verdict."""
    err = value / ref_value - 1 if error is None else error
    if tol is None:
        verdict = "reported"
    else:
        verdict = "pass" if abs(err) <= tol else "**fails**"
    return [
        check,
        reference,
        sig(ref_value, digits),
        sig(value, digits),
        pct(err, 2).replace(" ", NNBSP),
        "—" if tol is None else f"±{100 * tol:g}{NNBSP}%",
        verdict,
        shows,
        measured,
    ]


@table(*VV_SOURCES.values())
def vv_summary() -> str:
    """Every check of the library against an independent reference, one row each."""
    rows: list[list[str]] = []
    ver = load(VV_SOURCES["verification"])
    when = _measured_on(ver)
    # Elastic column at the scene's default spacing (0.125 m in 2D and 3D).
    for c in ver["columns"]:
        o = c["overrides"]
        if o["spacing"] != 0.125:
            continue
        tol = 0.005 if o["dim"] == 2 else 0.01
        name = f"elastic column {o['dim']}D, σ_v (rel. L2)"
        row = _vv_row(
            name,
            "σ_v = −ρg(H − z) (analytic)",
            1.0,
            1.0,
            tol,
            "`tests/scenes/test_scenes.py`",
            when,
            error=c["sigma_v_rel_l2"],
        )
        row[2:4] = ["exact", "—"]
        rows.append(row)
        rows.append(
            _vv_row(
                f"elastic column {o['dim']}D, settlement",
                "ρgH²/(2M) (analytic)",
                c["settlement_exact"],
                c["settlement"],
                0.005,
                "`tests/scenes/test_scenes.py`",
                when,
            )
        )
    per = ver["period"]
    rows.append(
        _vv_row(
            "sudden gravity, period of the top",
            "4H/c_p (analytic)",
            per["period_exact"],
            per["period"],
            0.03,
            "`tests/scenes/test_scenes.py`",
            when,
        )
    )
    for f in ver["footings"]:
        o = f["overrides"]
        rough = o.get("footing") == "rough"
        dp = o.get("material") == "drucker-prager"
        mat = "Drucker–Prager φ = 0" if dp else "Tresca"
        name = (
            f"Prandtl footing, {mat}, {'rough' if rough else 'smooth'}, "
            f"{f['elements_across']} el."
        )
        tol = 0.002 if f["elements_across"] == 32 else (None if rough else 0.01)
        rows.append(
            _vv_row(
                name,
                "2 + π (Prandtl)",
                f["reference"],
                f["bearing_factor"],
                tol,
                "`tests/scenes/test_scenes.py`",
                when,
            )
        )
    plateau = load(VV_SOURCES["footing_plateau"])
    when = _measured_on(plateau)
    gates = {
        (0.0, "smooth"): 0.03,
        (20.0, "smooth"): 0.03,
        (30.0, "smooth"): 0.05,
        (30.0, "rough"): 0.05,
    }
    for r in plateau["rows"]:
        if r["domain"] != 5:
            continue
        tol = gates.get((r["phi"], r["footing"]))
        if tol is None and r["phi"] < 40:
            continue  # the full table: docs/validation/footing_plateau.md
        rows.append(
            _vv_row(
                f"footing at its plateau, φ = {r['phi']:g}°, {r['footing']}",
                "N_c (Prandtl–Reissner)",
                r["reference"],
                r["bearing_factor"],
                tol,
                (
                    "`tests/scenes/test_footing.py`"
                    if tol
                    else "`demos/studies/footing_plateau.py`"
                ),
                when,
            )
        )
    lock = load(VV_SOURCES["locking"])
    for case in lock["cases"]:
        ref = case["reference"]["value"]
        npfem = case["methods"]["N-PFEM"]
        n = lock["meshes"][-1]
        rows.append(
            _vv_row(
                f"Cook's membrane, ν = {case['nu']:g}, N-PFEM {n}×{n}",
                "u_C, P2 extrapolated (Richardson)",
                ref,
                npfem["u_C"][-1],
                None,
                "`demos/studies/compare_locking.py`",
                "—",
            )
        )
    col = load(VV_SOURCES["collapse"])
    small, large = col["fits"]["small_a"], col["fits"]["large_a"]
    lo, hi = small["gate"]
    rows.append(
        _vv_row(
            "column collapse, small-a slope k (N = 12)",
            "1.2 (Lube 2005) – 1.8 (Lajeunesse 2005)",
            1.5,
            small["slope_through_origin"],
            None,
            "`demos/studies/collapse_validation.py`",
            "—",
            digits=3,
        )
    )
    rows[-1][5] = f"{sig(lo, 3)}–{sig(hi, 3)}"
    rows[-1][6] = "pass" if small["pass"] else "**fails**"
    rows.append(
        _vv_row(
            "column collapse, large-a exponent (N = 12)",
            "2/3 (Lube 2005)",
            2 / 3,
            large["exponent"],
            None,
            "`demos/studies/collapse_validation.py`",
            "—",
            digits=3,
        )
    )
    lo, hi = large["gate"]
    rows[-1][5] = f"{sig(lo, 3)}–{sig(hi, 3)}"
    rows[-1][6] = "pass" if large["pass"] else "**fails**"
    finest = max(col["refinement"], key=lambda r: r["N"])
    a2 = finest["normalised_runout"]
    rows.append(
        _vv_row(
            f"column collapse a = 2, run-out (N = {finest['N']})",
            "2.4 (Lube) – 3.6 (Lajeunesse)",
            3.0,
            a2,
            None,
            "`demos/studies/collapse_validation.py`",
            "—",
            digits=3,
        )
    )
    rows[-1][5] = "2.4–3.6"
    rows[-1][6] = "pass" if 2.4 <= a2 <= 3.6 else "**fails**"
    seed = load(VV_SOURCES["seed_column"])["cases"]
    for key in ("axi-18", "3d-18"):
        if key not in seed:
            continue
        c = seed[key]
        on = c.get("measured_on", {}).get("date", "—")
        rows.append(
            _vv_row(
                f"seed column, {c['label']}, run-out",
                "Lube et al. (2004) fit",
                c["reference_runout_lube2004"],
                c["normalised_runout"],
                None,
                "`demos/studies/seed_column.py`",
                on,
                digits=4,
            )
        )
    return md(
        [
            "check",
            "reference",
            "reference value",
            "library",
            "error",
            "tolerance",
            "verdict",
            "shown by",
            "measured on",
        ],
        rows,
    )


def _machine(meta: dict) -> str:
    """``Intel(R) Xeon(R) Processor, 2 cores, 23.5 GB, clarabel 0.11.1, MKL ...``."""
    parts = [str(meta.get("cpu") or "unknown CPU")]
    if meta.get("cores"):
        parts.append(f"{meta['cores']} cores")
    if meta.get("memory_gb"):
        parts.append(f"{meta['memory_gb']:g} GB")
    if meta.get("clarabel"):
        parts.append(f"clarabel {meta['clarabel']}")
    if meta.get("mkl"):
        parts.append(f"MKL {meta['mkl']}")
    return ", ".join(parts)


def measured_on(sources: tuple[str, ...]) -> str:
    """`` Measured on DATE (MACHINE).`` from the sources' ``machine`` records.

    Benchmark reports record the date and the machine of their measurement;
    the table's note carries them, so the prose around it does not.  Sources
    without such a record add nothing.
    """
    dates: dict[str, list[str]] = {}
    for src in sources:
        try:
            data = load(src)
        except (OSError, ValueError):
            continue
        meta = data.get("machine") if isinstance(data, dict) else None
        if isinstance(meta, dict) and meta.get("date"):
            dates.setdefault(_machine(meta), []).append(str(meta["date"])[:10])
    out = []
    for machine, when in dates.items():
        lo, hi = min(when), max(when)
        span = lo if lo == hi else f"{lo} to {hi}"
        out.append(f"{span} ({machine})")
    return f" Measured on {'; '.join(out)}." if out else ""


# ---------------------------------------------------------------------------
# Directives.


class ResultsTable(SphinxDirective):
    """``{results-table} NAME``: a table built from committed JSON."""

    required_arguments = 1

    def run(self) -> list[nodes.Node]:
        """Build the table and parse it as Markdown."""
        name = self.arguments[0]
        if name not in BUILDERS:
            known = ", ".join(sorted(BUILDERS))
            raise self.error(f"unknown results table {name!r}; known: {known}")
        builder, sources = BUILDERS[name]
        for src in sources:
            self.env.note_dependency(str(ROOT / src))
        note = ", ".join(f"`{src}`" for src in sources)
        measured = measured_on(sources)
        return self.parse_text_to_nodes(
            f"{builder()}\n\n<small>Table from {note}.{measured}</small>"
        )


class JsonMarkdown(SphinxDirective):
    """``{json-markdown} PATH`` with ``:key:``: Markdown a demo stored in its JSON."""

    required_arguments = 1
    option_spec: ClassVar[dict] = {"key": str}

    def run(self) -> list[nodes.Node]:
        """Parse the stored Markdown."""
        path = ROOT / self.arguments[0]
        self.env.note_dependency(str(path))
        value = json.loads(path.read_text(encoding="utf-8"))
        for key in self.options.get("key", "table").split("."):
            value = value[key]
        note = f"<small>Table from `{self.arguments[0]}`.</small>"
        return self.parse_text_to_nodes(f"{value}\n\n{note}")


def setup(app) -> None:
    """Register the table directives."""
    app.add_directive("results-table", ResultsTable)
    app.add_directive("json-markdown", JsonMarkdown)
