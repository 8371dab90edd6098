#!/usr/bin/env python
"""Verification tables: the elastic column and the Prandtl footing, measured.

Runs the verification cases of docs/verification.md through the scenes (the
same cases the tests assert, plus the refinements they do not all run) and
writes their measured errors to ``docs/validation/verification.json``; the
documentation builds the tables of docs/verification.md from that file.

* **Elastic column** (scene ``elastic-column``, oedometric, H = 4 m, W = 1 m,
  rho = 2000 kg/m^3, nu = 0.3, static): relative L2 errors of the vertical and
  horizontal stress against sigma_v = -rho g (H - z), sigma_h = nu/(1-nu)
  sigma_v, and of the top settlement against rho g H^2 / (2M), in 2D at
  spacings 0.25, 0.125, 0.0625 m and in 3D at 0.25, 0.125 m.
* **Sudden gravity** (the same column, dynamic, E = 100 MPa, theta1 = theta2 =
  1/2, dt = T/40, 100 steps): the top's period against the first oedometric
  period T = 4H/c_p.
* **Prandtl footing** (scene ``strip-footing``, weightless Tresca soil, run to
  the load plateau): q/c against 2 + pi for 8, 16 and 32 elements across the
  half-footing (smooth), Drucker-Prager with the plane-strain match at phi = 0,
  and the rough footing at 8 and 16.

About two minutes on one core.  Usage (from the repository root)::

    python demos/studies/verification_tables.py [--out docs/validation]
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import platform
import time
from pathlib import Path

from _common import ROOT, benchmark

import skfem_npfem as npfem

COLUMNS = [
    {"dim": 2, "spacing": 0.25},
    {"dim": 2, "spacing": 0.125},
    {"dim": 2, "spacing": 0.0625},
    {"dim": 3, "spacing": 0.25},
    {"dim": 3, "spacing": 0.125},
]
FOOTINGS = [
    {"spacing": 0.125},
    {"spacing": 0.0625},
    {"spacing": 0.03125},
    {"spacing": 0.125, "material": "drucker-prager"},
    {"spacing": 0.125, "interface": "rough"},
    {"spacing": 0.0625, "interface": "rough"},
]


def column_case(overrides: dict) -> dict:
    """One static elastic column: stress errors and settlement error."""
    t0 = time.perf_counter()
    s = npfem.run_scene("elastic-column", overrides)
    m = s["metrics"]
    return {
        "overrides": overrides,
        "n_particles": m["n_particles"],
        "sigma_v_rel_l2": m["sigma_v_rel_l2"],
        "sigma_h_rel_l2": m["sigma_h_rel_l2"],
        "settlement": m["settlement"],
        "settlement_exact": m["settlement_exact"],
        "settlement_error": m["settlement"] / m["settlement_exact"] - 1,
        "ipm_iterations_max": s["solver"]["ipm_iterations_max"],
        "wall_time": time.perf_counter() - t0,
    }


def period_case() -> dict:
    """Sudden gravity on the column: the top's period against 4H/c_p."""
    E, nu, rho, H = 1.0e8, 0.3, 2000.0, 4.0
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    T = 4 * H / math.sqrt(M / rho)
    overrides = {
        "E": E,
        "mode": "dynamic",
        "theta1": 0.5,
        "theta2": 0.5,
        "dt": T / 40,
        "steps": 100,
    }
    t0 = time.perf_counter()
    m = npfem.run_scene("elastic-column", overrides)["metrics"]
    h = 2 * math.pi / 40  # the trapezoidal rule's own elongation, h / (2 atan(h/2))
    return {
        "overrides": overrides,
        "period": m["period"],
        "period_exact": m["period_exact"],
        "period_error": m["period"] / m["period_exact"] - 1,
        "trapezoidal_elongation": h / (2 * math.atan(h / 2)) - 1,
        "wall_time": time.perf_counter() - t0,
    }


def footing_case(overrides: dict) -> dict:
    """One footing to its plateau: q/c against 2 + pi."""
    t0 = time.perf_counter()
    s = npfem.run_scene("strip-footing", overrides)
    m = s["metrics"]
    return {
        "overrides": overrides,
        "elements_across": round(1.0 / overrides["spacing"]),
        "n_particles": m["n_particles"],
        "bearing_factor": m["bearing_factor"],
        "reference": 2 + math.pi,
        "relative_error": m["bearing_factor"] / (2 + math.pi) - 1,
        "plateau_reached": m["plateau_reached"],
        "steps": s["solver"]["steps"],
        "wall_time": time.perf_counter() - t0,
    }


