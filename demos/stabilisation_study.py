#!/usr/bin/env python
"""Stress roughness, run-out, volume and cost against the stabilisation factor.

Measures what ``docs/validation/stabilisation.md`` (the page on stress
oscillation, the stabilisation and the volume correction) and
``docs/theory.md`` (section "Stabilisation") quote:

1. **Column collapse** (scene ``column-collapse``, a = 2, its default
   resolution, dt = 5 ms) from release to rest, for the node-mass rule and the
   factor ``beta`` of the element-residual stabilisation: ``particle`` masses
   without stabilisation (the library's former defaults), ``mesh`` masses with
   beta = 0, 3, 10, 30, 100.  Reported: the stress roughness ``R`` (the
   measure of ``skfem_npfem.baseline.roughness.stress_roughness``) after 20, 40,
   80, 160 steps, its maximum over the run and at rest, the normalised run-out,
   the final height, the volume change and the median time of a step.
2. **Remeshed elastic column at rest** (the same scene with c = 1 MPa: no
   yielding; remeshed every step for 1 s): ``R`` at the end and the creep
   (largest particle displacement and speed at the end; an exact solver would
   keep the body still after its elastic settlement of ~1e-5 m).
3. **Cost at ~4k particles** (spacing L0/48): the median time of a step with
   beta = 30 against beta = 0, stepped alternately in one process.

Writes ``docs/validation/stabilisation.json`` and the tables generated from it,
``docs/validation/stabilisation.inc`` (a fragment that
``docs/validation/stabilisation.md`` includes).  Usage (repository root)::

    python demos/stabilisation_study.py            # ~20 CPU-min
    python demos/stabilisation_study.py --quick    # reduced (tests)
    python demos/stabilisation_study.py --page     # fragment from the JSON only

The aspect-ratio sweep with the new defaults runs through the validation demo
and is condensed here (the committed ``collapse_validation.json`` holds the
sweep before the change)::

    python demos/collapse_validation.py --aspects 0.5,1,2,4,8 \
        --particles-across 12 --refinement "" --variants "" --out DIR
    python demos/stabilisation_study.py --sweep DIR   # adds it to the JSON
"""

from __future__ import annotations

import argparse
import json
import math
import runpy
import time
from pathlib import Path
from typing import Any

import numpy as np

from skfem_npfem.baseline.roughness import stress_roughness
from skfem_npfem.io import write_json
from skfem_npfem.scenes import get_scene
from skfem_npfem.sweeps import run_tasks

ROOT = Path(__file__).resolve().parent.parent
ROUGHNESS = "`stress_roughness` of `skfem_npfem/baseline/roughness.py`"
OUT = ROOT / "docs" / "validation" / "stabilisation.json"
BEFORE = ROOT / "docs" / "validation" / "collapse_validation.json"

#: Collapse cases: label -> scene parameters.
COLLAPSE = {
    "particle mass, beta=0": {"nodal_mass": "particle", "stabilisation": 0.0},
    "mesh mass, beta=0": {"nodal_mass": "mesh", "stabilisation": 0.0},
    "mesh mass, beta=3": {"nodal_mass": "mesh", "stabilisation": 3.0},
    "mesh mass, beta=10": {"nodal_mass": "mesh", "stabilisation": 10.0},
    "mesh mass, beta=30": {"nodal_mass": "mesh", "stabilisation": 30.0},
    "mesh mass, beta=100": {"nodal_mass": "mesh", "stabilisation": 100.0},
}
#: Elastic column at rest: the collapse scene with a cohesion it never reaches.
AT_REST = {"c": 1e6, "t_end": 1.0, "rest_fraction": 0.0}
REPORT_STEPS = (20, 40, 80, 160)


