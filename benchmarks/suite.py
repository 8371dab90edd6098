#!/usr/bin/env python
"""Benchmark suite: time per N-PFEM step per case, linear-solver backend and preset.

Cases (``--cases``; see ``benchmarks/README.md``):

* ``collapse-1k``, ``collapse-4k``, ``collapse-16k`` (``collapse-2k`` optional):
  steps of the ``column-collapse`` scene (a = 2, spacing L0/22, L0/44, L0/89,
  L0/31), remeshed every step;
* ``block3d-3k``, ``block3d-11k`` (``block3d-10k`` optional): the gravity-loaded
  Drucker-Prager block of ``step_time.py`` (open variant) in 3D at 3 312,
  10 692 (9 537) nodes;
* ``footing-1.6k``, ``footing-4.8k``: the ``strip-footing`` scene at spacing
  0.0625 and 0.03125 (all 8 settlement steps; q_ult is recorded).

Every (case, backend, preset) runs in its own subprocess (this script called
with ``--child``): the first step is a warm-up and is not timed (scene build,
first factorisation symbolic work, imports), then ``steps`` steps are timed one
``Simulation.run(steps=1)`` at a time.  With ``--repeat N`` every combination is
run N times, interleaved (round robin, rotated order) so that ratios between
backends and presets come from the same stretch of machine load.

Usage::

    PYTHONPATH=. python benchmarks/suite.py                          # default cases
    PYTHONPATH=. python benchmarks/suite.py --cases collapse-4k --backends qdldl,mkl
    PYTHONPATH=. python benchmarks/suite.py --compare A.json B.json
    PYTHONPATH=. python benchmarks/suite.py --render results/suite.json

Writes ``<out>/suite.json`` and ``<out>/suite.md`` (default ``benchmarks/results``).
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
import _tables as docs_tables
import step_time as st

# --------------------------------------------------------------------------------
# Cases
# --------------------------------------------------------------------------------
#: kind "collapse": column-collapse scene, spacing = L0 / div (a = 2, L0 = 0.2 m).
#: kind "block3d": step_time.py's open DP block in 3D with nx x ny x nz elements.
#: kind "footing": strip-footing scene with the given spacing (8 steps in all).
#: kind "cylinder3d": 3D PFEM collapse of a quarter cylinder (R = 0.2 m, a = 2,
#: cubic lattice with ``nr`` spacings over R, symmetry walls x = 0 and y = 0,
#: cohesionless Drucker-Prager, Δt = 2 ms, remeshed every step): the geometry of
#: the 3D reference timings (docs/performance.md, "Reference timings").
#: ``steps``: timed steps after the untimed warm-up step.
CASES: dict[str, dict] = {
    "collapse-1k": {"kind": "collapse", "div": 22, "steps": 5},
    "collapse-2k": {"kind": "collapse", "div": 31, "steps": 5},
    "collapse-4k": {"kind": "collapse", "div": 44, "steps": 5},
    "collapse-16k": {"kind": "collapse", "div": 89, "steps": 5},
    "block3d-3k": {"kind": "block3d", "n": (22, 11, 11), "steps": 3},
    "block3d-10k": {"kind": "block3d", "n": (32, 16, 16), "steps": 3},
    "block3d-11k": {"kind": "block3d", "n": (32, 17, 17), "steps": 3},
    "cylinder3d-4k": {"kind": "cylinder3d", "nr": 13, "steps": 3},
    "cylinder3d-10k": {"kind": "cylinder3d", "nr": 18, "steps": 2},
    "footing-1.6k": {"kind": "footing", "spacing": 0.0625, "steps": 7},
    "footing-4.8k": {"kind": "footing", "spacing": 0.03125, "steps": 7},
}
DEFAULT_CASES = (
    "collapse-1k",
    "collapse-4k",
    "collapse-16k",
    "block3d-3k",
    "block3d-11k",
    "footing-1.6k",
    "footing-4.8k",
)
BACKENDS = ("qdldl", "faer", "mkl")
PRESETS = ("high", "fast")
#: Solver variants: the two presets of SolverOptions plus diagnostic
#: combinations that separate the tolerance from the iterative refinement
#: (``fast-noref`` is the ``fast`` preset as it first was: it also turned the
#: refinement off for qdldl and faer).
PRESET_SPECS = {
    "high": {"accuracy": "high"},
    "fast": {"accuracy": "fast"},
    "fast+ref": {"tol": 1e-6, "iterative_refinement": True},
    "high-noref": {"tol": 1e-8, "iterative_refinement": False},
    "fast-noref": {"tol": 1e-6, "iterative_refinement": False},
    "high-nocnr": {"accuracy": "high", "reproducible": False},
    "fast-nocnr": {"accuracy": "fast", "reproducible": False},
}
#: Combinations skipped by default, with the reason (printed in the notes).
HOPELESS = {
    ("block3d-10k", "qdldl"): "qdldl on 3D at ~10k nodes: a one-step probe of "
    "step_time.py 3d-10k had not finished after 8.5 min (qdldl is ~5-9x slower "
    "per IPM iteration than faer on 3D programs)",
    ("block3d-11k", "qdldl"): "as block3d-10k / qdldl (larger still)",
    ("cylinder3d-4k", "qdldl"): "qdldl is 5-9x slower than faer on 3D programs",
    ("cylinder3d-10k", "qdldl"): "as block3d-10k / qdldl",
}
#: Reference timings of a straightforward implementation on a 2-core machine,
#: s per step (docs/performance.md, "Reference timings").
#: (3D: a quarter cylinder of 3.4k / 10.7k nodes, not the block; indicative.)
REFERENCE = {
    "collapse-1k": {"qdldl": 0.2},
    "collapse-4k": {"qdldl": 2.1, "mkl": 1.3},
    "collapse-16k": {"faer": 17.0, "mkl": 8.2},
    "block3d-3k": {"faer": 21.0, "mkl": 9.4},
    "block3d-11k": {"mkl": 75.0},
    # The reference's own geometry, at 3.9k / 10.0k particles instead of 3.4k / 10.7k.
    "cylinder3d-4k": {"faer": 21.0, "mkl": 9.4},
    "cylinder3d-10k": {"mkl": 75.0},
}
#: Targets, s per step (best backend).
TARGET = {
    "collapse-4k": 1.4,
    "collapse-16k": 9.0,
    "block3d-3k": 9.0,
    "block3d-11k": 75,
    "cylinder3d-4k": 9.0,
    "cylinder3d-10k": 75,
}
PHASES = ("mesh", "assembly", "setup", "solve", "update", "output", "other")
L0 = 0.2
#: A step is "clean" when other processes used fewer cores than this meanwhile.
CLEAN_OTHERS = 0.25


def case_size(name: str) -> int:
    """Particles / nodes of a case (without building it)."""
    c = CASES[name]
    if c["kind"] == "collapse":
        return (c["div"] + 1) * (2 * c["div"] + 1)
    if c["kind"] == "block3d":
        nx, ny, nz = c["n"]
        return (nx + 1) * (ny + 1) * (nz + 1)
    if c["kind"] == "cylinder3d":
        return cylinder_lattice(c["nr"])[0].shape[0]
    from skfem_npfem.scenes.footing.strip import graded_coordinates

    return len(graded_coordinates(1.0, c["spacing"], 5.0, 1.15)) ** 2


# --------------------------------------------------------------------------------
# Child: build a case and time its steps
# --------------------------------------------------------------------------------
def solver_options(backend: str, preset: str, threads: int = 0):
    """SolverOptions of a backend and a variant of PRESET_SPECS."""
    from skfem_npfem import SolverOptions

    return SolverOptions(
        linear_solver=backend, max_threads=threads, **PRESET_SPECS[preset]
    )


def build_block3d(n: tuple[int, int, int], backend: str, preset: str, threads: int):
    """Simulation of step_time.py's open 3D Drucker-Prager block (nx x ny x nz)."""
    import numpy as np
    from skfem import MeshTet

    from skfem_npfem import FixedMesh, Model, Simulation
    from skfem_npfem.materials import DruckerPrager
    from skfem_npfem.mesh.smoothing import nodal_integration
    from skfem_npfem.particles import Particles

    nx, ny, nz = n
    W, D, H = st.WIDTH, st.DEPTH, st.HEIGHT
    mesh = MeshTet.init_tensor(
        np.linspace(0, W, nx + 1), np.linspace(0, D, ny + 1), np.linspace(0, H, nz + 1)
    )
    mat = DruckerPrager(
        st.E, st.NU, st.RHO, c=st.COHESION, phi=st.PHI, psi=st.PSI, match="compression"
    )
    x = mesh.p.T.copy()
    vol = nodal_integration(mesh).volumes
    sv = -st.RHO * st.GRAV * (H - x[:, -1])
    stress = np.zeros((x.shape[0], 6))
    stress[:, :3] = st.K0 * sv[:, None]
    stress[:, 2] = sv
    fixed = np.zeros((x.shape[0], 3), bool)
    fixed[np.isclose(x[:, 2], 0.0)] = True
    for k, ext in ((0, W), (1, D)):
        fixed[np.isclose(x[:, k], 0.0) | np.isclose(x[:, k], ext), k] = True
    # Open variant: the face x = W is free (the block starts to collapse).
    fixed[np.isclose(x[:, 0], W) & ~np.isclose(x[:, 2], 0.0), 0] = False
    particles = Particles.create(x, st.RHO * vol, stress=stress, fixed=fixed)
    model = Model(
        dim=3,
        materials=[mat],
        gravity=st.GRAV,
        mode="dynamic",
        theta1=1.0,
        theta2=1.0,
        solver=solver_options(backend, preset, threads),
    )
    return Simulation(particles, model, FixedMesh(mesh.t), st.DT)


