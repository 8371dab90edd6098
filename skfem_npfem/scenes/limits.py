"""Up-front limits of a scene run: particles, memory and steps.

A run that cannot fit in memory or would take ~forever is refused before
anything is built, with one line that says how big it would be and what to
change.  The memory model is an upper envelope of measured peak memory
(``benchmarks/memory.py``, results in ``benchmarks/results/memory.md``): one
step in a fresh process, for the remeshed 2D collapse, the 2D footing, a 3D
elastic column and a 3D Drucker-Prager block, with the qdldl, faer and MKL
Pardiso linear solvers, then a safety factor (:data:`SAFETY`).  2D cost is close
to linear in the particles; 3D grows faster (the fill-in of the factorisation).

Scenes call :func:`check_size` with their particle count before building
anything, and :func:`check_steps` once the run's step count is known.  Both are
skipped with the scene parameter ``size_check=false``.

Examples
--------
>>> round(estimate_memory_mb(1000, 2))
137
>>> estimate_memory_mb(10_000, 3) > estimate_memory_mb(10_000, 2)
True
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from typing import Any

from ..errors import ParameterError

__all__ = [
    "LENGTH",
    "MAGNITUDES",
    "MAX_STEPS",
    "SAFETY",
    "SPACING",
    "check_size",
    "check_steps",
    "estimate_memory_mb",
    "format_bytes",
    "machine_memory_mb",
]

#: Resident memory of a process that has imported the package and its
#: dependencies (measured: 75-77 MB) plus MKL Pardiso's own (about 25 MB), MiB.
BASE_MB = 110.0
#: Memory above the baseline, MiB: ``coef * n ** exponent`` for n particles,
#: an upper envelope of the measurements by dimension (all three solvers).
#: 2D: at most 0.0178 MB per particle (collapse, MKL, 15.8k particles; 0.0173
#: at 34k: linear).  3D: faer on the Drucker-Prager block is the worst (240 MB
#: at 3.3k, 1451 MB at 9.5k particles); n**1.5 through its largest point stays
#: above every 3D measurement (MKL 2051 MB at 23.8k).
_MODEL = {2: (0.018, 1.0), 3: (0.00156, 1.5)}
#: Factor applied to the fitted envelope (later steps, other solvers, threads).
SAFETY = 1.5
#: Share of the machine's memory a run may be estimated to use.
USABLE = 0.8
#: Most steps a run may plan without ``size_check=false``.
MAX_STEPS = 1_000_000


#: Magnitudes a nonzero value of these parameters must have, by name (the same
#: in every scene): the ranges the scenes were run at (both ends of each are run
#: by tests/run/test_reliability_ranges.py).  Outside them the arithmetic leaves
#: double precision (``dt**2`` underflows at 1e-162 s, a compliance of 1e300
#: overflows) or the solver can no longer resolve the load (a tolerance of
#: 1e-8 relative to the largest stress).  Zero stays governed by the parameter
#: itself (e.g. ``c = 0`` or ``gravity = 0`` where allowed).
MAGNITUDES: dict[str, tuple[float, float]] = {
    "E": (1.0, 1e13),
    "rho": (1e-3, 1e5),
    "gamma": (1e-2, 1e6),
    "gravity": (1e-3, 1e3),
    "c": (1e-3, 1e12),
    "K0": (1e-2, 1e2),
    "dt": (1e-9, 1e4),
    "t_end": (1e-9, 1e6),
    "min_time": (1e-9, 1e6),
    "height": (1e-4, 1e4),
    "width": (1e-4, 1e4),
    "half_width": (1e-4, 1e4),
    "aspect": (1e-2, 1e2),
    "settlement": (1e-9, 1e6),
    "max_settlement": (1e-9, 1e7),
    "max_displacement": (1e-3, 10.0),
}


#: Range of every length parameter that has no range of its own in
#: :data:`MAGNITUDES` (``spacing``, ``radius``, ``depth``), m: the same as
#: ``height`` and the widths there (docs/output.md).
LENGTH: dict[str, float] = {"lo": 1e-4, "hi": 1e4}

#: Range of a particle ``spacing``, m: down to 1e-6 m so that a body of the
#: smallest size (1e-4 m) can still be resolved by tens of particles.
SPACING: dict[str, float] = {"lo": 1e-6, "hi": 1e4}


def estimate_memory_mb(n_particles: float, dim: int) -> float:
    """Conservative peak memory of a run with ``n_particles`` in ``dim`` D, MiB."""
    coef, expo = _MODEL[3 if dim == 3 else 2]
    return BASE_MB + SAFETY * coef * max(float(n_particles), 0.0) ** expo


def machine_memory_mb() -> float:
    """Physical memory of this machine, or the cgroup limit if lower, MiB.

    Returns ``inf`` where it cannot be read.
    """
    total = math.inf
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**20
    except (AttributeError, ValueError, OSError):  # pragma: no cover - not POSIX
        pass
    for path in (
        "/sys/fs/cgroup/memory.max",
        "/sys/fs/cgroup/memory/memory.limit_in_bytes",
    ):
        try:
            with open(path) as f:
                text = f.read().strip()
        except OSError:
            continue
        if text.isdigit():
            total = min(total, int(text) / 2**20)
    return total


def format_bytes(mb: float) -> str:
    """``mb`` MiB as a short text (MB, GB, TB, ...)."""
    value, unit = mb, "MB"
    for bigger in ("GB", "TB", "PB", "EB"):
        if value < 1024:
            break
        value, unit = value / 1024, bigger
    if value >= 1024:  # beyond EB
        return f"{mb * 2**20:.1e} bytes"
    return f"{value:.3g} {unit}"


def _enabled(values: Mapping[str, Any]) -> bool:
    return bool(values.get("size_check", True))


def check_size(
    n_particles: float,
    dim: int,
    values: Mapping[str, Any],
    name: str = "spacing",
    advice: str = "use a larger spacing",
) -> None:
    """Refuse a run whose estimated memory exceeds this machine's.

    Parameters
    ----------
    n_particles : float
        Particles the scene would create (estimated from its geometry and
        spacing, before building anything; may be huge).
    dim : int
        Spatial dimension (2 or 3; axisymmetric runs count as 2).
    values : mapping
        The scene's resolved values; ``size_check=False`` skips the check.
    name : str
        The parameter to name in the message (the one that made it large).
    advice : str
        What to change.

    Raises
    ------
    ParameterError
        Naming ``name``, the particles, the estimated and the available memory.
    """
    if not _enabled(values):
        return
    need = estimate_memory_mb(n_particles, dim)
    have = machine_memory_mb()
    if need <= USABLE * have and math.isfinite(need):
        return
    raise ParameterError(
        name,
        values.get(name),
        f"~{n_particles:.3g} particles ({dim}D) would need an estimated "
        f"{format_bytes(need)} of memory; this machine has {format_bytes(have)}: "
        f"{advice} (or set size_check=false to run anyway)",
    )


def check_steps(
    n_steps: float,
    values: Mapping[str, Any],
    name: str,
    why: str,
    advice: str,
) -> None:
    """Refuse a run that plans more than :data:`MAX_STEPS` steps.

    ``why`` says where the count comes from (e.g. ``"t_end/dt = 1/1e-12 s"``;
    empty when ``name`` is the count itself).
    """
    if not _enabled(values) or n_steps <= MAX_STEPS:
        return
    raise ParameterError(
        name,
        values.get(name),
        f"{why + ' gives ' if why else ''}~{n_steps:.2g} steps, more than the "
        f"{MAX_STEPS:.0e} a run may plan: {advice} (or set size_check=false to run "
        "anyway)",
    )