def one_run(params: dict[str, Any], steps: int | None = None) -> dict[str, Any]:
    """Run the collapse scene with ``params``; roughness, creep and metrics."""
    scene = get_scene("column-collapse")
    # Measured without the volume correction (the scene's default since; the
    # study is about the stresses): kappa = 0 unless params say otherwise.
    values = scene.resolve({"volume_correction": 0.0, **params, "threads": 1})
    run = scene.build(values, out=None, progress=False)
    sim = run.simulation
    x0 = sim.particles.x.copy()
    rough: list[tuple[int, float]] = []

    def record(sim_, p, res) -> bool:
        r = stress_roughness(res.cells, p.stress)
        rough.append((res.record.step, float(r)))
        return False

    sim.callbacks.append(record)
    kwargs = {"steps": steps} if steps else dict(run.run_kwargs)
    start = time.perf_counter()
    sim.run(**kwargs)
    wall = time.perf_counter() - start
    metrics = run.metrics(sim)
    p = sim.particles
    per_step = [sum(r.timings.values()) for r in sim.records]
    finite = [r for _, r in rough if math.isfinite(r)]
    return {
        "params": params,
        "steps": len(rough),
        "R_at": {s: r for s, r in rough if s in REPORT_STEPS},
        "R_final": rough[-1][1] if rough else None,
        "R_max": max(finite) if finite else None,
        "normalised_runout": metrics.get("normalised_runout"),
        "final_height": metrics.get("final_height"),
        "volume_change": metrics.get("volume_change"),
        "max_displacement": float(np.linalg.norm(p.x - x0, axis=1).max()),
        "max_speed_end": float(np.linalg.norm(p.v, axis=1).max()),
        "median_step_s": float(np.median(per_step)) if per_step else None,
        "wall_s": wall,
    }


def cost(spacing_divisor: int, steps: int) -> dict[str, Any]:
    """Median step time with beta = 30 and beta = 0, stepped alternately.

    The measurement is ``alternate`` of benchmarks/stabilisation_cost.py.
    """
    bench = runpy.run_path(str(ROOT / "benchmarks" / "stabilisation_cost.py"))
    params = {"spacing": 0.2 / spacing_divisor, "threads": 1}
    r = bench["alternate"](params, steps)
    med = r["median_step_s"]
    return {
        "particles": r["particles"],
        "steps": steps,
        "median_step_s": {"0.0": med["beta=0"], "30.0": med["beta=30"]},
        "ratio": r["ratio"],
    }


def _f(v: Any, fmt: str) -> str:
    return (
        "–"
        if v is None or (isinstance(v, float) and not math.isfinite(v))
        else (format(v, fmt))
    )


