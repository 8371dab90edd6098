"""Solver statistics of a run: what :meth:`Simulation.summary` reports.

Steps, interior-point iterations, time per phase, the medians of the step time
and the conservation checks, from the run's scalar step records alone, and the
peak memory of the process.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..step.stages import StepRecord

__all__ = ["peak_memory_mb", "run_statistics"]


def run_statistics(
    records: Sequence[StepRecord],
    time: float,
    n_particles: int,
    initial_mass: float,
    peak_memory_before: float = 0.0,
) -> dict[str, Any]:
    """Solver statistics of the steps ``records`` of a run at ``time``.

    Parameters
    ----------
    records : sequence of StepRecord
        The run's step records (possibly none).
    time : float
        The run's time, s.
    n_particles : int
        Number of particles.
    initial_mass : float
        Mass at the start, kg: the reference of ``mass_change``.
    peak_memory_before : float, default 0
        Peak memory of the processes that ran the steps before this one (a run
        continued from a checkpoint), MiB: ``peak_memory_mb`` is the larger of
        it and this process's peak.

    Returns
    -------
    dict
        ``steps``, ``time``, the interior-point iterations (total, max, mean),
        ``statuses``, ``retries``, ``wall_time`` per phase, the median step
        time (whole and per phase), ``n_particles``, ``mass_change`` and
        ``volume_change`` of the last step, ``max_kinetic_energy``,
        ``linear_solvers`` and ``peak_memory_mb``.

    Examples
    --------
    >>> run_statistics([], 0.0, 10, 1.0)["steps"]
    0
    """
    recs = list(records)
    phases: dict[str, float] = {}
    for r in recs:
        for k, v in r.timings.items():
            phases[k] = phases.get(k, 0.0) + v
    its = [r.iterations for r in recs]
    keys = sorted({k for r in recs for k in r.timings})
    median = {k: float(np.median([r.timings.get(k, 0.0) for r in recs])) for k in keys}
    step_times = [sum(r.timings.values()) for r in recs]
    return {
        "steps": len(recs),
        "time": time,
        "ipm_iterations_total": int(sum(its)),
        "ipm_iterations_max": int(max(its, default=0)),
        "ipm_iterations_mean": float(np.mean(its)) if its else 0.0,
        "statuses": sorted({r.status for r in recs}),
        "retries": int(sum(r.retries for r in recs)),
        "wall_time": phases,
        "step_time_median": float(np.median(step_times)) if recs else 0.0,
        "step_time_median_by_phase": median,
        "n_particles": int(n_particles),
        "mass_change": float(recs[-1].mass / initial_mass - 1.0) if recs else 0.0,
        "volume_change": float(recs[-1].volume_change) if recs else 0.0,
        "max_kinetic_energy": float(max((r.kinetic_energy for r in recs), default=0.0)),
        "linear_solvers": sorted({r.linear_solver for r in recs} - {""}),
        "peak_memory_mb": max(peak_memory_mb(), peak_memory_before),
    }


def peak_memory_mb() -> float:
    """Peak resident memory of this process so far, MiB (0 where unknown)."""
    try:
        import resource
    except ImportError:  # pragma: no cover - not on Windows
        return 0.0
    kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return float(kib) / (1024.0 if sys.platform != "darwin" else 1024.0**2)
