#!/usr/bin/env python
"""What the ``fast`` solver preset costs against ``high``: accuracy, iterations, time.

Two measurements (``benchmarks/README.md``):

``--step``  one step, same state, every backend x preset against a tight
    reference (qdldl, or faer in 3D, tol 1e-10 with iterative refinement).  The
    state is reached with the reference-free default settings (qdldl / faer,
    ``high``) after ``warm`` steps.  Reports the relative difference of the
    displacement increment Δu and of the stress σ (2-norm over all nodes and
    components, relative to ||Δu_ref||, to ||σ_ref|| and to the stress increment
    ||σ_ref - σ_n||; and the max norm), IPM iterations and the solve time.

``--full``  whole scene runs, one subprocess per (run, variant), interleaved:
    the column collapse (a = 2) to rest at spacing L0/div, and the strip footing
    (8 steps) at a spacing; per variant (``default``, ``high``, ``fast``, optionally
    ``preset@backend``) the scene metrics, IPM iterations, steps, wall time of the
    run (``wall_time_total``), CPU time, peak memory and load.

Usage::

    PYTHONPATH=. python benchmarks/presets.py --step collapse-4k,block3d-3k,footing-4.8k
    PYTHONPATH=. python benchmarks/presets.py --full collapse:12,footing:0.03125 \\
        --variants default,fast --repeat 2
    PYTHONPATH=. python benchmarks/presets.py --render results/presets_full.json

Writes ``<out>/presets_step.json|md`` and ``<out>/presets_full.json|md``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import time
from dataclasses import replace
from pathlib import Path

HERE = Path(__file__).resolve().parent

import _harness as harness
import _tables as docs_tables
import suite

#: Warm-up steps (with the default settings) before the compared step.
STEP_CASES = {
    "collapse-1k": 40,  # t = 0.2 s: the column is flowing
    "collapse-4k": 5,
    "collapse-16k": 5,
    "block3d-3k": 2,
    "block3d-11k": 2,
    "footing-1.6k": 7,  # the 8th (last, plateau) settlement step
    "footing-4.8k": 7,
}
REF_TOL = 1e-10


# --------------------------------------------------------------------------------
# One step, many solvers
# --------------------------------------------------------------------------------
def _norms(sol, ref, sigma_n) -> dict:
    import numpy as np

    ddu = sol.du - ref.du
    dsg = sol.sigma - ref.sigma
    inc = ref.sigma - sigma_n
    return {
        "du_rel": float(np.linalg.norm(ddu) / np.linalg.norm(ref.du)),
        "du_rel_max": float(np.max(np.abs(ddu)) / np.max(np.abs(ref.du))),
        "sigma_rel": float(np.linalg.norm(dsg) / np.linalg.norm(ref.sigma)),
        "sigma_rel_increment": float(np.linalg.norm(dsg) / np.linalg.norm(inc)),
        "sigma_rel_max": float(np.max(np.abs(dsg)) / np.max(np.abs(ref.sigma))),
    }


def step_accuracy(case: str, backends: list[str], presets: list[str]) -> dict:
    """Solve one step of ``case`` with every backend x preset and the reference."""
    from skfem_npfem import SolverOptions, advance
    from skfem_npfem.errors import SolverError

    dim3 = suite.CASES[case]["kind"] == "block3d"
    base_backend = "faer" if dim3 else "qdldl"
    sim, _ = suite.build(case, base_backend, "high", 0)
    warm = STEP_CASES[case]
    sim.run(steps=warm)
    p, model, dt = sim.particles, sim.model, sim.dt
    k = sim.step + 1

    def solve(opts):
        m = replace(model, solver=opts)
        t0 = time.perf_counter()
        _, step = advance(p, m, dt, sim.mesh_source, step=k)
        return step, time.perf_counter() - t0

    ref_opts = SolverOptions(
        linear_solver=base_backend, tol=REF_TOL, iterative_refinement=True
    )
    ref, t_ref = solve(ref_opts)
    sigma_n = p.stress[ref.active]
    out = {
        "case": case,
        "particles": int(p.n),
        "warm_steps": warm,
        "step": k,
        "time": sim.time,
        "dt": dt,
        "variables": int(ref.solution.sizes["variables"]),
        "reference": {
            "backend": base_backend,
            "tol": REF_TOL,
            "iterations": ref.record.iterations,
            "status": ref.record.status,
            "solve_s": ref.record.timings["solve"],
        },
        "du_ref_max": float(abs(ref.solution.du).max()),
        "rows": [],
        "loadavg": [os.getloadavg()[0]],
    }
    sols = {}
    for backend in backends:
        if dim3 and backend == "qdldl":
            continue
        for preset in presets:
            opts = suite.solver_options(backend, preset)
            try:
                rec, wall = solve(opts)
            except SolverError as err:
                out["rows"].append(
                    {
                        "backend": backend,
                        "preset": preset,
                        "tol": opts.tol,
                        "status": err.status,
                        "iterations": err.iterations,
                        "failed": str(err),
                        "loadavg": os.getloadavg()[0],
                    }
                )
                print(f"  {case} {backend:5s} {preset:4s}: {err.status}", flush=True)
                continue
            sols[(backend, preset)] = rec.solution
            row = {
                "backend": backend,
                "preset": preset,
                "tol": opts.tol,
                "refinement": opts.clarabel_settings(
                    backend
                ).iterative_refinement_enable,
                "status": rec.record.status,
                "iterations": rec.record.iterations,
                "solve_s": rec.record.timings["solve"],
                "step_wall_s": wall,
                "loadavg": os.getloadavg()[0],
                **_norms(rec.solution, ref.solution, sigma_n),
            }
            out["rows"].append(row)
            print(
                f"  {case} {backend:5s} {preset:4s}: it {rec.record.iterations:3d}, du "
                f"{row['du_rel']:.2e}, sigma/inc {row['sigma_rel_increment']:.2e}",
                flush=True,
            )
    # fast vs high, same backend
    for row in out["rows"]:
        hi = sols.get((row["backend"], "high"))
        if row["preset"] != "high" and hi is not None and "failed" not in row:
            d = _norms(sols[(row["backend"], row["preset"])], hi, sigma_n)
            row["vs_high"] = d
    out["reference"]["step_wall_s"] = t_ref
    out["loadavg"].append(os.getloadavg()[0])
    return out


def markdown_step(report: dict) -> str:
    lines = [
        "# One step: fast vs high preset against a tight reference",
        "",
        f"{report['machine_line']}",
        "",
        "Same state (reached with the default settings), one step solved by every "
        "backend x preset.  Reference: tol 1e-10 with iterative refinement (qdldl in "
        "2D, faer in 3D).  `Δu`: ||Δu - Δu_ref||₂ / ||Δu_ref||₂ (max: in the max "
        "norm); `σ/σ`: ||σ - σ_ref||₂ / ||σ_ref||₂; `σ/Δσ`: the same over the "
        "stress increment ||σ_ref - σ_n||₂; `vs high`: Δu and σ/Δσ of the variant "
        "against high of the same backend.  Variants: `fast+ref` = tol 1e-6 with "
        "iterative refinement, `high-noref` = tol 1e-8 without.  `solve s`: "
        "Clarabel solve time (load in the last column).",
        "",
        "| case | step | variables | backend | preset | IPM it. | status | Δu | Δu max "
        "| σ/σ | σ/Δσ | vs high Δu | vs high σ/Δσ | solve s | load |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in report["cases"]:
        ref = c["reference"]
        lines.append(
            f"| {c['case']} | {c['step']} | {c['variables']} | {ref['backend']} | "
            f"tol 1e-10 (ref) | {ref['iterations']} | {ref['status']} | 0 | 0 | 0 | 0 "
            f"| | | {suite.fmt_s(ref['solve_s'])} | {c['loadavg'][0]:.1f} |"
        )
        for r in c["rows"]:
            if "failed" in r:
                lines.append(
                    f"| {c['case']} | {c['step']} | {c['variables']} | {r['backend']} "
                    f"| {r['preset']} | {r['iterations']} | **{r['status']}** |"
                    + " |"
                    * 8
                )
                continue
            vh = r.get("vs_high") or {}
            lines.append(
                f"| {c['case']} | {c['step']} | {c['variables']} | {r['backend']} | "
                f"{r['preset']} | {r['iterations']} | {r['status']} | "
                f"{r['du_rel']:.1e} | {r['du_rel_max']:.1e} | {r['sigma_rel']:.1e} | "
                f"{r['sigma_rel_increment']:.1e} | "
                + (
                    f"{vh['du_rel']:.1e} | {vh['sigma_rel_increment']:.1e} | "
                    if vh
                    else "— | — | "
                )
                + f"{suite.fmt_s(r['solve_s'])} | {r['loadavg']:.1f} |"
            )
    lines.append("")
    return "\n".join(lines)


# --------------------------------------------------------------------------------
# Whole runs
# --------------------------------------------------------------------------------
VARIANTS = {
    "default": {},
    "high": {"accuracy": "high"},
    "fast": {"accuracy": "fast"},
    # MKL Pardiso without its conditional numerical reproducibility mode.
    "nocnr": {"reproducible": False},
    "fast-nocnr": {"accuracy": "fast", "reproducible": False},
}


def variant_overrides(name: str) -> dict:
    """``preset`` or ``preset@backend`` -> scene overrides."""
    preset, _, backend = name.partition("@")
    ov = dict(VARIANTS[preset])
    if backend:
        ov["linear_solver"] = backend
    return ov


def run_overrides(run: str) -> tuple[str, dict]:
    """``collapse:12`` / ``footing:0.03125`` -> (scene, overrides)."""
    kind, _, val = run.partition(":")
    if kind == "collapse":
        return "column-collapse", {
            "spacing": suite.L0 / float(val),
            "t_end": 5.0,
            "output_every": 1000000,
        }
    if kind == "footing":
        return "strip-footing", {"spacing": float(val)}
    raise ValueError(run)


def full_child(run: str, variant: str) -> dict:
    """Run one scene to its end in this process; metrics and solver summary."""
    from skfem_npfem.scenes import run_scene

    scene, ov = run_overrides(run)
    ov.update(variant_overrides(variant))
    with harness.Meter() as meter:
        res = run_scene(scene, ov)
    metrics = {
        k: v for k, v in res["metrics"].items() if not isinstance(v, list | dict)
    }
    solver = res["solver"]
    hist = res["history"]
    return {
        "run": run,
        "variant": variant,
        "scene": scene,
        "overrides": ov,
        "metrics": metrics,
        "steps": solver["steps"],
        "time": solver["time"],
        "ipm_iterations_total": solver["ipm_iterations_total"],
        "ipm_iterations_mean": solver["ipm_iterations_mean"],
        "statuses": solver["statuses"],
        "retries": solver["retries"],
        "linear_solvers": solver["linear_solvers"],
        "step_time_median": solver["step_time_median"],
        "phase_total_s": solver["wall_time"],
        "wall_time_total": res["wall_time_total"],
        "wall_s": meter.wall,
        "cpu_s": meter.cpu,
        "peak_memory_mb": solver["peak_memory_mb"],
        "loadavg_before": meter.load_before,
        "loadavg_after": os.getloadavg()[0],
        "other_cores": meter.others,
        "n_particles": solver["n_particles"],
        "dt_last": hist[-1]["dt"] if hist else None,
    }


def run_full_subprocess(run: str, variant: str, args) -> dict:
    if args.wait_load > 0:
        harness.wait_for_quiet(args.wait_load, args.wait_max)
    if args.wait_idle > 0:
        harness.wait_for_idle(args.wait_idle, args.wait_max)
    res, note, wall, cpu = harness.run_child(
        Path(__file__).resolve(),
        ["--full-child", f"{run}|{variant}"],
        args.timeout,
        killed="killed after {timeout} s",
    )
    if res is None:
        return {"run": run, "variant": variant, "note": note}
    res["subprocess_s"] = wall
    res["subprocess_cpu_s"] = cpu
    return res


FULL_KEYS = {
    "column-collapse": (
        ("normalised_runout", ".4f"),
        ("final_height", ".4f"),
        ("collapse_time", ".3f"),
        ("volume_change", ".2e"),
    ),
    "strip-footing": (("q_ult", ".6g"), ("bearing_factor", ".5f")),
}


def _rel(v, v0) -> str:
    if v is None or v0 is None or v0 == 0:
        return "—"
    return f"{(v - v0) / abs(v0):+.2e}"


def markdown_full(report: dict) -> str:
    lines = [
        "# Whole runs per solver variant",
        "",
        f"{report['machine_line']}",
        "",
        "One subprocess per run and variant, interleaved (`--repeat` rounds); the "
        "metrics are deterministic (identical in every repeat), the times are the "
        "median of the repeats (each repeat listed).  `default` = scene defaults "
        "(tol 1e-8, backend auto; identical to `high`); `fast` = tol 1e-6 without "
        "iterative refinement.  `wall` = the scene's `wall_time_total` (build + all "
        "steps, no output); `cpu` = process CPU time (all threads); `load` = 1-min "
        "load average before-after the run; `others` = mean cores used by other "
        "processes during the run (/proc/stat minus our CPU time; 2 cores).",
        "",
    ]
    groups: dict[str, dict[str, list]] = {}
    for r in report["runs"]:
        groups.setdefault(r["run"], {}).setdefault(r["variant"], []).append(r)
    for run, byvar in groups.items():
        ok = [rs for rs in byvar.values() if any("metrics" in r for r in rs)]
        if not ok:
            continue
        scene = next(r for rs in ok for r in rs if "metrics" in r)["scene"]
        keys = FULL_KEYS[scene]
        lines += [
            f"## {run} ({scene})",
            "",
            "| variant | backend | particles | "
            + " | ".join(k for k, _ in keys)
            + " | Δ vs default (rel., first two) | steps | IPM it. total | it./step "
            "| wall s | runs | cpu s | s/step (median) | peak MB | load | others |",
            "|---|---|---|"
            + "---|" * len(keys)
            + "---|---|---|---|---|---|---|---|---|---|---|",
        ]
        base = next(
            (r for r in byvar.get("default", byvar.get("high", [])) if "metrics" in r),
            None,
        )
        for variant, rs in byvar.items():
            good = [r for r in rs if "metrics" in r]
            if not good:
                lines.append(f"| {variant} | {rs[0].get('note', '')[:80]} |")
                continue
            r0 = good[0]
            walls = [r["wall_time_total"] for r in good]
            cpus = [r["cpu_s"] for r in good]
            vals = " | ".join(
                "—" if r0["metrics"][k] is None else format(r0["metrics"][k], f)
                for k, f in keys
            )
            if base is not None and r0 is not base:
                delta = ", ".join(
                    _rel(r0["metrics"][k], base["metrics"][k]) for k, _ in keys[:2]
                )
            else:
                delta = "—"
            lines.append(
                f"| {variant} | {'/'.join(r0['linear_solvers'])} | "
                f"{r0['n_particles']} | {vals} | {delta} | {r0['steps']} | "
                f"{r0['ipm_iterations_total']} | {r0['ipm_iterations_mean']:.1f} | "
                f"{statistics.median(walls):.1f} | "
                + ", ".join(f"{w:.1f}" for w in walls)
                + f" | {statistics.median(cpus):.1f} | "
                f"{suite.fmt_s(statistics.median(r['step_time_median'] for r in good))}"
                f" | {max(r['peak_memory_mb'] for r in good):.0f} | "
                + ", ".join(
                    f"{r['loadavg_before']:.1f}-{r['loadavg_after']:.1f}" for r in good
                )
                + " | "
                + ", ".join(f"{r.get('other_cores', math.nan):.2f}" for r in good)
                + " |"
            )
        lines.append("")
    return "\n".join(lines)


def markdown(report: dict) -> str:
    """Tables of a ``--step`` or a ``--full`` report."""
    return (
        markdown_full(report) if report.get("kind") == "full" else markdown_step(report)
    )


def machine_line(m: dict) -> str:
    code = m.get("code", {})
    return (
        f"Machine: {m['cpu']} ({m['cores_available']} cores, {m['memory_gb']} GB), "
        f"Python {m['python']}, numpy {m['numpy']}, scipy {m['scipy']}, clarabel "
        f"{m['clarabel']}, mkl {m.get('mkl')}; {m['date']}; code git "
        f"{code.get('git_head', '?')}, source hash {code.get('source_sha1', '?')}."
    )


# ---------------------------------------------------------------------------
# The tables of the docs pages, rendered from the committed JSON (--tables).

TABLES: docs_tables.Tables = {}
docs_table = docs_tables.registry(TABLES)


@docs_table(f"{docs_tables.RESULTS}/presets_step.json")
def presets_step() -> str:
    """One step with the high and fast presets against a tight (1e-10) solve."""
    out = []
    for c in docs_tables.load(f"{docs_tables.RESULTS}/presets_step.json")["cases"]:
        backend = c["reference"]["backend"]
        rows = {r["preset"]: r for r in c["rows"] if r["backend"] == backend}
        hi, fa = rows.get("high"), rows.get("fast")
        if not (hi and fa):
            continue

        def err(r: dict) -> str:
            if "du_rel" not in r:  # the solve failed; the report says why
                return f"failed ({r['status']})"
            du, sigma = r["du_rel"], r["sigma_rel"]
            return f"{docs_tables.sci(du, 1)} / {docs_tables.sci(sigma, 1)}"

        out.append(
            [
                suite.CASE_LABELS.get(c["case"], c["case"]),
                backend,
                err(hi),
                err(fa),
                f"{hi['iterations']} → {fa['iterations']}",
                " → ".join(docs_tables.sig(r.get("solve_s")) for r in (hi, fa)),
            ]
        )
    return docs_tables.md(
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


@docs_table(f"{docs_tables.RESULTS}/full_2k_cnr.json")
def full_runs() -> str:
    """Whole 2k collapse runs to rest with the MKL settings (presets.py)."""
    names = {
        "default": "MKL, defaults",
        "nocnr": "`reproducible=False`",
        "fast": "`accuracy=fast`",
        "fast-nocnr": "both",
    }
    out = []
    for r in docs_tables.load(f"{docs_tables.RESULTS}/full_2k_cnr.json")["runs"]:
        m = r["metrics"]
        out.append(
            [
                names.get(r["variant"], r["variant"]),
                "/".join(r["linear_solvers"]),
                docs_tables.count(r["n_particles"]),
                r["steps"],
                f"{r['wall_s']:.1f}",
                docs_tables.num(r.get("step_time_median", r["wall_s"] / r["steps"])),
                docs_tables.num(m.get("normalised_runout")),
                docs_tables.num(m.get("final_height")),
            ]
        )
    return docs_tables.md(
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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--step", help=f"cases for the one-step check: {list(STEP_CASES)}")
    ap.add_argument("--backends", default="qdldl,faer,mkl")
    ap.add_argument("--presets", default="high,fast")
    ap.add_argument(
        "--full", help="runs: collapse:<div>, footing:<spacing> (comma-separated)"
    )
    ap.add_argument(
        "--variants",
        default="default,fast",
        help="default, high, fast, or preset@backend (e.g. fast@mkl)",
    )
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=3600.0)
    ap.add_argument("--wait-load", type=float, default=0.0)
    ap.add_argument(
        "--wait-idle",
        type=float,
        default=0.0,
        help="wait until other processes use fewer cores than this (see suite.py)",
    )
    ap.add_argument("--wait-max", type=float, default=300.0)
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--name", default=None, help="output stem")
    ap.add_argument("--append", action="store_true")
    ap.add_argument("--render", metavar="FILE.json")
    ap.add_argument("--full-child", help=argparse.SUPPRESS)
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    args = ap.parse_args(argv)
    if args.tables:
        return docs_tables.write(TABLES)

    if args.full_child:
        run, variant = args.full_child.split("|")
        harness.emit_result(full_child(run, variant))
        return 0
    if args.render:
        return harness.render(args.render, markdown)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    machine = harness.machine_info()
    if args.step:
        path = out / f"{args.name or 'presets_step'}.json"
        rep = (
            json.loads(path.read_text())
            if args.append and path.exists()
            else {"kind": "step", "machine": machine, "cases": []}
        )
        rep["machine_line"] = machine_line(rep["machine"])
        for case in args.step.split(","):
            print(f"{case} ...", flush=True)
            res = step_accuracy(case, args.backends.split(","), args.presets.split(","))
            rep["cases"] = [c for c in rep["cases"] if c["case"] != case] + [res]
            harness.write_report(path, rep, markdown_step(rep))
        print(markdown_step(rep))
    if args.full:
        path = out / f"{args.name or 'presets_full'}.json"
        rep = (
            json.loads(path.read_text())
            if args.append and path.exists()
            else {"kind": "full", "machine": machine, "runs": []}
        )
        rep.setdefault("niceness", []).append(os.nice(0))
        rep["machine_line"] = machine_line(rep["machine"])
        variants = args.variants.split(",")
        for run in args.full.split(","):
            for k in range(args.repeat):
                order = variants if k % 2 == 0 else variants[::-1]
                for v in order:
                    print(
                        f"{run} {v} #{k + 1} (load {os.getloadavg()[0]:.2f}) ...",
                        end=" ",
                        flush=True,
                    )
                    res = run_full_subprocess(run, v, args)
                    res["repeat"] = k
                    rep["runs"].append(res)
                    if "metrics" in res:
                        m = res["metrics"]
                        print(
                            f"wall {res['wall_time_total']:.1f} s, steps "
                            f"{res['steps']}, it {res['ipm_iterations_total']}, "
                            + ", ".join(
                                f"{key}={m[key]:{f}}"
                                for key, f in FULL_KEYS[res["scene"]][:2]
                            ),
                            flush=True,
                        )
                    else:
                        print(res.get("note"), flush=True)
                    harness.write_report(path, rep, markdown_full(rep))
        print(markdown_full(rep))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
