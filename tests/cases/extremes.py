"""The extremes matrix: numerical stability at the edges of the parameters.

A matrix of short runs with parameters pushed to the edges: Poisson's ratio,
Young's modulus, time step, friction angle, cohesion, length scale,
near-duplicate particles and sliver elements.  Every case states the physical
answer it expects (also the table of docs/extremes.md) or a documented error,
and :func:`result` runs it once per process.

Examples
--------
>>> from cases.extremes import CASES, DEFAULT, SLOW
>>> len(CASES) == len(DEFAULT) + len(SLOW), sorted({c.group for c in CASES})
(True, ['E', 'c', 'dt', 'length', 'mesh', 'nu', 'phi'])
"""

from __future__ import annotations

# Importing the case modules registers their cases.
from . import extremes_column, extremes_footing, extremes_mesh  # noqa: F401
from .framework import CASES, ENERGY_TOLERANCE, Case, Outcome, result

__all__ = ["CASES", "DEFAULT", "ENERGY_TOLERANCE", "SLOW", "Case", "Outcome", "result"]

#: Cases of the default test run.
DEFAULT = [c for c in CASES if not c.slow]
#: Long cases (``pytest -m slow``).
SLOW = [c for c in CASES if c.slow]
