"""Run the extreme-parameter matrix and write docs/extremes.json and docs/extremes.md.

The cases (parameters, expected physical answer or documented error, the check)
live in tests/cases/extremes.py, the single source of truth that
tests/scenes/test_extremes.py asserts; this script runs all of them, default and slow
(about a minute), and tabulates the outcome.  The coupled (consolidation) cases
live in tests/water/test_coupled_extremes.py, which asserts them; ``--coupled``
runs only those (a few seconds) and rewrites their block, keeping the other rows.

Usage::

    python demos/studies/extremes_matrix.py [--only-default] [--coupled] [--out docs]
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from pathlib import Path

import clarabel
from _common import ROOT

import skfem_npfem

sys.path.insert(0, str(ROOT / "tests"))  # the cases are test data: tests/cases/
sys.path.insert(0, str(ROOT / "tests" / "water"))
import test_coupled_extremes as tc
from cases import extremes as tx


def fmt_params(params: dict) -> str:
    return ", ".join(
        f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in params.items()
    )


def fmt_error(x: float) -> str:
    if x is None or not math.isfinite(x):
        return "-"
    return f"{x:+.2e}" if x < 0 else f"{x:.2e}"


def fmt_iters(its: list[int]) -> str:
    if not its:
        return "-"
    lo, hi = min(its), max(its)
    return f"{lo}" if lo == hi else f"{lo}-{hi}"


def case_row(c) -> dict:
    """Run one case of ``cases.extremes``; its row of extremes.json."""
    t0 = time.perf_counter()
    try:
        o = tx.result(c.name)
        passed, outcome, error, its, plastic = (
            o.passed,
            o.outcome,
            o.error,
            o.iterations,
            o.plastic,
        )
        yielding, energy = o.yielding, o.energy
    except Exception as err:  # a crash is a finding, not a demo failure
        passed, outcome, error, its, plastic = (
            False,
            f"{type(err).__name__}: {err}",
            float("nan"),
            [],
            False,
        )
        yielding, energy = False, float("nan")
    return {
        "case": c.name,
        "group": c.group,
        "scene": c.scene,
        "parameters": c.params,
        "expected": c.expected,
        "outcome": outcome,
        "passed": bool(passed),
        "error": error if error is None or math.isfinite(error) else None,
        "iterations": list(its),
        "plastic": plastic,
        "yielding": yielding,
        "energy": energy if math.isfinite(energy) else None,
        "slow": c.slow,
        "seconds": round(time.perf_counter() - t0, 3),
    }


def summarise(rows: list[dict], wall: float) -> dict:
    """Counts, IPM iteration ranges and versions of the rows (``summary``)."""
    peaks = [max(r["iterations"]) for r in rows if r["plastic"] and r["iterations"]]
    ypeaks = [max(r["iterations"]) for r in rows if r["yielding"] and r["iterations"]]
    summary = {
        "cases": len(rows),
        "passed": sum(r["passed"] for r in rows),
        "plastic_cases": len(peaks),
        "ipm_iterations_peak_min": min(peaks) if peaks else None,
        "ipm_iterations_peak_max": max(peaks) if peaks else None,
        "yielding_cases": len(ypeaks),
        "yielding_iterations_peak_min": min(ypeaks) if ypeaks else None,
        "yielding_iterations_peak_max": max(ypeaks) if ypeaks else None,
        "elastic_iterations": sorted(
            {i for r in rows if not r["plastic"] for i in r["iterations"]}
        ),
        "wall_time": round(wall, 1),
        "versions": {
            "skfem_npfem": skfem_npfem.__version__,
            "clarabel": getattr(clarabel, "__version__", "?"),
            "python": platform.python_version(),
        },
    }
    return summary


def coupled_row(c) -> dict:
    """Run one case of ``test_coupled_extremes``; its row of extremes.json."""
    t0 = time.perf_counter()
    try:
        o = tc.result(c)
        passed, outcome, error, its = o.passed, o.outcome, o.error, o.iterations
    except Exception as err:  # a crash is a finding, not a demo failure
        passed, outcome, error, its = False, f"{type(err).__name__}: {err}", None, []
    return {
        "case": c.name,
        "parameters": c.params,
        "expected": c.expected,
        "outcome": outcome,
        "passed": bool(passed),
        "error": error,
        "iterations": [int(i) for i in its],
        "seconds": round(time.perf_counter() - t0, 3),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only-default", action="store_true", help="skip slow cases")
    ap.add_argument(
        "--coupled",
        action="store_true",
        help="run only the coupled cases; keep the other rows of extremes.json",
    )
    ap.add_argument("--out", default=str(ROOT / "docs"), help="output folder")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    start = time.perf_counter()
    if args.coupled:
        kept = json.loads((out / "extremes.json").read_text())
        rows, summary = kept["cases"], kept["summary"]
    else:
        rows = []
        for c in tx.CASES:
            if c.slow and args.only_default:
                continue
            rows.append(case_row(c))
            flag = "ok  " if rows[-1]["passed"] else "FAIL"
            print(f"{flag} {c.name:<40} {rows[-1]['outcome']}", flush=True)
        summary = summarise(rows, time.perf_counter() - start)
    coupled = [coupled_row(c) for c in tc.CASES]
    for r in coupled:
        flag = "ok  " if r["passed"] else "FAIL"
        print(f"{flag} {r['case']:<40} {r['outcome']}", flush=True)
    report = {"summary": summary, "cases": rows, "coupled": coupled}
    (out / "extremes.json").write_text(json.dumps(report, indent=1) + "\n")
    (out / "extremes.md").write_text(
        markdown(rows, summary) + coupled_markdown(coupled)
    )
    print(
        f"{summary['passed']}/{summary['cases']} passed; plastic IPM iterations "
        f"(per-case peak) {summary['ipm_iterations_peak_min']}-"
        f"{summary['ipm_iterations_peak_max']}; {summary['wall_time']} s; coupled "
        f"{sum(r['passed'] for r in coupled)}/{len(coupled)} passed"
    )
    ok = summary["passed"] == summary["cases"] and all(r["passed"] for r in coupled)
    return 0 if ok else 1


def coupled_markdown(rows: list[dict]) -> str:
    """The block of the coupled (consolidation) cases."""
    lines = [
        "",
        "## Coupled consolidation",
        "",
        "Cases of `tests/water/test_coupled_extremes.py` (all run in the test "
        'suite, in a few seconds): coupled steps (`Water("coupled", '
        "permeability=k, storage=S)`, tau = 1) at k from 1e-12 to 1e-2 m/s, dt "
        "from 1e-6 to 1e3 s and fluid storage S = n/K_w from 1e-15 (nearly "
        "incompressible water) to 1e-3 1/Pa (M S = 1.3e4), on Terzaghi's column "
        "(weightless, H = 1 m, 2 x 10 lattice, E = 10 MPa, nu = 0.3, q0 = 10 "
        "kPa, gamma_w = 1e4 N/m^3; T = c_v dt / H^2 with c_v = k / (gamma_w "
        "(1/M + S))) and on a Mohr-Coulomb footing loaded near collapse "
        "(weightless block 2 m x 1 m, 17 x 9 nodes, c = 10 kPa, phi = 20 deg, "
        "psi = 0, smooth rigid footing of half-width 0.5 m, 4 settlements of "
        "5 mm). Every step solves (Clarabel's status Solved): none of "
        "these extremes ends in a solver error. *error* is the case's main "
        "error measure (see *outcome*).",
        "",
        "| case | parameters | expected | outcome | error | iterations | |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        mark = "pass" if r["passed"] else "**FAIL**"
        error = fmt_error(r["error"]) if r["error"] is not None else "-"
        lines.append(
            f"| `{r['case']}` | {fmt_params(r['parameters'])} | {r['expected']} | "
            f"{r['outcome']} | {error} | {fmt_iters(r['iterations'])} | {mark} |"
        )
    return "\n".join(lines) + "\n"


def markdown(rows: list[dict], summary: dict) -> str:
    lines = [
        "# Extreme parameters and bad input",
        "",
        "Generated by `python demos/studies/extremes_matrix.py` from the cases of "
        "`tests/cases/extremes.py` (asserted by `tests/scenes/test_extremes.py`: the "
        "default cases run in the test suite, the ones marked *slow* with "
        "`pytest -m slow`). Each case asserts the "
        "physical answer in *expected* or a specific documented error. "
        "*error* is the case's main error measure (relative; see *outcome*). "
        "*iterations* are Clarabel's interior-point iterations per step "
        "(elastic programs are a single KKT solve: 0). *energy* is the energy "
        "the run created, relative to the energy it turned over (largest over "
        "its steps of K + (P - P_0) + (Psi - Psi_0) - W, with K the kinetic "
        "energy, 0 in quasi-static steps, P the potential energy of gravity, "
        "Psi the elastic energy of the stresses and W the work of the "
        "prescribed motions; `tests/cases/framework.py` `EnergyBudget`): "
        "backward Euler with a dissipative material cannot create energy, and "
        "every case asserts it is at most "
        f"{tx.ENERGY_TOLERANCE:g} beside its physical answer (negative: "
        "energy dissipated or stored; '-': a documented error before the "
        "first step).",
        "",
        f"Result: {summary['passed']} of {summary['cases']} cases pass. "
        "Per-case peak IPM iterations: "
        f"{summary['yielding_iterations_peak_min']}-"
        f"{summary['yielding_iterations_peak_max']} over the "
        f"{summary['yielding_cases']} cases that reach a collapse load (the test "
        "allows a factor 2), "
        f"{summary['ipm_iterations_peak_min']}-"
        f"{summary['ipm_iterations_peak_max']} over all {summary['plastic_cases']} "
        "programs with yield cones, active or not (factor 5 allowed); elastic "
        "cases: "
        f"{', '.join(map(str, summary['elastic_iterations'])) or '-'} iterations. "
        f"Versions: skfem-npfem {summary['versions']['skfem_npfem']}, clarabel "
        f"{summary['versions']['clarabel']}, Python "
        f"{summary['versions']['python']}; wall time {summary['wall_time']} s.",
        "",
        "Defaults: `elastic-column` W = 1 m, H = 4 m, spacing 0.125 m (297 "
        "particles), E = 10 MPa, nu = 0.3, rho = 2000 kg/m^3, static; "
        "`strip-footing` half model, b = 1 m, block 5 b, spacing 0.125 m "
        "(576 particles), Tresca c = 10 kPa, E = 100 MPa, smooth, weightless.",
        "",
        "| case | parameters | expected | outcome | error | iterations | energy | |",
        "|---|---|---|---|---|---|---|---|",
    ]

    def cell(text: str) -> str:  # a "|" inside a cell would split the row
        return str(text).replace("|", "\\|")

    for r in rows:
        name = f"`{r['case']}`" + (" *(slow)*" if r["slow"] else "")
        mark = "pass" if r["passed"] else "**FAIL**"
        lines.append(
            f"| {name} | {cell(fmt_params(r['parameters']))} | "
            f"{cell(r['expected'])} | {cell(r['outcome'])} | "
            f"{fmt_error(r['error'])} | {fmt_iters(r['iterations'])} | "
            f"{fmt_error(r.get('energy'))} | {mark} |"
        )
    lines += [
        "",
        "## What broke on the way, and the fixes",
        "",
        "* **Small time steps lost the displacement increment (conic.py).** The "
        "program was scaled with the static displacement scale U* = s* h / E. "
        "With inertia the increment is F* dt^2/m, (c dt/h)^2 times smaller, so "
        "the scaled duals (du = -U* z) were tiny and du, hence the velocity, "
        "carried round-off and solver noise. Columns at rest in equilibrium "
        "(the `*-at-rest` cases) moved at |v| = 3e-4 g t (elastic, dt = 1e-9 s; "
        "now 7e-16) and, with Mohr-Coulomb cones, at up to 2.5e4 g t (E = 1 kPa) "
        "and 2.5 g t (E = 10 MPa) at dt = 1e-9 s, 2.5e-2 g t at dt = 1e-6 s "
        "(now <= 1.5e-7 everywhere). U* is now F*/(k_el + k_in) with "
        "k_el = E h^(d-2) and k_in = m~/dt^2: the old scale when c dt/h >> 1 "
        "(half of it at c dt/h = 1).",
        "* **Tolerance applied to the total stress (conic.py).** The cone "
        "program's unknowns were the end-of-step stresses, so Clarabel's "
        "relative tolerance 1e-8 bounded the error of the increment only "
        "relative to the whole stress (and to the whole elastic energy in the "
        "objective). The unknowns are now the increments ds = s - s_n: the "
        "right-hand side of the equilibrium rows is the out-of-balance force "
        "and the cone rows are shifted by s_n (same feasible set, same "
        "optimum). At rest the stress change fell from up to 1.2e-6 rho g H to "
        "<= 7e-8, and the footing q/c became E/c- and length-scale-invariant "
        "to <= 4e-12 instead of up to 5e-10. Iterations: 14-24 (before 12-22) "
        "on the "
        "collapse cases; 2169 vs 2160 for the 164-step coarse column collapse.",
        "* **Zero-area elements (conic.py).** A node on the opposite edge of a "
        "triangle gave infinite P1 gradients, NaN operators and a Clarabel "
        "NumericalError whose hint said 'reduce dt'. The step now refuses it "
        "with `ParameterError: invalid mesh=...degenerate element...`. "
        "Near-degenerate elements are fine (the sliver cases).",
        "* **nu = 0 metric (scenes/elastic/column.py).** `sigma_h_rel_l2` was NaN "
        "(the exact s_h is 0); it is now normalised by |s_v| in that case.",
        "* **Energy from nowhere at E = 1 kPa (step/stabilisation.py).** The "
        "soft column collapse of `tests/scenes/test_extremes_collapse.py` "
        "(E = 1 kPa, 91 particles, dt = 5 ms) solved every step and blew up: "
        "kinetic energy 0.6 J at step 1, 289 J at step 21 (the potential "
        "energy had not fallen at all), 1.5e11 J from step 30 on, particles at "
        "665 km/s. Logging K + P + Psi per step (Psi: the elastic energy of the "
        "stresses, 451 J at the start, more than the 283 J of potential "
        "energy: the geostatic stress of so soft a column stores a lot, so K "
        "above the potential energy released, from step 1 on, was not yet "
        "wrong) showed it growing from step 2 on (+1.2, +7, +16, +20 J per "
        "step, +350 J by "
        "step 21, Psi 1954 J), with no inverted element before step 23 and "
        "the fastest particles in the mesh (a grain in free flight kept "
        "2.9 m/s); the 665 km/s step then started on a sliver of 1e-14 m^2. "
        "Switched off one at a time over the first 12 steps: the "
        "stabilisation off, the run lost energy every step (largest single "
        "gain +0.4 J, -22 J in all); the volume correction off, the same "
        "numbers to the last digit (it is not active in this run); particle "
        "masses instead of mesh masses, still +5 to +146 J per step; "
        "associated flow (psi = phi), faster growth. The cause was the "
        "stabilisation. Its residual takes the acceleration of the start of "
        "the step and its weight was beta h^2 / G: the lagged inertia was fed "
        "back with a gain beta rho h^2 / (G dt^2), 0.7 at E = 10 MPa but about "
        "7e3 at E = 1 kPa, where the shear wave (0.44 m/s) takes 8 steps to "
        "cross an element. The weight is now beta min(h^2/G, dt^2/rho) |e| "
        "(the time-step term of GLS parameters of transient problems): "
        "unchanged where the wave crosses an element within a step (every "
        "ordinary run; the benchmark digest is bit-identical), the inertial "
        "scale where it does not. The same run now loses energy (K + P + Psi "
        "733 J -> 631 J after 40 steps, K = 145 J, Psi 451 J -> 213 J, "
        "fastest particle 4.4 m/s, no inverted element). Every case now checks "
        "its energy balance (the *energy* column), and so does every run of "
        "the column-collapse part of the matrix "
        "(`tests/scenes/test_extremes_collapse.py`): +8.8e-4 at E = 1 kPa "
        "(before: 1.0, all of the energy turned over was created), -4.7e-4 to "
        "-4e-5 for nu, E = 10 GPa, phi and length scale, -0.13 for the "
        "cohesive column, -0.96 for the one step of dt = 1 s.",
        "",
        "## Observations",
        "",
        "* Frictional footings approach N_c(phi) from *below* on these meshes "
        "and the gap grows with phi (-0.2 % at 10 deg, -3.4 % at 30 deg, "
        "-8.7 % at 50 deg); it shrinks under refinement (-1.5 % at 30 deg with "
        "spacing 0.0625). At 50 deg the Prandtl mechanism reaches about 36 b "
        "from the footing edge, so that case needs a 45 b block.",
        "* Heavy cohesionless soil (N_gamma, 30 deg) lands above the exact "
        "values: +6.4 % smooth, +0.8 % rough (N_gamma footing gates 7 % and 5 %).",
        "* A single static step of a very soft column (E = 1 kPa, settlement "
        "29 H) is still the small-strain answer, but the objective stress "
        "rotation by the spin of that increment adds some shear (2.3 % of the "
        "stress in L2; s_v itself stays within 0.5 %).",
        "* Positions are stored as x + du in double precision, so increments "
        "below 1e-16 |x| are lost from `x` and from the accumulated "
        "displacement `u` (free fall at dt = 1e-9 s showed u = 0 on a 4 m "
        "column); velocities are unaffected.",
        "",
        "## Bad input",
        "",
        "`tests/test_bad_input.py` checks with hypothesis that the public API "
        "and the CLI refuse wrong shapes and NaN/inf in `Particles.create`, "
        "zero or negative masses, nu outside (-1, 0.5), E <= 0, negative "
        "density or cohesion, phi >= 90 deg, psi > phi, dt <= 0 (advance, "
        "Simulation, scene `dt`), unknown or out-of-range scene parameters, "
        "malformed `--set`, material ids outside the model, zero-area "
        "elements and corrupted checkpoints, each with a `ParameterError` (a "
        "`ValueError`) or `CheckpointError` naming the parameter, the value "
        "and what is allowed; the CLI prints it as one `error:` line and exits "
        "with 2. No known gaps: the former ones (`--out`/`--summary` below a "
        "regular file, a checkpoint whose zip header flags are corrupted, "
        "particles of the wrong dimension, `FixedMesh` indices out of range) "
        "now give the same one-line errors. `tests/run/test_reliability.py` "
        "adds: tiny or huge values outside the magnitudes the scenes run "
        "at (`scenes/limits.py`, listed in docs/scenes.md), runs estimated to "
        "need more than this machine's memory or more than 1e6 steps "
        "(refused before anything is built; `size_check=false` overrides), "
        "numpy scalars (accepted), a repeated `--set`, an empty `--out`, "
        "non-Material materials, a zero-area element shared by others and a "
        "tangled fixed mesh (refused at the source).",
        "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
