#!/usr/bin/env python
"""Wall time per N-PFEM step: gravity-loaded Drucker-Prager block, 2D and 3D.

Each (case, linear solver) pair runs in its own subprocess (this script called
with ``--case NAME --solver S``) so that memory peaks and solver threads are
independent.  The parent collects the per-step records and writes

* ``<out>/step_time.json``  (machine info + every step of every run)
* ``<out>/step_time.md``    (summary table)

Usage::

    PYTHONPATH=. python benchmarks/step_time.py                      # all cases
    PYTHONPATH=. python benchmarks/step_time.py --cases 2d-1k,2d-4k --solvers faer
    PYTHONPATH=. python benchmarks/step_time.py --compare before.json after.json
    PYTHONPATH=. python benchmarks/step_time.py --case 2d-4k --solver qdldl \
        --profile step.prof                                         # cProfile one run

See ``benchmarks/README.md``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

import _harness as harness
from _harness import fmt_s

# --------------------------------------------------------------------------------
# Cases
# --------------------------------------------------------------------------------
# Block W x H (2D) or W x D x H (3D); n = elements over the height, 2n over W.
WIDTH, DEPTH, HEIGHT = 2.0, 1.0, 1.0
SIZES: dict[str, dict] = {
    "2d-1k": {"dim": 2, "n": 22},  # 45 x 23      = 1 035 nodes
    "2d-4k": {"dim": 2, "n": 44},  # 89 x 45      = 4 005 nodes
    "2d-16k": {"dim": 2, "n": 89},  # 179 x 90     = 16 110 nodes
    "3d-3k": {"dim": 3, "n": 11},  # 23 x 12 x 12 = 3 312 nodes
    "3d-10k": {"dim": 3, "n": 16},  # 33 x 17 x 17 = 9 537 nodes
}
# Side conditions.  "open" (default): rollers on every side wall except the face
# x = W, which is free, so that the block starts to collapse and many yield
# cones are active (10-11 IPM iterations).  "confined": rollers on all side
# walls; the geostatic state is then in exact equilibrium and strictly inside
# the cone (K0 = 0.5 > K0 at yield ~ 0.47), the step is elastic, no cone is
# active and Clarabel needs only 6-7 iterations.
VARIANTS = ("open", "confined")
CASES: dict[str, dict] = {
    **{k: {**v, "variant": "open"} for k, v in SIZES.items()},
    **{f"{k}-confined": {**v, "variant": "confined"} for k, v in SIZES.items()},
}
DEFAULT_CASES = tuple(SIZES)
SOLVERS = ("qdldl", "faer")
# docs/performance.md, "Reference timings": a straightforward implementation,
# granular collapse, 2-core EPYC VM, seconds per 2D step (qdldl; faer 0.52 /
# 3.08 / 18.8 s solve).
REFERENCE_BY_SIZE = {"2d-1k": 0.32, "2d-4k": 2.3, "2d-16k": 20.0}
REFERENCE = {
    name: REFERENCE_BY_SIZE[name.removesuffix("-confined")]
    for name in CASES
    if name.removesuffix("-confined") in REFERENCE_BY_SIZE
}
# Why a pair is usually skipped (printed in the notes when --skip names it).
SKIP_REASONS = {
    ("3d-10k", "qdldl"): "far above the ~2 min per step budget: a one-step probe "
    "(`--case 3d-10k --solver qdldl --steps 1`) had not finished step 1 after "
    "8.5 min of CPU (qdldl is ~9x slower per IPM iteration than faer at 3d-3k: "
    "5.5 vs 0.58 s)",
    ("3d-3k-confined", "qdldl"): "to save time (3d-3k / qdldl covers the size)",
}
PHASES = ("mesh", "assembly", "setup", "solve", "update")

# Physics (SI).
E, NU, RHO, GRAV = 10.0e6, 0.3, 1800.0, 9.81
COHESION, PHI, PSI, K0 = 1.0e3, 30.0, 0.0, 0.5
DT = 5.0e-3


def case_nodes(name: str) -> int:
    """Number of nodes of a case (without building it)."""
    c = CASES[name]
    n = c["n"]
    return (2 * n + 1) * (n + 1) if c["dim"] == 2 else (2 * n + 1) * (n + 1) ** 2


# --------------------------------------------------------------------------------
# Child: build and run one case
# --------------------------------------------------------------------------------
def build_case(name: str, linear_solver: str, threads: int, time_limit: float):
    """Particles, model and mesh source of a case."""
    import numpy as np
    from skfem import MeshTet, MeshTri

    from skfem_npfem import FixedMesh, Model, SolverOptions
    from skfem_npfem.materials import DruckerPrager
    from skfem_npfem.mesh.smoothing import nodal_integration
    from skfem_npfem.particles import Particles

    c = CASES[name]
    dim, n = c["dim"], c["n"]
    xs = np.linspace(0.0, WIDTH, 2 * n + 1)
    zs = np.linspace(0.0, HEIGHT, n + 1)
    if dim == 2:
        mesh = MeshTri.init_tensor(xs, zs)
        mat = DruckerPrager(E, NU, RHO, c=COHESION, phi=PHI, psi=PSI)
    else:
        ys = np.linspace(0.0, DEPTH, n + 1)
        mesh = MeshTet.init_tensor(xs, ys, zs)
        mat = DruckerPrager(
            E, NU, RHO, c=COHESION, phi=PHI, psi=PSI, match="compression"
        )
    x = mesh.p.T.copy()
    npts = x.shape[0]
    vol = nodal_integration(mesh).volumes
    # Geostatic stress: s_v = -rho g (H - z), s_h = K0 s_v (full Voigt).
    sv = -RHO * GRAV * (HEIGHT - x[:, -1])
    stress = np.zeros((npts, 4 if dim == 2 else 6))
    stress[:, :3] = K0 * sv[:, None]
    stress[:, dim - 1] = sv
    # Fixed base, rollers on the side walls.
    fixed = np.zeros((npts, dim), bool)
    fixed[np.isclose(x[:, -1], 0.0)] = True
    extent = (WIDTH, DEPTH) if dim == 3 else (WIDTH,)
    for k in range(dim - 1):
        fixed[np.isclose(x[:, k], 0.0) | np.isclose(x[:, k], extent[k]), k] = True
    if c["variant"] == "open":
        fixed[np.isclose(x[:, 0], WIDTH) & ~np.isclose(x[:, -1], 0.0), 0] = False
    particles = Particles.create(x, RHO * vol, stress=stress, fixed=fixed)
    model = Model(
        dim=dim,
        materials=[mat],
        gravity=GRAV,
        mode="dynamic",
        theta1=1.0,
        theta2=1.0,
        solver=SolverOptions(
            linear_solver=linear_solver, max_threads=threads, time_limit=time_limit
        ),
    )
    return particles, model, FixedMesh(mesh.t)


def yield_active_fraction(model, p_old, result) -> float:
    """Fraction of nodes on the yield surface at the end of the step."""
    import numpy as np

    sol = result.solution
    mat = model.materials[0]
    comp = tuple(model.components)
    cone = mat.cone(model.dim, comp, p_old.stress[result.active])
    s = sol.sigma[:, list(comp)]
    rhs = cone.k - np.einsum("ni,ni->n", cone.a, s)
    norm = np.linalg.norm(s @ cone.M.T, axis=1)
    return float(np.mean(norm >= (1.0 - 1e-3) * rhs))


def run_child(args) -> dict:
    """Run one case with one solver; return a JSON-able record."""
    t_import = time.perf_counter()
    import numpy as np

    from skfem_npfem import advance
    from skfem_npfem.errors import SolverError

    t_import = time.perf_counter() - t_import
    rss0 = harness.peak_rss_mb()
    t0 = time.perf_counter()
    p, model, mesh_source = build_case(
        args.case, args.solver, args.threads, args.time_limit
    )
    t_init = time.perf_counter() - t0
    out = {
        "case": args.case,
        "dim": CASES[args.case]["dim"],
        "variant": CASES[args.case]["variant"],
        "nodes": int(p.n),
        "solver": args.solver,
        "threads": args.threads,
        "steps_requested": args.steps,
        "dt": DT,
        "source_sha1": harness.source_hash(),
        "init_s": t_init,
        "import_s": t_import,
        "rss_after_import_mb": rss0,
        "steps": [],
        "note": "",
    }
    profiler = None
    if args.profile:
        import cProfile

        profiler = cProfile.Profile()
    for k in range(1, args.steps + 1):
        load = os.getloadavg()[0]
        c0 = time.process_time()
        t0 = time.perf_counter()
        try:
            if profiler is not None:
                profiler.enable()
            new, result = advance(p, model, DT, mesh_source, step=k)
        except SolverError as err:
            out["steps"].append(
                {
                    "step": k,
                    "status": err.status,
                    "iterations": err.iterations,
                    "wall": time.perf_counter() - t0,
                    "peak_rss_mb": harness.peak_rss_mb(),
                }
            )
            out["note"] = f"solver failed at step {k}: {err.status}"
            break
        finally:
            if profiler is not None:
                profiler.disable()
        wall = time.perf_counter() - t0
        cpu = time.process_time() - c0
        rec = result.record
        phases = {ph: float(rec.timings.get(ph, 0.0)) for ph in PHASES}
        phases["other"] = max(wall - sum(phases.values()), 0.0)
        step = {
            "step": k,
            "status": rec.status,
            "iterations": int(rec.iterations),
            "phases": phases,
            # Step 1 also pays the case build (structured mesh, initial
            # smoothing cells, particles): reported in "total", not in "wall".
            "wall": wall,
            "total": wall + (t_init if k == 1 else 0.0),
            # CPU time of all threads of the process, and the 1-min load average
            # before the step (> cores: the machine was shared, times inflated).
            "cpu": cpu,
            "loadavg_1min": load,
            "sizes": {
                k2: int(v) if isinstance(v, int | float) else v
                for k2, v in result.solution.sizes.items()
            },
            "n_cones": int(rec.n_active),
            "yield_active_fraction": yield_active_fraction(model, p, result),
            "max_speed": float(np.max(np.linalg.norm(new.v, axis=1))),
            "peak_rss_mb": harness.peak_rss_mb(),
        }
        out["steps"].append(step)
        p = new
        if wall > args.step_limit and k < args.steps:
            out["note"] = (
                f"stopped after step {k}: {wall:.0f} s > step limit "
                f"{args.step_limit:g} s"
            )
            break
    out["peak_rss_mb"] = harness.peak_rss_mb()
    if profiler is not None:
        import pstats

        profiler.dump_stats(args.profile)
        st = pstats.Stats(profiler, stream=sys.stderr)
        st.sort_stats("cumulative").print_stats(30)
        st.sort_stats("tottime").print_stats(30)
    return out


# --------------------------------------------------------------------------------
# Parent: drive subprocesses, summarise
# --------------------------------------------------------------------------------
def run_subprocess(case: str, solver: str, args) -> dict:
    """Run one (case, solver) pair in a fresh interpreter."""
    if args.wait_load > 0:
        harness.wait_for_quiet(args.wait_load, args.wait_max)
    child_args = [
        "--case",
        case,
        "--solver",
        solver,
        "--steps",
        str(args.steps),
        "--threads",
        str(args.threads),
        "--step-limit",
        str(args.step_limit),
        "--time-limit",
        str(args.time_limit),
    ]
    timeout = args.steps * (args.time_limit + 120.0) + 300.0
    res, note, wall, _ = harness.run_child(
        Path(__file__).resolve(),
        child_args,
        timeout,
        failed="subprocess failed",
        killed="subprocess killed after {timeout:.0f} s",
        tail=2000,
    )
    if res is None:
        return {
            "case": case,
            "solver": solver,
            "nodes": case_nodes(case),
            "steps": [],
            "note": note,
        }
    res["subprocess_s"] = wall
    return res


def summarise(run: dict) -> dict:
    """Median step time, phase split, iterations of one run."""
    steps = [s for s in run.get("steps", []) if "phases" in s]
    if not steps:
        return {}
    totals = [s["total"] for s in steps]
    walls = [s["wall"] for s in steps]
    phase_sum = {ph: sum(s["phases"][ph] for s in steps) for ph in (*PHASES, "other")}
    tot = sum(phase_sum.values()) or 1.0
    return {
        "median_s": statistics.median(totals),
        "median_wall_s": statistics.median(walls),
        "min_wall_s": min(walls),
        "split_pct": {ph: 100.0 * v / tot for ph, v in phase_sum.items()},
        "median_phase_s": {
            ph: statistics.median(s["phases"][ph] for s in steps) for ph in PHASES
        },
        "iterations": [s["iterations"] for s in steps],
        "statuses": sorted({s["status"] for s in steps}),
        "s_per_iteration": statistics.median(
            s["phases"]["solve"] / max(s["iterations"], 1) for s in steps
        ),
        "sizes": steps[0]["sizes"],
        "yield_active_fraction": [round(s["yield_active_fraction"], 3) for s in steps],
        "peak_rss_mb": max(s["peak_rss_mb"] for s in steps),
        "median_cpu_s": statistics.median(s.get("cpu", math.nan) for s in steps),
        "max_loadavg": max(s.get("loadavg_1min", math.nan) for s in steps),
    }


def markdown(report: dict) -> str:
    """Summary table of a report."""
    m = report["machine"]
    lines = [
        "# N-PFEM step time",
        "",
        f"Machine: {m['cpu']} ({m['cores_available']} of {m['cores']} cores, "
        f"{m['memory_gb']} GB), Python {m['python']}, numpy {m['numpy']}, "
        f"scipy {m['scipy']}, clarabel {m['clarabel']}, scikit-fem {m['scikit-fem']}; "
        f"{m['date']}.",
        "",
        harness.code_line(m.get("code", {})),
        "",
        f"Problem: {report['problem']}",
        "",
        "Median over the steps of the wall time per step; step 1 includes the case "
        "build (structured mesh, initial smoothing cells, particles). Phase split "
        "is of the summed step times: mesh / assembly / Clarabel setup / solve / "
        "update (/ other = glue in `advance` outside the timed phases).  "
        "`yield-active`: nodes on the yield surface after each step.  "
        "`cpu s`: median process CPU time per step (all threads; for the "
        "single-threaded qdldl a proxy for the time on an idle core).  "
        "`cpu/wall`: process CPU time (all threads) / wall time; `load`: largest "
        "1-min load average seen before a step (above the core count the machine "
        "was shared and the wall times are inflated).  "
        "`ref` = median / reference (0.32, 2.3, 20 s per 2D step of a "
        "straightforward implementation, docs/performance.md, 'Reference timings': "
        "a granular collapse on a 2-core EPYC VM — indicative only, < 1 is faster).",
        "",
        "| case | nodes | solver | vars / rows / nnz(A) | median s/step | cpu s | "
        "mesh/asm/setup/solve/upd/other % | s/iter | IPM iterations | status | "
        "yield-active | peak MB | cpu/wall | load | ref |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for run in report["runs"]:
        s = run.get("summary") or {}
        case, solver = run["case"], run["solver"]
        nodes = run.get("nodes", case_nodes(case))
        if not s:
            lines.append(
                f"| {case} | {nodes} | {solver} | | "
                + ("skipped" if run.get("note") else "—")
                + " |" * 11
            )
            continue
        sp = s["split_pct"]
        split = "/".join(f"{sp[ph]:.0f}" for ph in (*PHASES, "other"))
        sz = s["sizes"]
        sizes = f"{sz['variables']} / {sz['rows']} / {sz['nnz_A']}"
        ref = REFERENCE.get(case)
        ratio = f"{s['median_s'] / ref:.2f}" if ref else "—"
        its = ", ".join(str(i) for i in s["iterations"])
        ya = ", ".join(f"{100 * f:.0f}%" for f in s["yield_active_fraction"])
        lines.append(
            f"| {case} | {nodes} | {solver} | {sizes} | {fmt_s(s['median_s'])} | "
            f"{fmt_s(s['median_cpu_s'])} | "
            f"{split} | {fmt_s(s['s_per_iteration'])} | {its} | "
            f"{', '.join(s['statuses'])} | {ya} | {s['peak_rss_mb']:.0f} | "
            f"{s['median_cpu_s'] / s['median_wall_s']:.2f} | "
            f"{s['max_loadavg']:.1f} | {ratio} |"
        )
    by_hash = harness.runs_by_hash(
        report["runs"], lambda r: f"{r['case']}/{r['solver']}"
    )
    changed = (
        [
            "",
            "**Warning**: the library sources changed during the sweep; runs with "
            "different hashes are not strictly comparable: "
            + "; ".join(f"{h}: {', '.join(v)}" for h, v in by_hash.items())
            + ".",
        ]
        if len(by_hash) > 1
        else []
    )
    notes = [
        f"* {r['case']} / {r['solver']}: {r['note']}"
        for r in report["runs"]
        if r.get("note")
    ]
    return harness.finish_markdown(lines + changed, notes)


def compare(path_a: str, path_b: str) -> str:
    """Before/after table of two JSON reports."""
    a, b, rows = harness.load_pair(path_a, path_b)

    def index(rep):
        return {(r["case"], r["solver"]): r.get("summary") or {} for r in rep["runs"]}

    ia, ib = index(a), index(b)
    keys = [k for k in ia if k in ib] + [k for k in ib if k not in ia]
    rows += [
        "| case | solver | A s/step | B s/step | B/A | A solve | B solve | B/A solve "
        "| A non-solve | B non-solve | B/A non-solve | A iters | B iters |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    for key in keys:
        sa, sb = ia.get(key, {}), ib.get(key, {})
        if not sa or not sb:
            rows.append(f"| {key[0]} | {key[1]} | " + ("| " * 11).strip())
            continue
        ta, tb = sa["median_s"], sb["median_s"]
        xa, xb = sa["median_phase_s"]["solve"], sb["median_phase_s"]["solve"]
        na, nb = (
            harness.non_solver_s(sa["median_phase_s"]),
            harness.non_solver_s(sb["median_phase_s"]),
        )
        rows.append(
            f"| {key[0]} | {key[1]} | {fmt_s(ta)} | {fmt_s(tb)} | {tb / ta:.2f} | "
            f"{fmt_s(xa)} | {fmt_s(xb)} | {xb / xa:.2f} | {fmt_s(na)} | {fmt_s(nb)} | "
            f"{nb / na:.2f} | {sa['iterations']} | {sb['iterations']} |"
        )
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--cases",
        default=",".join(DEFAULT_CASES),
        help=f"comma-separated cases from {list(CASES)}",
    )
    ap.add_argument("--solvers", default=",".join(SOLVERS), help="qdldl,faer")
    ap.add_argument("--steps", type=int, default=3, help="steps per run")
    ap.add_argument("--out", default=str(HERE / "results"), help="output folder")
    ap.add_argument(
        "--threads", type=int, default=0, help="Clarabel max_threads (0: automatic)"
    )
    ap.add_argument(
        "--step-limit",
        type=float,
        default=120.0,
        help="stop a run after the first step that takes longer (s)",
    )
    ap.add_argument(
        "--time-limit",
        type=float,
        default=900.0,
        help="Clarabel time limit per solve (s); the subprocess is killed later",
    )
    ap.add_argument(
        "--skip",
        default="",
        help="comma-separated case:solver pairs not to run (recorded as skipped)",
    )
    ap.add_argument(
        "--wait-load",
        type=float,
        default=0.0,
        help="before each run, wait until the 1-min load average is below this "
        "(0: do not wait; shared machines)",
    )
    ap.add_argument(
        "--wait-max", type=float, default=300.0, help="longest wait per run (s)"
    )
    ap.add_argument("--compare", nargs=2, metavar=("A.json", "B.json"))
    ap.add_argument(
        "--render",
        metavar="FILE.json",
        help="rewrite FILE.md from FILE.json (after editing notes, or a new table "
        "layout)",
    )
    ap.add_argument("--case", help=argparse.SUPPRESS)  # child mode
    ap.add_argument("--solver", default="faer", help=argparse.SUPPRESS)
    ap.add_argument(
        "--profile",
        metavar="FILE.prof",
        help="with --case: run in-process under cProfile, dump stats to FILE",
    )
    args = ap.parse_args(argv)

    if args.compare:
        print(compare(*args.compare))
        return 0
    if args.render:
        path = Path(args.render)
        report = json.loads(path.read_text())
        for run in report["runs"]:
            key = (run["case"], run["solver"])
            if not run.get("steps") and key in SKIP_REASONS:
                run["note"] = f"skipped (--skip): {SKIP_REASONS[key]}"
        harness.write_report(path, report, markdown(report))
        print(markdown(report))
        return 0
    if args.case:
        if args.case not in CASES:
            ap.error(f"unknown case {args.case!r}; choose from {list(CASES)}")
        harness.emit_result(run_child(args))
        return 0

    cases = [c for c in args.cases.split(",") if c]
    solvers = [s for s in args.solvers.split(",") if s]
    for c in cases:
        if c not in CASES:
            ap.error(f"unknown case {c!r}; choose from {list(CASES)}")
    skip = {tuple(x.split(":")) for x in args.skip.split(",") if x}
    report = {
        "machine": harness.machine_info(),
        "problem": (
            f"Drucker-Prager block {WIDTH:g} x {HEIGHT:g} m (3D: {WIDTH:g} x "
            f"{DEPTH:g} x {HEIGHT:g} m) under gravity, geostatic initial stress "
            f"(K0 = {K0:g}), E = {E:g} Pa, nu = {NU:g}, rho = {RHO:g}, "
            f"c = {COHESION:g} Pa, phi = {PHI:g}, psi = {PSI:g} (frozen friction), "
            f"DP match plane-strain (2D) / compression (3D); fixed base; 'open' "
            "cases: rollers on the side walls except the free face x = W (the "
            "block starts to collapse); '-confined' cases: rollers on all side "
            "walls (static equilibrium, elastic step); dynamic theta1 = theta2 = 1, "
            f"dt = {DT:g} s; structured "
            "MeshTri/MeshTet.init_tensor, FixedMesh."
        ),
        "settings": {
            "steps": args.steps,
            "threads": args.threads,
            "step_limit_s": args.step_limit,
            "time_limit_s": args.time_limit,
            "wait_load": args.wait_load,
            "loadavg_at_start": os.getloadavg(),
        },
        "reference_s_per_step": REFERENCE,
        "runs": [],
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for case in cases:
        for solver in solvers:
            if (case, solver) in skip:
                run = {
                    "case": case,
                    "solver": solver,
                    "nodes": case_nodes(case),
                    "steps": [],
                    "note": "skipped (--skip)"
                    + (
                        f": {SKIP_REASONS[(case, solver)]}"
                        if (case, solver) in SKIP_REASONS
                        else ""
                    ),
                }
            else:
                print(f"{case:7s} {solver:6s} ...", end=" ", flush=True)
                run = run_subprocess(case, solver, args)
            run["summary"] = summarise(run)
            s = run["summary"]
            if s:
                print(
                    f"median {s['median_s']:.3f} s/step, solve "
                    f"{s['split_pct']['solve']:.0f} %, iterations {s['iterations']}, "
                    f"peak {s['peak_rss_mb']:.0f} MB {run.get('note', '')}",
                    flush=True,
                )
            else:
                print(run.get("note", "no result"), flush=True)
            report["runs"].append(run)
            # Write after every run so that partial results survive.
            harness.write_report(out / "step_time.json", report, markdown(report))
    print(markdown(report))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
