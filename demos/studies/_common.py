"""What the studies of this folder share: paths, the collapse sweep, results files.

A study imports it as ``import _common`` (Python puts a script's own folder on
``sys.path`` when it runs ``python demos/studies/x.py``; ``tests/conftest.py``
puts this folder there for the tests).  Studies import each other the same way
(``import volume_correction``), never by file path.
"""

from __future__ import annotations

import importlib
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

#: The repository root.
ROOT = Path(__file__).resolve().parents[2]
#: Committed results: docs pages and their JSON, figures.
VALIDATION = ROOT / "docs" / "validation"
COMPARISON = VALIDATION / "comparison"
#: Work folder of the studies (gitignored): full records, logs, per-case files.
WORK = ROOT / "out"

#: The collapse sweep of the volume-correction, stabilisation-factor and
#: roughness-floor studies: aspects a = H0/L0 and L0 (m).
ASPECTS = (0.5, 1.0, 2.0, 4.0, 8.0)
LENGTH = 0.2
#: t_end = T_END_FACTOR * sqrt(H0 / g), a cap the at-rest rule stops before (as
#: in demos/studies/collapse_validation.py); the scene's own 1 s stops tall
#: columns early.
T_END_FACTOR = 15.0
G = 9.81

#: Elastic column at rest: the collapse scene with a cohesion it never reaches.
AT_REST = {"c": 1e6, "t_end": 1.0, "rest_fraction": 0.0}
#: Steps at which :func:`roughness_run` reports the stress roughness.
REPORT_STEPS = (20, 40, 80, 160)


def floats(text: str) -> list[float]:
    """``"0.5,1,2"`` -> ``[0.5, 1.0, 2.0]`` (empty items skipped)."""
    return [float(t) for t in text.split(",") if t.strip()]


def ints(text: str) -> list[int]:
    """``"8,12"`` -> ``[8, 12]`` (empty items skipped)."""
    return [int(t) for t in text.split(",") if t.strip()]


def run_to_rest(overrides: dict[str, Any]) -> dict[str, Any]:
    """One ``column-collapse`` run to rest; its metrics and step times.

    Parameters
    ----------
    overrides
        Scene parameters; ``t_end`` defaults to ``T_END_FACTOR sqrt(H0/g)`` and
        ``volume_correction`` to 0 (0.1 became the scene's default after the
        volume-correction study).

    Returns
    -------
    dict
        Particles, steps, volume change, run-out, final height, stress
        roughness at rest and its maximum, whether the run came to rest, the
        median step time and the wall time.
    """
    from skfem_npfem.scenes import get_scene

    scene = get_scene("column-collapse")
    h0 = overrides.get("aspect", 2.0) * overrides.get("half_width", LENGTH)
    t_end = T_END_FACTOR * math.sqrt(h0 / G)
    values = scene.resolve(
        {"t_end": t_end, "volume_correction": 0.0, **overrides, "threads": 1}
    )
    srun = scene.build(values, out=None, progress=False)
    sim = srun.simulation
    t0 = time.perf_counter()
    sim.run(**srun.run_kwargs)
    m = srun.metrics(sim)
    steps = [sum(r.timings.values()) for r in sim.records]
    return {
        "overrides": overrides,
        "particles": int(sim.particles.n),
        "steps": len(sim.records),
        "volume_change": m["volume_change"],
        "normalised_runout": m["normalised_runout"],
        "final_height": m.get("final_height"),
        "R_at_rest": m["stress_roughness"],
        "R_max": m["stress_roughness_max"],
        "at_rest": bool(m["at_rest"]),
        "step_median_s": float(np.median(steps)),
        "wall_s": time.perf_counter() - t0,
    }


def roughness_run(params: dict[str, Any], steps: int | None = None) -> dict[str, Any]:
    """Run the collapse scene with ``params``; roughness, creep and metrics.

    Parameters
    ----------
    params
        Scene parameters (``volume_correction`` 0 unless given: the
        stabilisation studies are about the stresses).
    steps
        Number of steps (None: the scene's own end and at-rest rule).

    Returns
    -------
    dict
        The stress roughness at :data:`REPORT_STEPS`, at the end and its
        maximum, run-out, final height, volume change, the largest
        displacement and speed at the end, the median step time and wall time.
    """
    from skfem_npfem.metrics import stress_roughness
    from skfem_npfem.scenes import get_scene

    scene = get_scene("column-collapse")
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


def replace_rows(
    old: list[dict], new: list[dict], key: Callable[[dict], Any]
) -> list[dict]:
    """Runs of ``old`` whose ``key`` no run of ``new`` has, then ``new``.

    How the studies of this folder add runs to their committed JSON (``--append``).
    """
    done = {key(r) for r in new}
    return [r for r in old if key(r) not in done] + list(new)


def write_results(path: Path, text: str | None, page: str) -> None:
    """The JSON ``text`` at ``path`` (None: keep it), ``page`` beside it as .inc.

    The ``.inc`` fragment is included by the study's page under
    ``docs/validation`` (not a page of its own).

    The page is printed too.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    if text is not None:
        path.write_text(text)
    path.with_suffix(".inc").write_text(page)
    print(page)


def benchmark(name: str) -> ModuleType:
    """Import the script ``benchmarks/<name>.py`` (it imports its siblings)."""
    folder = str(ROOT / "benchmarks")
    if folder not in sys.path:
        sys.path.append(folder)
    return importlib.import_module(name)