def page(result: dict[str, Any]) -> str:
    """The Markdown tables of a study result (a fragment of a page, generated)."""
    lines = [
        "<!-- Generated by demos/stabilisation_study.py from stabilisation.json;",
        "do not edit by hand: rerun the script (--page) instead. -->",
        "",
        "`R`: the stress roughness of sigma_v over interior particles",
        f"({ROUGHNESS}).  Column collapse a = 2 at the scene's default resolution,",
        "dt = 5 ms, to rest.",
        "",
        "**Column collapse**",
        "",
        "| case | R @20 | R @40 | R @80 | R @160 | R max | R at rest | run-out "
        "(L-L0)/L0 | H/L0 | volume | steps | s/step |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for label, r in result["collapse"].items():
        if "error" in r:
            lines.append(f"| {label} | failed: {r['error']} |" + " |" * 10)
            continue
        at = {int(k): v for k, v in r["R_at"].items()}
        cells = [_f(at.get(s), ".3f") for s in REPORT_STEPS]
        lines.append(
            f"| {label} | " + " | ".join(cells) + f" | {_f(r['R_max'], '.3f')} | "
            f"{_f(r['R_final'], '.3f')} | {_f(r['normalised_runout'], '.2f')} | "
            f"{_f(r['final_height'], '.2f')} | {_f(r['volume_change'], '+.1%')} | "
            f"{r['steps']} | {_f(r['median_step_s'], '.2f')} |"
        )
    lines += [
        "",
        "**Elastic column at rest, remeshed every step**",
        "",
        "The collapse scene with c = 1 MPa (never yields), 1 s.  An exact solver keeps",
        "the body still after its elastic settlement (~1e-5 m).",
        "",
        "| case | R at the end | R max | largest displacement (m) | "
        "largest speed at the end (m/s) |",
        "|---|---|---|---|---|",
    ]
    for label, r in result["at_rest"].items():
        if "error" in r:
            lines.append(f"| {label} | failed: {r['error']} | | | |")
            continue
        lines.append(
            f"| {label} | {_f(r['R_final'], '.4f')} | {_f(r['R_max'], '.4f')} | "
            f"{_f(r['max_displacement'], '.2e')} | {_f(r['max_speed_end'], '.2e')} |"
        )
    if result.get("sweep"):
        lines += [
            "",
            "**Aspect-ratio sweep (12 particles across L0)**",
            "",
            "After: the current defaults (mesh masses, beta = 30).  Before: the",
            "committed validation sweep (particle masses, no stabilisation), which",
            "did not record R.",
            "",
            "| a | particles | R max | R at rest | run-out after | run-out before | "
            "H/L0 after | H/L0 before | volume after | volume before |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in result["sweep"]:
            b = r["before"]
            lines.append(
                f"| {r['aspect']:g} | {r['particles']} | {_f(r['R_max'], '.3f')} | "
                f"{_f(r['R_final'], '.3f')} | {_f(r['normalised_runout'], '.2f')} | "
                f"{_f(b['normalised_runout'], '.2f')} | "
                f"{_f(r['final_height'], '.2f')} | {_f(b['final_height_L0'], '.2f')} | "
                f"{_f(r['volume_change'], '+.1%')} | {_f(b['volume_change'], '+.1%')} |"
            )
    c = result["cost"]
    med = c["median_step_s"]
    lines += [
        "",
        "**Cost of a step**",
        "",
        f"{c['particles']} particles, {c['steps']} steps of each variant stepped",
        "alternately in one process: median step "
        f"{_f(med['0.0'], '.2f')} s with beta = 0, {_f(med['30.0'], '.2f')} s with "
        f"beta = 30: ratio **{c['ratio']:.2f}**.  {result.get('machine_note', '')}.",
        "",
    ]
    return "\n".join(lines)


def condense_sweep(folder: Path) -> list[dict[str, Any]]:
    """Per aspect ratio: the validation demo's cases in ``folder`` against before.

    ``before`` is the primary sweep of the committed ``collapse_validation.json``
    (made with the former defaults: particle masses, no stabilisation).
    """
    before = {}
    if BEFORE.exists():
        for row in json.loads(BEFORE.read_text())["sweep"]:
            if row.get("variant") is None:
                before[(row["aspect"], row["N"])] = row
    rows = []
    for path in sorted(Path(folder, "cases").glob("a*_N*.json")):
        case = json.loads(path.read_text())
        m, par = case["metrics"], case["parameters"]
        a = float(par["aspect"])
        n = round(0.2 / float(par["spacing"])) if par.get("spacing") else None
        old = before.get((a, n), {})
        rows.append(
            {
                "aspect": a,
                "N": n,
                "particles": m["n_particles"],
                "steps": case["solver"]["steps"],
                "R_max": m["stress_roughness_max"],
                "R_final": m["stress_roughness"],
                "normalised_runout": m["normalised_runout"],
                "final_height": m["final_height"],
                "volume_change": m["volume_change"],
                "at_rest": m["at_rest"],
                "before": {
                    k: old.get(k)
                    for k in ("normalised_runout", "final_height_L0", "volume_change")
                },
            }
        )
    return sorted(rows, key=lambda r: r["aspect"])


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run the study and write the JSON (returned)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="reduced runs (tests)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--page", action="store_true", help="only the page from the JSON")
    ap.add_argument("--sweep", type=Path, help="add a validation-demo sweep folder")
    args = ap.parse_args(argv)
    if args.page or args.sweep:
        result = json.loads(args.out.read_text())
        if args.sweep:
            result["sweep"] = condense_sweep(args.sweep)
            write_json(args.out, result)
        args.out.with_suffix(".inc").write_text(page(result))
        return result
    steps = 20 if args.quick else None
    tasks: dict[str, tuple] = {}
    for label, params in COLLAPSE.items():
        extra = {"spacing": 0.05} if args.quick else {}
        tasks[f"collapse: {label}"] = ({**params, **extra}, steps)
    for label in ("particle mass, beta=0", "mesh mass, beta=0", "mesh mass, beta=30"):
        extra = {"spacing": 0.05, "t_end": 0.1} if args.quick else {}
        tasks[f"at rest: {label}"] = ({**COLLAPSE[label], **AT_REST, **extra}, None)
    outcomes = run_tasks(one_run, tasks, workers=args.workers)
    result: dict[str, Any] = {"collapse": {}, "at_rest": {}}
    for name, out in outcomes.items():
        group, label = name.split(": ", 1)
        key = "collapse" if group == "collapse" else "at_rest"
        result[key][label] = out.value if out.ok else {"error": out.error}
    result["cost"] = cost(12, 3) if args.quick else cost(48, 10)
    result["machine_note"] = "2 cores, shared with other jobs: times are indicative"
    write_json(args.out, result)
    args.out.with_suffix(".inc").write_text(page(result))
    print(page(result))
    return result


if __name__ == "__main__":
    main()
