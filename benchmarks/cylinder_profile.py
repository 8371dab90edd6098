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
  rest of Clarabel's solve is its own work (cone updates, KKT assembly);
* ``--variants``: the same program solved again with MKL Pardiso options the
  library does not use (:data:`VARIANTS`), interleaved with the library's
  settings over ``--rounds`` rounds, each solve in its own child process:
  solve time, iterations, and whether the solution is bit-identical to the
  library's (the reproducibility the library promises).

Usage::

    python benchmarks/cylinder_profile.py --divisions 12 --skip 5
    python benchmarks/cylinder_profile.py --divisions 18 --skip 1
    python benchmarks/cylinder_profile.py --divisions 12 --skip 2 --variants all

The step is the reference paper's bare method, as the committed results
measured it (``--method bare``, pinned whatever the scene's defaults);
``--method default`` profiles the quarter cylinder's default step instead
(stabilised, volume-keeping, with its speed defaults; add ``--name`` to keep
both), and ``--set KEY=VALUE`` adds scene overrides on top of either
(``--method default --set refine=none``: the default step on the uniform
lattice).  The
committed r0/6 result is older than the symmetry planes' prescribed
displacements: a rerun takes the same 14 iterations on 35 contact candidates
instead of 217, with 0.47 M factor non-zeros instead of 0.56 M (today's
default step: 13 iterations, 0.81 M).

Writes ``benchmarks/results/cylinder_profile_<divisions>.json`` and ``.md``.
The machine is shared: the child's times carry the load of the moment
(recorded as ``others``, cores used by other processes).
"""

from __future__ import annotations

import argparse
import json
import pickle
import re
import subprocess
import sys
import tempfile
from pathlib import Path
from statistics import median

import _harness as harness

import skfem_npfem.step.conic as conic
from skfem_npfem.scenes import get_scene
from skfem_npfem.scenes.collapse.cylinder import SEED
from skfem_npfem.scenes.collapse.runs import build_geometry

CHILD = r"""
import dataclasses, hashlib, json, pickle, sys, time
import clarabel
import numpy as np
from skfem_npfem.step.backends import pardiso_threads
from skfem_npfem.step.solver import SolverOptions
P, q, A, b, cones, opts = pickle.load(open(sys.argv[1], "rb"))
variant = json.loads(sys.argv[2])
if "reproducible" in variant:
    opts = dataclasses.replace(opts, reproducible=variant["reproducible"])
cones = [getattr(clarabel, name)(dim) for name, dim in cones]
with pardiso_threads(opts.max_threads):
    s = opts.clarabel_settings("mkl")
    iparm = list(s.pardiso_iparm)
    for i, v in variant.get("iparm", {}).items():
        iparm[int(i)] = int(v)
    s.pardiso_iparm = iparm
    s.pardiso_verbose = True
    t0 = time.perf_counter()
    solver = clarabel.DefaultSolver(P, q, A, b, cones, s)
    t1 = time.perf_counter()
    sol = solver.solve()
    t2 = time.perf_counter()
digest = hashlib.sha256(np.asarray(sol.x).tobytes()).hexdigest()[:16]
print("@@", sol.status, sol.iterations, t1 - t0, t2 - t1, digest, flush=True)
"""

#: Pardiso options measured against the library's settings (``--variants``):
#: name -> changes (0-based ``iparm`` indices; ``reproducible`` of
#: :class:`~skfem_npfem.step.solver.SolverOptions`).
#: ``label`` names it in the table (the child ignores it).
VARIANTS: dict[str, dict] = {
    "two-level": {"iparm": {23: 1}, "label": "two-level factorisation (iparm[23] = 1)"},
    "diagonal-pivots": {
        "iparm": {20: 0},
        "label": "1x1 diagonal pivoting (iparm[20] = 0)",
    },
    "min-degree": {"iparm": {1: 0}, "label": "minimum-degree ordering (iparm[1] = 0)"},
    "no-cnr": {"reproducible": False, "label": "no CNR (reproducible = False)"},
}
LIBRARY = "library (METIS, Bunch-Kaufman pivots, CNR)"


def _floats(pattern: str, text: str) -> list[float]:
    return [float(x) for x in re.findall(pattern, text)]


def _first(pattern: str, text: str) -> float | None:
    found = _floats(pattern, text)
    return found[0] if found else None


def _count(pattern: str, text: str) -> int | None:
    found = _first(pattern, text)
    return None if found is None else int(found)


def capture_step(sim) -> dict:
    """Step ``sim`` once; return the scaled program Clarabel was given.

    Keys ``P, q, A, b, cones, options`` (Clarabel's arguments), and ``ns``
    (stress variables per particle) and ``sigma`` (their slice in the layout)
    from the step's :class:`~skfem_npfem.step.program.Program`.
    """
    captured: dict = {}
    solve, build = conic.solve_clarabel, conic.build_program

    def spy(P, q, A, b, cones, options, dim, *rest, **kw):
        captured.update(P=P, q=q, A=A, b=b, cones=cones, options=options)
        return solve(P, q, A, b, cones, options, dim, *rest, **kw)

    def spy_build(*args, **kw):
        prog, program = build(*args, **kw)
        captured.update(ns=int(prog.ns), sigma=prog.slice("sigma"))
        return prog, program

    conic.solve_clarabel, conic.build_program = spy, spy_build
    try:
        sim.run(steps=1)
    finally:
        conic.solve_clarabel, conic.build_program = solve, build
    return captured


def save_program(program: dict) -> str:
    """Pickle a captured program for the child processes; return its path."""
    desc = [(type(c).__name__, c.dim) for c in program["cones"]]
    keys = ("P", "q", "A", "b")
    data = (*(program[k] for k in keys), desc, program["options"])
    with tempfile.NamedTemporaryFile(suffix=".pkl", delete=False) as f:
        pickle.dump(data, f)
        return f.name


def pardiso_split(path: str, variant: dict | None = None) -> dict:
    """Solve the saved program with Pardiso's statistics; parse times and sizes.

    Pardiso prints no statistics for some options (the two-level
    factorisation): those entries are then None.
    """
    with harness.Meter() as m:
        proc = subprocess.run(
            [sys.executable, "-c", CHILD, path, json.dumps(variant or {})],
            capture_output=True,
            text=True,
            env=harness.child_env(),
        )
    out = proc.stdout + proc.stderr
    line = next(ln for ln in out.splitlines() if ln.startswith("@@"))
    _, status, its, setup, solve, digest = line.split()
    numfct = _floats(r"factorization step[^:]*:\s+([\d.]+)", out)
    solves = _floats(r"at solve step \(solve\)\s+:\s+([\d.]+)", out)
    refine = _floats(r"iterative refinement steps performed\s+(\d+)", out)
    return {
        "status": status,
        "iterations": int(its),
        "setup_s": float(setup),
        "solve_s": float(solve),
        "x_digest": digest,
        "kkt_equations": _count(r"number of equations:\s+(\d+)", out),
        "kkt_nnz": _count(r"number of non-zeros in A:\s+(\d+)", out),
        "factor_nnz": _count(r"number of non-zeros in L:\s+(\d+)", out),
        "gflop_per_factorisation": _first(
            r"gflop\s+for the numerical factorization:\s+([\d.]+)", out
        ),
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
        **harness.method_overrides("quarter-cylinder", args.method),
        **dict(args.set),
    }
    values = get_scene("column-collapse").resolve(over)
    sim = build_geometry(values).simulation
    sim.run(steps=args.skip)
    with harness.Meter() as m:
        captured = capture_step(sim)
    rec = sim.records[-1]
    path = save_program(captured)
    try:
        split = pardiso_split(path)
        variants = compare_variants(path, args.variants, args.rounds)
    finally:
        Path(path).unlink()
    return {
        "divisions": args.divisions,
        "method": args.method,
        "set": dict(args.set),
        "scene_overrides": over,
        "n_particles": int(sim.particles.n),
        "step": rec.step,
        "status": rec.status,
        "iterations": rec.iterations,
        "wall_s": m.wall,
        "others": m.others,
        "phases_s": rec.timings,
        "n_contacts": rec.n_contacts,
        "pardiso": split,
        "variants": variants,
        "machine": harness.machine_info(),
    }


def compare_variants(path: str, names: str, rounds: int) -> dict:
    """Solve the saved program with the library's settings and each variant.

    The solves alternate (library, variant 1, variant 2, ..., then again for
    each round), so that every setting sees the same machine load.  Returns
    ``{name: [solve record per round]}`` with the library's settings under
    ``"library"``.
    """
    if not names:
        return {}
    chosen = list(VARIANTS) if names == "all" else names.split(",")
    unknown = [n for n in chosen if n not in VARIANTS]
    if unknown:
        raise SystemExit(f"error: unknown variants {unknown}; known: {list(VARIANTS)}")
    out: dict[str, list] = {"library": [], **{n: [] for n in chosen}}
    for _ in range(rounds):
        out["library"].append(pardiso_split(path))
        for name in chosen:
            out[name].append(pardiso_split(path, VARIANTS[name]))
    return out


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def variants_markdown(variants: dict) -> list[str]:
    """Rows of the variants table: median solve time and its ratio."""
    if not variants:
        return []
    base = median(r["solve_s"] for r in variants["library"])
    digest = variants["library"][0]["x_digest"]
    lines = [
        "",
        "Pardiso options against the library's settings, the same program solved "
        f"{len(variants['library'])} times each, interleaved (median solve time; "
        "`repeatable`: its own solves bit-identical to each other; `= library`: "
        "bit-identical to the library's):",
        "",
        "| settings | solve s (median) | ratio | IPM it. | GFLOP per factorisation "
        "| repeatable | = library |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, recs in variants.items():
        t = median(r["solve_s"] for r in recs)
        gflop = recs[0]["gflop_per_factorisation"]
        lines.append(
            f"| {VARIANTS[name]['label'] if name in VARIANTS else LIBRARY} | "
            f"{t:.2f} | {t / base:.2f} | "
            f"{'/'.join(str(r['iterations']) for r in recs)} | "
            f"{'—' if gflop is None else f'{gflop:.1f}'} | "
            f"{_yes(len({r['x_digest'] for r in recs}) == 1)} | "
            f"{_yes(recs[0]['x_digest'] == digest)} |"
        )
    return lines


#: What ``--method`` measured, as the report's title says it (results
#: written before the option existed measured the bare method).
METHOD_LABEL = {"bare": "the paper's bare method", "default": "today's defaults"}


def markdown(rep: dict) -> str:
    ph, pa = rep["phases_s"], rep["pardiso"]
    total = sum(ph.values())
    rest = pa["solve_s"] - pa["factorisation_s"] - pa["triangular_solve_s"]
    rate = pa["gflop_per_factorisation"] * pa["factorisations"] / pa["factorisation_s"]
    lines = [
        f"# One 3D seed-column step: spacing r0/{rep['divisions']:g}, "
        f"{rep['n_particles']} particles, step {rep['step']}, "
        f"{METHOD_LABEL[rep.get('method', 'bare')]}"
        + "".join(f", {k}={v}" for k, v in rep.get("set", {}).items()),
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
        f"per factorisation, factorised at {rate:.1f} GFLOP/s.",
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
    lines += variants_markdown(rep.get("variants", {}))
    return "\n".join(lines) + "\n"


def _override(text: str) -> tuple[str, str]:
    """``KEY=VALUE`` as ``skfem-npfem run --set`` takes it (the scene converts)."""
    key, sep, value = text.partition("=")
    if not key or not sep:
        raise argparse.ArgumentTypeError(f"{text!r}: expected KEY=VALUE")
    return key, value


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--divisions", type=float, default=12.0)
    ap.add_argument("--skip", type=int, default=5, help="steps before the profile")
    ap.add_argument(
        "--variants",
        default="",
        help=f"'all' or comma-separated names of {list(VARIANTS)} (default: none)",
    )
    ap.add_argument("--rounds", type=int, default=2, help="solves of each variant")
    harness.add_method_argument(ap)
    ap.add_argument(
        "--set",
        action="append",
        default=[],
        type=_override,
        metavar="KEY=VALUE",
        help="a scene override on top of the method, as `skfem-npfem run --set` "
        "takes it (repeatable): refine=none",
    )
    ap.add_argument("--name", default=None, help="result file stem")
    ap.add_argument("--render", default=None, help="rewrite FILE.md from FILE.json")
    args = ap.parse_args(argv)
    if args.render:
        return harness.render(args.render, markdown)
    rep = run(args)
    stem = args.name or f"cylinder_profile_{args.divisions:g}"
    path = harness.HERE / "results" / f"{stem}.json"
    harness.write_report(path, rep, markdown(rep))
    print(markdown(rep))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
