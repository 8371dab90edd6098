"""Up-front size checks: particles and memory of a run, before any work.

A 3D run's memory is dominated by the sparse factorisation of the step's KKT
system, whose fill grows like ``n^(4/3)`` for a 3D mesh of ``n`` particles
(nested dissection); a 2D one's grows about linearly.  The peak resident
memory of whole runs measured on this project's machine
(``benchmarks/results/cylinder3d.md``, ``suite_16k.md``; MKL Pardiso and faer)
lies below

    3D: 250 MB + 6e-3 MB * n^(4/3)     (3 942 particles: 387-504 MB measured,
                                        estimate 624; 10 027: 961-1 246, 1 547)
    2D: 150 MB + 0.03 MB * n           (16 110 particles: 383-415, 633)

:func:`check_memory` refuses a run whose estimate exceeds the memory the
machine has available now, with one line saying the estimate, the machine's
memory and what to change.
"""

from __future__ import annotations

import math
import os

from ..errors import ParameterError

__all__ = [
    "available_memory_mb",
    "check_memory",
    "estimate_memory_mb",
    "lattice_particles",
]


def estimate_memory_mb(n_particles: float, dim: int) -> float:
    """Estimated peak memory of a run with ``n_particles``, MB (see the notes).

    Examples
    --------
    >>> round(estimate_memory_mb(10_027, 3))
    1547
    """
    n = float(n_particles)
    if dim == 3:
        return 250.0 + 6e-3 * n ** (4.0 / 3.0)
    return 150.0 + 0.03 * n


def available_memory_mb() -> tuple[float, float]:
    """``(available, total)`` memory of the machine, MB (``inf`` where unknown).

    Linux: ``MemAvailable`` and ``MemTotal`` of ``/proc/meminfo``; elsewhere the
    physical memory for both.
    """
    try:
        with open("/proc/meminfo") as f:
            info = {line.split(":")[0]: float(line.split()[1]) / 1024.0 for line in f}
        return info["MemAvailable"], info["MemTotal"]
    except (OSError, KeyError, ValueError, IndexError):
        pass
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**20
        return float(total), float(total)
    except (ValueError, OSError, AttributeError):  # pragma: no cover
        return math.inf, math.inf


def lattice_particles(geometry: str, values: dict, spacing: float) -> float:
    """Particles of a column's lattice (estimated without building it).

    ``values`` holds ``radius`` and ``height`` (cylindrical geometries) or
    ``length``, ``aspect``, ``depth`` and ``symmetric`` (box).  The quarter
    cylinder's count per layer is the quarter disc's area in lattice cells plus
    one edge and the centre, ``pi n^2 / 4 + n + 1`` (Gauss's circle problem:
    273.5 for ``n = 18`` spacings over the radius, 271 counted).
    """
    h = float(spacing)
    if geometry in ("axisymmetric", "quarter-cylinder"):
        nr = max(1.0, round(values["radius"] / h))
        layers = max(1.0, round(values["height"] / h)) + 1.0
        if geometry == "axisymmetric":
            return (nr + 1.0) * layers
        return (math.pi / 4.0 * nr * nr + nr + 1.0) * layers
    width = values["length"] * (1.0 if values["symmetric"] else 2.0)
    height = values["aspect"] * values["length"]
    per = [max(1.0, round(v / h)) + 1.0 for v in (width, values["depth"], height)]
    return per[0] * per[1] * per[2]


def check_memory(geometry: str, values: dict, spacing: float, dim: int) -> float:
    """Refuse a run that would need more memory than the machine has.

    Returns the estimated particle count.

    Raises
    ------
    ParameterError
        Naming ``spacing``, with the estimate, the machine's memory, the largest
        particle count that fits and the override ``size_check=false``.
    """
    n = lattice_particles(geometry, values, spacing)
    need = estimate_memory_mb(n, dim)
    avail, total = available_memory_mb()
    if need <= avail:
        return n
    # The largest particle count whose estimate fits (dim 3: invert n^(4/3)).
    if dim == 3:
        fit = max(0.0, (avail - 250.0) / 6e-3) ** 0.75
    else:
        fit = max(0.0, (avail - 150.0) / 0.03)
    scale = (n / max(fit, 1.0)) ** (1.0 / dim)
    raise ParameterError(
        "spacing",
        spacing,
        f"a larger spacing: geometry={geometry} at this spacing has ~{n:.3g} "
        f"particles and needs ~{need / 1024:.3g} GB, but the machine has "
        f"{avail / 1024:.3g} GB available ({total / 1024:.3g} GB total); about "
        f"{fit:.3g} particles fit (spacing >= ~{spacing * scale:.3g} m), or set "
        "size_check=false to run anyway",
    )
