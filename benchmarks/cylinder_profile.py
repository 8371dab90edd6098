#!/usr/bin/env python
"""Where the time of one 3D seed-column step goes: phases, and inside Clarabel.

Builds the ``column-collapse`` quarter cylinder (the seed column, spacing
``r0 / divisions``), advances it ``--skip`` steps, then profiles the next step:

* the step's phases (:attr:`StepRecord.timings`: remeshing and smoothing cells,
  assembly, Clarabel's setup and solve, particle update) and its IPM
  iterations;
* inside the solve: the program's scaled matrices are captured and solved again
  in a child process with MKL Pardiso's statistics switched on, which gives
  the KKT size, the non-zeros of the factor, the GFLOP of one factorisation,
  and the time of the ordering (METIS), of the numerical factorisations and of
  the triangular solves (with MKL's own iterative-refinement steps) -- the
  rest of Clarabel's solve is its own work (cone updates, KKT assembly).

Usage::

    python benchmarks/cylinder_profile.py --divisions 12 --skip 5
    python benchmarks/cylinder_profile.py --divisions 18 --skip 1

Writes ``benchmarks/results/cylinder_profile_<divisions>.json`` and ``.md``.
The machine is shared: the child's times carry the load of the moment
(recorded as ``others``, cores used by other processes).
"""

from __future__ import annotations

import argparse
import pickle
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import _harness as harness

import skfem_npfem.conic as conic
from skfem_npfem.scenes import get_scene
from skfem_npfem.scenes.collapse_runs import build_geometry
from skfem_npfem.scenes.cylinder import SEED

CHILD = r"""
import pickle, sys, time
import clarabel
from skfem_npfem.backends import pardiso_threads
from skfem_npfem.solver import SolverOptions
P, q, A, b, cones, opts = pickle.load(open(sys.argv[1], "rb"))
cones = [getattr(clarabel, name)(dim) for name, dim in cones]
with pardiso_threads(opts.max_threads):
    s = opts.clarabel_settings("mkl")
    s.pardiso_verbose = True
    t0 = time.perf_counter()
    solver = clarabel.DefaultSolver(P, q, A, b, cones, s)
    t1 = time.perf_counter()
    sol = solver.solve()
    t2 = time.perf_counter()
print("@@", sol.status, sol.iterations, t1 - t0, t2 - t1, flush=True)
"""


def _floats(pattern: str, text: str) -> list[float]:
    return [float(x) for x in re.findall(pattern, text)]


def pardiso_split(P, q, A, b, cones, options) -> dict:
    """Solve once more with Pardiso's statistics; parse its times and sizes."""
    desc = [(type(c).__name__, c.dim) for c in cones]
    with tempfile.NamedTemporaryFile(suffix=".pkl", delete=False) as f:
        pickle.dump((P, q, A, b, desc, options), f)
        path = f.name
    with harness.Meter() as m:
        proc = subprocess.run(
            [sys.executable, "-c", CHILD, path],
            capture_output=True,
            text=True,
            env=harness.child_env(),
        )
    Path(path).unlink()
    out = proc.stdout + proc.stderr
    line = next(ln for ln in out.splitlines() if ln.startswith("@@"))
    _, status, its, setup, solve = line.split()
    numfct = _floats(r"factorization step[^:]*:\s+([\d.]+)", out)
    solves = _floats(r"at solve step \(solve\)\s+:\s+([\d.]+)", out)
    refine = _floats(r"iterative refinement steps performed\s+(\d+)", out)
    return {
        "status": status,
        "iterations": int(its),
        "setup_s": float(setup),
        "solve_s": float(solve),
        "kkt_equations": int(_floats(r"number of equations:\s+(\d+)", out)[0]),
        "kkt_nnz": int(_floats(r"number of non-zeros in A:\s+(\d+)", out)[0]),
        "factor_nnz": int(_floats(r"number of non-zeros in L:\s+(\d+)", out)[0]),
        "gflop_per_factorisation": _floats(
            r"gflop\s+for the numerical factorization:\s+([\d.]+)", out
        )[0],
        "reorder_s": sum(_floats(r"\(reorder\)\s+:\s+([\d.]+)", out)),
        "factorisations": len(numfct),
        "factorisation_s": sum(numfct),
        "triangular_solves": len(solves),
        "triangular_solve_s": sum(solves),
        "refinement_steps_per_solve": (sum(refine) / len(refine)) if refine else 0,
        "others": m.others,
    }


