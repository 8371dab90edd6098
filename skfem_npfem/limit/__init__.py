"""Limit analysis: collapse multipliers and factors of safety as cone programs.

The step's operator and yield cones without elasticity, inertia or time:

* :mod:`.analysis` -- :func:`limit_analysis`, the collapse multiplier of a
  reference load and the mechanism from the duals (:class:`LimitResult`);
* :mod:`.program` -- that cone program: dof map, rows, scaling and the
  Clarabel solve;
* :mod:`.safety` -- :func:`strength_reduction`, the factor of safety of
  Mohr-Coulomb materials (:class:`SafetyResult`, :func:`reduced_strength`).
"""

from .analysis import LimitResult, limit_analysis
from .safety import SafetyResult, reduced_strength, strength_reduction

__all__ = [
    "LimitResult",
    "SafetyResult",
    "limit_analysis",
    "reduced_strength",
    "strength_reduction",
]