# ---------------------------------------------------------------------------
# The tables of the docs pages, rendered from the committed JSON (--tables).

docs_tables = benchmark("_tables")
TABLES: docs_tables.Tables = {}
docs_table = docs_tables.registry(TABLES)


VERIFICATION = "docs/validation/verification.json"


@docs_table(VERIFICATION)
def elastic_column() -> str:
    """Static elastic column: stress and settlement errors (verification_tables.py)."""
    out = []
    for c in docs_tables.load(VERIFICATION)["columns"]:
        o = c["overrides"]
        out.append(
            [
                f"{o['dim']}D, spacing {o['spacing']:g} "
                f"({docs_tables.count(c['n_particles'])})",
                docs_tables.pct(c["sigma_v_rel_l2"], 2, sign=False),
                docs_tables.pct(c["sigma_h_rel_l2"], 2, sign=False),
                docs_tables.sci(abs(c["settlement_error"]), 1),
            ]
        )
    return docs_tables.md(
        ["case", "σ_v rel. L2", "σ_h rel. L2", "settlement error"], out
    )


@docs_table(VERIFICATION)
def column_period() -> str:
    """Sudden gravity: the top's period against 4H/c_p (verification_tables.py)."""
    p = docs_tables.load(VERIFICATION)["period"]
    row = [
        f"{p['period']:.5f}",
        f"{p['period_exact']:.5f}",
        docs_tables.pct(p["period_error"], 2),
        docs_tables.pct(p["trapezoidal_elongation"], 2),
    ]
    return docs_tables.md(
        ["period (s)", "4H/c_p (s)", "error", "trapezoidal rule's own elongation"],
        [row],
    )


def _interface(overrides: dict) -> str:
    """A footing run's interface (records measured before the parameter was
    named ``interface`` hold it as ``footing``)."""
    return overrides.get("interface", overrides.get("footing", "smooth"))


@docs_table(VERIFICATION)
def prandtl() -> str:
    """The Prandtl footing against 2 + pi (verification_tables.py)."""
    out = []
    for f in docs_tables.load(VERIFICATION)["footings"]:
        o = f["overrides"]
        names = {"tresca": "Tresca", "drucker-prager": "Drucker–Prager (φ = 0)"}
        kind = [names.get(o.get("material", "tresca")), _interface(o)]
        out.append(
            [
                f"{f['elements_across']} ({docs_tables.count(f['n_particles'])})",
                ", ".join(kind),
                f"{f['bearing_factor']:.4f}",
                docs_tables.pct(f["relative_error"], 3),
                "yes" if f["plateau_reached"] else "no",
                f["steps"],
            ]
        )
    return docs_tables.md(
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
        docs_tables.sig(ref_value, digits),
        docs_tables.sig(value, digits),
        docs_tables.pct(err, 2).replace(" ", docs_tables.NNBSP),
        "—" if tol is None else f"±{100 * tol:g}{docs_tables.NNBSP}%",
        verdict,
        shows,
        measured,
    ]


@docs_table(*VV_SOURCES.values())
def vv_summary() -> str:
    """Every check of the library against an independent reference, one row each."""
    rows: list[list[str]] = []
    ver = docs_tables.load(VV_SOURCES["verification"])
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
        rough = _interface(o) == "rough"
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
    plateau = docs_tables.load(VV_SOURCES["footing_plateau"])
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
    lock = docs_tables.load(VV_SOURCES["locking"])
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
    col = docs_tables.load(VV_SOURCES["collapse"])
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
    rows[-1][5] = f"{docs_tables.sig(lo, 3)}–{docs_tables.sig(hi, 3)}"
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
    rows[-1][5] = f"{docs_tables.sig(lo, 3)}–{docs_tables.sig(hi, 3)}"
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
    seed = docs_tables.load(VV_SOURCES["seed_column"])["cases"]
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
    return docs_tables.md(
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


def main(argv: list[str] | None = None) -> int:
    """Run every case and write the JSON."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "validation")
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    args = ap.parse_args(argv)
    if args.tables:
        return docs_tables.write(TABLES)
    t0 = time.perf_counter()
    report = {
        "meta": {
            "date": datetime.date.today().isoformat(),
            "skfem_npfem": npfem.__version__,
            "python": platform.python_version(),
        },
        "columns": [column_case(o) for o in COLUMNS],
        "period": period_case(),
        "footings": [footing_case(o) for o in FOOTINGS],
    }
    report["meta"]["wall_time"] = time.perf_counter() - t0
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "verification.json"
    path.write_text(json.dumps(report, indent=1) + "\n")
    print(f"wrote {path} ({report['meta']['wall_time']:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