def run(args) -> dict:
    over = {
        "geometry": "quarter-cylinder",
        "spacing": SEED["radius"] / args.divisions,
        "rest_fraction": 0.0,
        "linear_solver": "mkl",
    }
    values = get_scene("column-collapse").resolve(over)
    sim = build_geometry(values).simulation
    sim.run(steps=args.skip)
    captured = {}
    original = conic.solve_clarabel

    def spy(P, q, A, b, cones, options, dim):
        captured.update(P=P, q=q, A=A, b=b, cones=cones, options=options)
        return original(P, q, A, b, cones, options, dim)

    conic.solve_clarabel = spy
    try:
        with harness.Meter() as m:
            sim.run(steps=1)
    finally:
        conic.solve_clarabel = original
    rec = sim.records[-1]
    split = pardiso_split(**captured)
    return {
        "divisions": args.divisions,
        "n_particles": int(sim.particles.n),
        "step": rec.step,
        "status": rec.status,
        "iterations": rec.iterations,
        "wall_s": m.wall,
        "others": m.others,
        "phases_s": rec.timings,
        "n_contacts": rec.n_contacts,
        "pardiso": split,
        "machine": harness.machine_info(),
    }


def markdown(rep: dict) -> str:
    ph, pa = rep["phases_s"], rep["pardiso"]
    total = sum(ph.values())
    rest = pa["solve_s"] - pa["factorisation_s"] - pa["triangular_solve_s"]
    lines = [
        f"# One 3D seed-column step: spacing r0/{rep['divisions']:g}, "
        f"{rep['n_particles']} particles, step {rep['step']}",
        "",
        harness.code_line(rep["machine"]["code"]),
        "",
        f"Step: {total:.2f} s, {rep['iterations']} IPM iterations ({rep['status']}), "
        f"{rep['n_contacts']} contact candidates; other processes used "
        f"{rep['others']:.2f} cores meanwhile.",
        "",
        "| phase | s | share |",
        "|---|---|---|",
    ]
    for k, v in ph.items():
        lines.append(f"| {k} | {v:.3f} | {100 * v / total:.1f} % |")
    lines += [
        "",
        f"Inside Clarabel (the same program solved again with MKL Pardiso's "
        f"statistics; {pa['iterations']} iterations, {pa['status']}): KKT "
        f"{pa['kkt_equations']} equations, {pa['kkt_nnz']} non-zeros; factor "
        f"{pa['factor_nnz']} non-zeros, {pa['gflop_per_factorisation']:.1f} GFLOP "
        "per factorisation.",
        "",
        "| part | s | share of setup + solve |",
        "|---|---|---|",
    ]
    whole = pa["setup_s"] + pa["solve_s"]
    rows = [
        ("setup (KKT assembly, METIS ordering, symbolic factorisation)", pa["setup_s"]),
        ("  of which the ordering", pa["reorder_s"]),
        (f"{pa['factorisations']} numerical factorisations", pa["factorisation_s"]),
        (
            f"{pa['triangular_solves']} triangular solves "
            f"({pa['refinement_steps_per_solve']:.1f} refinement steps each)",
            pa["triangular_solve_s"],
        ),
        ("Clarabel's own work (cones, KKT updates, line search)", rest),
    ]
    for label, v in rows:
        lines.append(f"| {label} | {v:.2f} | {100 * v / whole:.1f} % |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--divisions", type=float, default=12.0)
    ap.add_argument("--skip", type=int, default=5, help="steps before the profile")
    ap.add_argument("--render", default=None, help="rewrite FILE.md from FILE.json")
    args = ap.parse_args(argv)
    if args.render:
        return harness.render(args.render, markdown)
    rep = run(args)
    path = harness.HERE / "results" / f"cylinder_profile_{args.divisions:g}.json"
    harness.write_report(path, rep, markdown(rep))
    print(markdown(rep))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
