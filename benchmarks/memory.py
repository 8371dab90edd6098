"""Peak memory against particles, for the up-front size check of the scenes.

Each case runs in a fresh child process: build, one step, then report the
particles and the peak resident memory (``ru_maxrss``) of the child, and the
resident memory after the imports (the baseline).  The fitted model and its
safety margin live in ``skfem_npfem/scenes/limits.py``; this script is how its
coefficients were measured (results in ``benchmarks/results/memory.json`` and
``memory.md``).

Usage::

    python benchmarks/memory.py [--cases collapse-22,block3d-16 ...] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: name -> (kind, size, linear solver)
CASES: dict[str, tuple[str, int, str]] = {}
for _solver in ("qdldl", "faer", "mkl"):
    for _k in (11, 22, 44, 88):
        CASES[f"collapse-{_k}-{_solver}"] = ("collapse", _k, _solver)
    for _k in (16, 32, 64):
        CASES[f"footing-{_k}-{_solver}"] = ("footing", _k, _solver)
    for _k in (6, 8, 11) if _solver == "qdldl" else (6, 8, 11, 16):
        CASES[f"block3d-{_k}-{_solver}"] = ("block3d", _k, _solver)
    if _solver != "qdldl":
        for _k in (8, 12, 16):
            CASES[f"column3d-{_k}-{_solver}"] = ("column3d", _k, _solver)
CASES["collapse-130-mkl"] = ("collapse", 130, "mkl")
CASES["collapse-130-faer"] = ("collapse", 130, "faer")
CASES["block3d-22-mkl"] = ("block3d", 22, "mkl")


CHILD = r"""
import json, resource, sys
kind, k, solver = sys.argv[1], int(sys.argv[2]), sys.argv[3]
import numpy as np, scipy, skfem, clarabel, skfem_npfem
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
from skfem_npfem import run_scene
common = {"linear_solver": solver}
from skfem_npfem.scenes import SCENES
if any(p.name == "size_check" for p in SCENES["elastic-column"].params):
    common["size_check"] = False
if kind == "collapse":
    res = run_scene("column-collapse", {"spacing": 0.2 / k, "t_end": 5e-3, **common})
    n = res["solver"]["n_particles"]
elif kind == "column3d":
    res = run_scene("elastic-column", {"dim": 3, "spacing": 1.0 / k, **common})
    n = res["solver"]["n_particles"]
elif kind == "footing":
    res = run_scene("strip-footing", {"spacing": 1.0 / k, "steps": 1,
                                      "plateau_tol": 0, **common})
    n = res["solver"]["n_particles"]
else:
    sys.path.insert(0, sys.argv[4])
    from suite import build_block3d
    sim = build_block3d((2 * k, k, k), solver, "high", 0)
    sim.run(steps=1)
    n = sim.particles.n
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print("RESULT " + json.dumps({"n": int(n), "peak_mb": peak, "base_mb": base}))
"""


def run_case(name: str) -> dict:
    """Run one case in a child process; return its measurements."""
    kind, k, solver = CASES[name]
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, kind, str(k), solver, str(HERE)],
        capture_output=True,
        text=True,
        check=False,
    )
    wall = time.perf_counter() - t0
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    if proc.returncode != 0 or not line:
        tail = proc.stderr.strip().splitlines()[-1:] or ["no output"]
        return {"case": name, "kind": kind, "solver": solver, "error": tail[0]}
    out = json.loads(line[0][7:])
    return {"case": name, "kind": kind, "solver": solver, "wall_s": wall, **out}


def markdown(rows: list[dict]) -> str:
    """The measurements as a Markdown table."""
    lines = [
        "# Peak memory against particles (one step, fresh process)",
        "",
        "| case | solver | particles | peak MB | baseline MB "
        "| (peak - base) kB/particle |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['case']} | {r['solver']} | — | {r['error']} | | |")
            continue
        per = 1024 * (r["peak_mb"] - r["base_mb"]) / r["n"]
        lines.append(
            f"| {r['case']} | {r['solver']} | {r['n']} | {r['peak_mb']:.0f} | "
            f"{r['base_mb']:.0f} | {per:.1f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Run the cases and write the JSON and Markdown reports."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--out", default=str(HERE / "results" / "memory.json"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    rows = json.loads(out.read_text()) if out.exists() else []
    done = {r["case"] for r in rows}
    for name in args.cases.split(","):
        if name in done:
            continue
        row = run_case(name)
        print(json.dumps(row), flush=True)
        rows.append(row)
        out.write_text(json.dumps(rows, indent=1))
        out.with_suffix(".md").write_text(markdown(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