CYL_RADIUS, CYL_ASPECT = 0.2, 2.0


def cylinder_lattice(nr: int):
    """Cubic lattice (spacing R / nr) inside the quarter cylinder; (x, h)."""
    import numpy as np

    h = CYL_RADIUS / nr
    g = np.arange(nr + 1) * h
    gz = np.arange(round(CYL_ASPECT * CYL_RADIUS / h) + 1) * h
    x = np.stack(np.meshgrid(g, g, gz, indexing="ij"), axis=-1).reshape(-1, 3)
    return x[x[:, 0] ** 2 + x[:, 1] ** 2 <= CYL_RADIUS**2 * (1 + 1e-9)], h


def build_cylinder3d(nr: int, backend: str, preset: str, threads: int):
    """Simulation of the quarter-cylinder collapse (see CASES)."""
    import numpy as np

    from skfem_npfem import Model, Simulation
    from skfem_npfem.boundary import RigidWall, floor
    from skfem_npfem.materials import DruckerPrager
    from skfem_npfem.mesh.smoothing import nodal_integration
    from skfem_npfem.mesh.sources import AlphaShapeMesher
    from skfem_npfem.particles import Particles

    x, h = cylinder_lattice(nr)
    height = CYL_ASPECT * CYL_RADIUS
    rho, g, phi, k0 = 1800.0, 9.81, 30.0, 0.5
    walls = [
        floor(3, phi),
        RigidWall([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.0, "x=0"),
        RigidWall([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.0, "y=0"),
    ]
    mesher = AlphaShapeMesher(h, 1.3, walls=walls)
    active, _ = mesher(x)
    vol = np.zeros(x.shape[0])
    vol[active] = nodal_integration(mesher.last.mesh()).volumes
    stress = np.zeros((x.shape[0], 6))
    stress[:, 2] = -rho * g * (height - x[:, 2])
    stress[:, 0] = stress[:, 1] = k0 * stress[:, 2]
    particles = Particles.create(x, rho * vol, stress=stress, n_walls=len(walls))
    mat = DruckerPrager(
        10e6,
        0.3,
        rho,
        c=0.0,
        phi=phi,
        psi=0.0,
        match="compression",
        tension_cutoff=True,
    )
    model = Model(
        dim=3,
        materials=[mat],
        gravity=g,
        mode="dynamic",
        theta1=1.0,
        theta2=1.0,
        walls=walls,
        solver=solver_options(backend, preset, threads),
    )
    return Simulation(particles, model, mesher, 2e-3)


def build(case: str, backend: str, preset: str, threads: int):
    """(simulation, metrics function or None) of a case."""
    c = CASES[case]
    if c["kind"] == "block3d":
        return build_block3d(c["n"], backend, preset, threads), None
    if c["kind"] == "cylinder3d":
        return build_cylinder3d(c["nr"], backend, preset, threads), None
    from skfem_npfem.scenes import get_scene

    scene_preset = preset if preset in ("high", "fast") else "high"
    common = {"linear_solver": backend, "accuracy": scene_preset, "threads": threads}
    if c["kind"] == "collapse":
        scene = get_scene("column-collapse")
        values = scene.resolve({"spacing": L0 / c["div"], "t_end": 10.0, **common})
    else:
        scene = get_scene("strip-footing")
        values = scene.resolve({"spacing": c["spacing"], **common})
    srun = scene.build(values, out=None, progress=False)
    if preset != scene_preset:
        srun.simulation.model.solver = solver_options(backend, preset, threads)
    return srun.simulation, srun.metrics


def run_child(case: str, backend: str, preset: str, threads: int, steps: int) -> dict:
    """Warm-up step, then ``steps`` timed steps; a JSON-able record."""
    t0 = time.perf_counter()
    import numpy as np

    from skfem_npfem.errors import SolverError

    t_import = time.perf_counter() - t0
    t0 = time.perf_counter()
    sim, metrics = build(case, backend, preset, threads)
    t_build = time.perf_counter() - t0
    # The program sizes of each step reach the callbacks (records keep scalars).
    sizes_of_step: dict = {}
    sim.callbacks.append(lambda s, p, step: sizes_of_step.update(step.solution.sizes))
    out = {
        "case": case,
        "kind": CASES[case]["kind"],
        "backend": backend,
        "preset": preset,
        "threads": threads,
        "particles": int(sim.particles.n),
        "import_s": t_import,
        "build_s": t_build,
        "source_sha1": harness.source_hash(),
        "steps": [],
        "note": "",
    }
    for k in range(steps + 1):
        try:
            with harness.Meter() as meter:
                sim.run(steps=1)
        except SolverError as err:
            out["note"] = f"solver failed at step {k + 1}: {err}"
            break
        wall = meter.wall
        rec = sim.records[-1]
        if k == 0:
            out["warmup_s"] = wall
            out["warmup_iterations"] = int(rec.iterations)
            continue
        phases = {ph: float(rec.timings.get(ph, 0.0)) for ph in PHASES[:-1]}
        phases["other"] = max(wall - sum(phases.values()), 0.0)
        sizes = dict(sizes_of_step)
        out["steps"].append(
            {
                "step": rec.step,
                "dt": rec.dt,
                "status": rec.status,
                "iterations": int(rec.iterations),
                "retries": int(rec.retries),
                "phases": phases,
                "wall": wall,
                "cpu": meter.cpu,
                "loadavg_1min": meter.load_before,
                # Cores used by other processes during the step (/proc/stat).
                "other_cores": meter.others,
                "variables": int(sizes["variables"]),
                "rows": int(sizes["rows"]),
                "nnz_A": int(sizes["nnz_A"]),
                "linear_solver": sizes.get("linear_solver", backend),
                "n_active": int(rec.n_active),
                "peak_rss_mb": harness.peak_rss_mb(),
            }
        )
    out["peak_rss_mb"] = harness.peak_rss_mb()
    if metrics is not None and not out["note"]:
        if CASES[case]["kind"] == "footing":
            sim.run(steps=max(0, 8 - sim.step))  # all settlement steps
            m = metrics(sim)
            out["metrics"] = {
                "q_ult": m["q_ult"],
                "bearing_factor": m["bearing_factor"],
                "relative_error": m["relative_error"],
            }
    out["final_max_speed"] = float(np.max(np.linalg.norm(sim.particles.v, axis=1)))
    return out


# --------------------------------------------------------------------------------
# Parent
# --------------------------------------------------------------------------------
def run_subprocess(case, backend, preset, args, repeat: int) -> dict:
    """One (case, backend, preset) run in a fresh interpreter."""
    waited_load = None
    t_wait = time.monotonic()
    if args.wait_load > 0:
        waited_load = harness.wait_for_quiet(args.wait_load, args.wait_max)
    idle = None
    if args.wait_idle > 0:
        idle = harness.wait_for_idle(args.wait_idle, args.wait_max)
    waited = time.monotonic() - t_wait
    steps = args.steps or CASES[case]["steps"]
    child_args = [
        "--child",
        f"{case}:{backend}:{preset}",
        "--threads",
        str(args.threads),
        "--steps",
        str(steps),
    ]
    timeout = (steps + 3) * args.step_limit + 300.0
    base = {"case": case, "backend": backend, "preset": preset, "repeat": repeat}
    load0 = os.getloadavg()[0]
    res, note, wall, _ = harness.run_child(
        Path(__file__).resolve(), child_args, timeout, failed="subprocess failed"
    )
    if res is None:
        return {**base, "steps": [], "note": note}
    res.update(base)
    res["subprocess_s"] = wall
    res["loadavg_before"] = load0
    res["waited_s"] = waited
    res["waited_to_load"] = waited_load
    res["idle_before"] = idle
    return res


def summarise(runs: list[dict]) -> dict:
    """Pool the timed steps of the repeats of one (case, backend, preset)."""
    steps_all = [s for r in runs for s in r.get("steps", []) if "phases" in s]
    if not steps_all:
        return {}
    clean = [s for s in steps_all if s.get("other_cores", 0.0) < CLEAN_OTHERS]
    # Clean steps only when there are enough of them (else all, flagged).
    steps = clean if len(clean) >= max(2, len(steps_all) // 3) else steps_all
    runs = [{**r, "steps": [s for s in r.get("steps", []) if s in steps]} for r in runs]
    walls = [s["wall"] for s in steps]
    phase_sum = {ph: sum(s["phases"][ph] for s in steps) for ph in PHASES}
    tot = sum(phase_sum.values()) or 1.0
    per_run = [
        statistics.median(s["wall"] for s in r["steps"]) for r in runs if r["steps"]
    ]
    solver_pct = 100.0 * (phase_sum["setup"] + phase_sum["solve"]) / tot
    its = [s["iterations"] for s in steps]
    metrics = [r["metrics"] for r in runs if r.get("metrics")]
    return {
        "median_s": statistics.median(walls),
        "min_s": min(walls),
        "per_run_median_s": per_run,
        "median_cpu_s": statistics.median(s["cpu"] for s in steps),
        "median_phase_s": {
            ph: statistics.median(s["phases"][ph] for s in steps) for ph in PHASES
        },
        "split_pct": {ph: 100.0 * v / tot for ph, v in phase_sum.items()},
        "solver_pct": solver_pct,
        "non_solver_pct": 100.0 - solver_pct,
        "iterations": its,
        "iterations_mean": statistics.fmean(its),
        "s_per_iteration": statistics.median(
            s["phases"]["solve"] / max(s["iterations"], 1) for s in steps
        ),
        "statuses": sorted({s["status"] for s in steps}),
        "linear_solvers": sorted({s["linear_solver"] for s in steps}),
        "variables": statistics.median(s["variables"] for s in steps),
        "particles": runs[0].get("particles"),
        "peak_rss_mb": max(r.get("peak_rss_mb", 0.0) for r in runs),
        "max_loadavg": max(s["loadavg_1min"] for s in steps),
        "min_loadavg": min(s["loadavg_1min"] for s in steps),
        "repeats": len(per_run),
        "steps_used": len(steps),
        "steps_total": len(steps_all),
        "steps_clean": len(clean),
        "only_clean": steps is clean,
        "other_cores_median": statistics.median(
            s.get("other_cores", math.nan) for s in steps
        ),
        "metrics": metrics[0] if metrics else None,
        "metrics_all": metrics,
    }


def fmt_s(x: float) -> str:
    return harness.fmt_s(x) if x == x else "—"


def fmt_ratio(x: float) -> str:
    """A ratio to 2 decimals, "—" when it is undefined (NaN)."""
    return f"{x:.2f}" if x == x else "—"


def _index(report: dict) -> dict:
    """(case, backend, preset) -> list of runs."""
    idx: dict[tuple, list] = {}
    for r in report["runs"]:
        # Runs with an explicit thread count (--threads N) are kept apart.
        t = r.get("threads") or 0
        backend = r["backend"] + (f" ({t} thr.)" if t else "")
        idx.setdefault((r["case"], backend, r["preset"]), []).append(r)
    return idx


def summaries(report: dict) -> dict:
    return {k: summarise(v) for k, v in _index(report).items()}


def markdown(report: dict) -> str:
    """Tables of a suite report."""
    m = report["machine"]
    sm = summaries(report)
    lines = [
        "# N-PFEM benchmark suite",
        "",
        f"Machine: {m['cpu']} ({m['cores_available']} of {m['cores']} cores, "
        f"{m['memory_gb']} GB), Python {m['python']}, numpy {m['numpy']}, scipy "
        f"{m['scipy']}, clarabel {m['clarabel']}, mkl {m.get('mkl', '?')}, "
        f"scikit-fem {m['scikit-fem']}; {m['date']}.  "
        + harness.code_line(m.get("code", {})),
        "",
        f"Settings: {json.dumps(report['settings'])}",
        "",
        "`s/step`: median wall time of the timed steps (warm-up step excluded) "
        "pooled over the repeats; `runs`: median of each repeat; `cpu`: median "
        "process CPU time per step (all threads); `solver %`: Clarabel setup + "
        "solve share of the summed step time, `non-solver %` the rest (remeshing "
        "and smoothing cells, assembly, particle update, callbacks); `load`: 1-min "
        "load average before the steps (min-max).  `others`: median number of "
        "cores used by other processes during a timed step (from /proc/stat minus "
        "our CPU time); a step is clean when others < 0.25, and only clean steps "
        "enter the statistics when at least max(2, 1/3) of them are clean (`clean "
        "steps`; otherwise all steps are used and the row is contaminated by "
        "other jobs on this 2-core machine).  `ref`: reference time of a "
        "straightforward implementation with the same backend (3D: a quarter cylinder, "
        "indicative); `ratio` = s/step / ref.",
        "",
        "| case | particles | variables | backend | preset | s/step | runs | cpu s "
        "| IPM it. | s/iter | solver % | non-solver % | peak MB | clean steps | others "
        "| load | ref | ratio |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (case, backend, preset), s in sm.items():
        if not s:
            note = "; ".join(
                r.get("note", "") for r in _index(report)[(case, backend, preset)]
            )
            lines.append(
                f"| {case} | | | {backend} | {preset} | — ({note[:60]}) |" + " |" * 10
            )
            continue
        ref = REFERENCE.get(case, {}).get(backend) if " " not in backend else None
        used = "/".join(s["linear_solvers"])
        bname = backend if used == backend.split()[0] else f"{backend}→{used}"
        lines.append(
            f"| {case} | {s['particles']} | {s['variables']:.0f} | {bname} | {preset} "
            f"| {fmt_s(s['median_s'])} | "
            + ", ".join(fmt_s(x) for x in s["per_run_median_s"])
            + f" | {fmt_s(s['median_cpu_s'])} | {s['iterations_mean']:.1f} | "
            f"{fmt_s(s['s_per_iteration'])} | {s['solver_pct']:.1f} | "
            f"{s['non_solver_pct']:.1f} | {s['peak_rss_mb']:.0f} | "
            f"{s['steps_clean']}/{s['steps_total']}"
            + ("" if s["only_clean"] else " (all used)")
            + f" | {s['other_cores_median']:.2f} | "
            f"{s['min_loadavg']:.1f}-{s['max_loadavg']:.1f} | "
            + (f"{ref:g} | {s['median_s'] / ref:.2f} |" if ref else "— | — |")
        )
    # Best backend per case and preset, fast/high ratios.
    lines += [
        "",
        "## Best backend per case",
        "",
        "Ratios are of medians measured in the same (interleaved) run.  `fast/high`: "
        "s/step and IPM iterations of the fast preset over the high preset, same "
        "backend.",
        "",
        "| case | particles | best (high) | s/step | 2nd (high) | s/step | best/2nd "
        "| best (fast) | s/step | fast/high time (best) | fast/high iterations "
        "| target | met |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    cases = list(dict.fromkeys(k[0] for k in sm))
    for case in cases:
        row = {}
        for preset in PRESETS:
            cand = sorted(
                (s["median_s"], b)
                for (c, b, p), s in sm.items()
                if c == case and p == preset and s and b != "auto"
            )
            row[preset] = cand
        hi, fa = row.get("high", []), row.get("fast", [])
        if not hi:
            continue
        b1 = hi[0]
        b2 = hi[1] if len(hi) > 1 else (math.nan, "—")
        s_hi = sm[(case, b1[1], "high")]
        s_fa = sm.get((case, b1[1], "fast")) or {}
        tfh = s_fa["median_s"] / s_hi["median_s"] if s_fa else math.nan
        ifh = s_fa["iterations_mean"] / s_hi["iterations_mean"] if s_fa else math.nan
        tgt = TARGET.get(case)
        best = min(b1[0], fa[0][0] if fa else math.inf)
        lines.append(
            f"| {case} | {s_hi['particles']} | {b1[1]} | {fmt_s(b1[0])} | {b2[1]} | "
            f"{fmt_s(b2[0])} | {fmt_ratio(b1[0] / b2[0])} | "
            + (f"{fa[0][1]} | {fmt_s(fa[0][0])} | " if fa else "— | — | ")
            + f"{fmt_ratio(tfh)} | {fmt_ratio(ifh)} | "
            + (f"≤ {tgt:g} | {'yes' if best <= tgt else 'no'} |" if tgt else "— | — |")
        )
    # Footing q_ult per backend / preset.
    foot = [(k, s) for k, s in sm.items() if s and s.get("metrics")]
    if foot:
        lines += [
            "",
            "## Strip footing: q_ult per backend and preset",
            "",
            "| case | backend | preset | q_ult (Pa) | N_c = q/c | error vs 2+pi "
            "| vs high (same backend) |",
            "|---|---|---|---|---|---|---|",
        ]
        for (case, backend, preset), s in foot:
            q = s["metrics"]["q_ult"]
            hi = sm.get((case, backend, "high")) or {}
            qh = (hi.get("metrics") or {}).get("q_ult")
            rel = f"{q / qh - 1:+.2e}" if qh else "—"
            lines.append(
                f"| {case} | {backend} | {preset} | {q:.6g} | "
                f"{s['metrics']['bearing_factor']:.5f} | "
                f"{s['metrics']['relative_error']:+.4f} | {rel} |"
            )
    notes = [
        f"* {r['case']} / {r['backend']} / {r['preset']}: {r['note']}"
        for r in report["runs"]
        if r.get("note")
    ]
    hashes = harness.runs_by_hash(report["runs"], lambda r: r["case"])
    if len(hashes) > 1:
        notes.append(
            f"* **warning**: the library sources changed during the sweep "
            f"(hashes {', '.join(sorted(hashes))}); runs are not strictly comparable"
        )
    return harness.finish_markdown(lines, notes)


def compare(path_a: str, path_b: str) -> str:
    """Before/after table of two suite reports (B/A ratios)."""
    a, b, rows = harness.load_pair(path_a, path_b)
    sa, sb = summaries(a), summaries(b)
    keys = [k for k in sa if k in sb] + [k for k in sb if k not in sa]
    rows += [
        "| case | backend | preset | A s/step | B s/step | B/A | A solve | B solve "
        "| B/A solve | A non-solver | B non-solver | A it. | B it. | A load | B load |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    for key in keys:
        x, y = sa.get(key) or {}, sb.get(key) or {}
        if not x or not y:
            rows.append(f"| {' | '.join(key)} |" + " |" * 12)
            continue
        xs, ys = x["median_phase_s"]["solve"], y["median_phase_s"]["solve"]
        xn = harness.non_solver_s(x["median_phase_s"])
        yn = harness.non_solver_s(y["median_phase_s"])
        rows.append(
            f"| {' | '.join(key)} | {fmt_s(x['median_s'])} | {fmt_s(y['median_s'])} "
            f"| {y['median_s'] / x['median_s']:.2f} | {fmt_s(xs)} | {fmt_s(ys)} | "
            f"{ys / xs:.2f} | {fmt_s(xn)} | {fmt_s(yn)} | "
            f"{x['iterations_mean']:.1f} | {y['iterations_mean']:.1f} | "
            f"{x['max_loadavg']:.1f} | {y['max_loadavg']:.1f} |"
        )
    return "\n".join(rows)


# ---------------------------------------------------------------------------
# The tables of the docs pages, rendered from the committed JSON (--tables).

TABLES: docs_tables.Tables = {}
docs_table = docs_tables.registry(TABLES)


def _suite_summaries(name: str) -> dict:
    """Per (case, backend, preset) statistics of a suite report (suite.py's own)."""
    return summaries(docs_tables.load(f"{docs_tables.RESULTS}/{name}.json"))


def _s(summary: dict | None) -> str:
    return docs_tables.sig(summary["median_s"]) if summary else "—"


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
        report = docs_tables.load(f"{docs_tables.RESULTS}/{name}.json")
        date = report["machine"]["date"]
        for key, sm in _suite_summaries(name).items():
            if not sm:
                continue
            clean = bool(sm["only_clean"] and sm["steps_clean"] >= 2)
            rank = (clean, date)
            if key not in best or rank > best[key][0]:
                best[key] = (rank, {**sm, "report": name})
    return {k: v for k, (_, v) in best.items()}


@docs_table(*(f"{docs_tables.RESULTS}/{n}.json" for n in SUITE_REPORTS))
def time_per_step() -> str:
    """Seconds per step per case and backend, pooled over the suite reports."""
    pool = _pooled()
    cases = [c for c in CASES if any(k[0] == c for k in pool)]
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
        ref = REFERENCE.get(case, {})
        target = TARGET.get(case)
        best_s = high[winner]["median_s"]
        out.append(
            [
                CASE_LABELS.get(case, case),
                docs_tables.count(any_s["particles"]),
                f"{any_s['variables'] / 1e3:.1f}k",
                *cells,
                _s(fastest) + (f" ({fastest['linear_solvers'][0]})" if fastest else ""),
                _s(get("mkl", "high-nocnr")),
                " / ".join(f"{v:g} ({b})" for b, v in ref.items()) or "—",
                f"≤ {target:g}" if target else "—",
                ("yes" if best_s <= target else "no") if target else "—",
            ]
        )
    return docs_tables.md(
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


@docs_table(f"{docs_tables.RESULTS}/threads.json")
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
    return docs_tables.md(["case"] + [label for _, label in cols], out)


@docs_table(f"{docs_tables.RESULTS}/cnr.json")
def cnr() -> str:
    """MKL Pardiso with and without conditional numerical reproducibility."""
    sm = _suite_summaries("cnr")
    out = []
    for case in dict.fromkeys(k[0] for k in sm):
        hi, nohi = sm.get((case, "mkl", "high")), sm.get((case, "mkl", "high-nocnr"))
        fa, nofa = sm.get((case, "mkl", "fast")), sm.get((case, "mkl", "fast-nocnr"))
        ratio = f"{nohi['median_s'] / hi['median_s']:.2f}" if hi and nohi else "—"
        out.append([case, _s(hi), _s(nohi), ratio, _s(fa), _s(nofa)])
    return docs_tables.md(
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


@docs_table(f"{docs_tables.RESULTS}/suite.json")
def reference_timings() -> str:
    """The reference implementation's s/step per backend, and the suite's targets."""
    data = docs_tables.load(f"{docs_tables.RESULTS}/suite.json")
    refs, targets = data["reference_s_per_step"], data["targets_s_per_step"]
    out = []
    for case, label in REFERENCE_ROWS.items():
        ref = refs.get(case, {})
        cells = [_seconds(ref.get(b)) for b in ("qdldl", "faer", "mkl")]
        out.append([label, *cells, _seconds(targets.get(case))])
    return docs_tables.md(
        ["case", "qdldl", "faer", "MKL Pardiso", "target (best backend)"], out
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default=",".join(DEFAULT_CASES), help=f"{list(CASES)}")
    ap.add_argument(
        "--backends", default=",".join(BACKENDS), help="qdldl,faer,mkl (or auto)"
    )
    ap.add_argument("--presets", default=",".join(PRESETS), help="high,fast")
    ap.add_argument(
        "--steps", type=int, default=0, help="timed steps (0: the case's default)"
    )
    ap.add_argument("--repeat", type=int, default=1, help="runs per combination")
    ap.add_argument("--threads", type=int, default=0, help="Clarabel max_threads")
    ap.add_argument(
        "--skip",
        default="",
        help="extra case:backend pairs to skip (hopeless 3D qdldl is always skipped "
        "unless --no-default-skips)",
    )
    ap.add_argument("--no-default-skips", action="store_true")
    ap.add_argument(
        "--step-limit",
        type=float,
        default=300.0,
        help="a child is killed after (steps + 3) * this + 300 s",
    )
    ap.add_argument(
        "--wait-idle",
        type=float,
        default=0.0,
        help="before each run wait (up to --wait-max s) until other processes "
        "use fewer than this many cores (3 s /proc/stat window); e.g. 0.15",
    )
    ap.add_argument("--wait-load", type=float, default=0.0)
    ap.add_argument("--wait-max", type=float, default=300.0)
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--name", default="suite", help="output file stem")
    ap.add_argument(
        "--append", action="store_true", help="add runs to <out>/<name>.json"
    )
    ap.add_argument("--compare", nargs=2, metavar=("A.json", "B.json"))
    ap.add_argument("--render", metavar="FILE.json")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    args = ap.parse_args(argv)
    if args.tables:
        return docs_tables.write(TABLES)

    if args.compare:
        print(compare(*args.compare))
        return 0
    if args.render:
        return harness.render(args.render, markdown)
    if args.child:
        case, backend, preset = args.child.split(":")
        harness.emit_result(run_child(case, backend, preset, args.threads, args.steps))
        return 0

    cases = [c for c in args.cases.split(",") if c]
    for c in cases:
        if c not in CASES:
            ap.error(f"unknown case {c!r}; choose from {list(CASES)}")
    backends = [b for b in args.backends.split(",") if b]
    presets = [p for p in args.presets.split(",") if p]
    skip = {tuple(x.split(":")) for x in args.skip.split(",") if x}
    reasons = {} if args.no_default_skips else dict(HOPELESS)
    skip |= set(reasons)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    jpath = out / f"{args.name}.json"
    if args.append and jpath.exists():
        report = json.loads(jpath.read_text())
        report.setdefault("appended", []).append(
            {"date": time.strftime("%Y-%m-%dT%H:%M:%S"), "argv": sys.argv[1:]}
        )
    else:
        report = {
            "machine": harness.machine_info(),
            "settings": {
                "repeat": args.repeat,
                "threads": args.threads,
                "wait_load": args.wait_load,
                "wait_idle": args.wait_idle,
                # Scheduling priority of the runs (negative: favoured over the
                # other jobs of a shared machine; `nice -n -10 python ...`).
                "niceness": os.nice(0),
                "steps": args.steps or "case default",
                "loadavg_at_start": os.getloadavg(),
                "argv": sys.argv[1:],
            },
            "cases": {c: CASES[c] for c in CASES},
            "reference_s_per_step": REFERENCE,
            "targets_s_per_step": TARGET,
            "runs": [],
        }

    def save():
        harness.write_report(jpath, report, markdown(report))

    for case in cases:
        combos = []
        for backend in backends:
            if (case, backend) in skip:
                for p in presets:
                    report["runs"].append(
                        {
                            "case": case,
                            "backend": backend,
                            "preset": p,
                            "steps": [],
                            "note": "skipped"
                            + (
                                f": {reasons[(case, backend)]}"
                                if (case, backend) in reasons
                                else ""
                            ),
                        }
                    )
                continue
            combos += [(backend, p) for p in presets]
        for rep in range(args.repeat):
            k = rep % max(len(combos), 1)
            order = combos[k:] + combos[:k]
            if rep % 2:
                order = order[::-1]
            for backend, preset in order:
                print(
                    f"{case:13s} {backend:5s} {preset:4s} #{rep + 1} "
                    f"({time.strftime('%H:%M:%S')}, load {os.getloadavg()[0]:.2f}) ...",
                    end=" ",
                    flush=True,
                )
                run = run_subprocess(case, backend, preset, args, rep)
                s = summarise([run])
                if s:
                    print(
                        f"{s['median_s']:.3f} s/step, it {s['iterations']}, "
                        f"solver {s['solver_pct']:.1f} %, "
                        f"peak {s['peak_rss_mb']:.0f} MB, "
                        f"load {s['min_loadavg']:.1f}-{s['max_loadavg']:.1f}, "
                        f"others {s['other_cores_median']:.2f} "
                        f"({s['steps_clean']}/{s['steps_total']} clean)",
                        flush=True,
                    )
                else:
                    print(run.get("note", "no result"), flush=True)
                report["runs"].append(run)
                save()
    save()
    print(markdown(report))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
