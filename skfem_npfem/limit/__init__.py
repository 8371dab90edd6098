"""Limit analysis: collapse multipliers and factors of safety as cone programs.

The step's operator and yield cones without elasticity, inertia or time:

* :mod:`.analysis` -- :func:`limit_analysis`, the collapse multiplier of a
  reference load and the mechanism from the duals (:class:`LimitResult`);
* :mod:`.program` -- that cone program: dof map, rows, scaling and the
  Clarabel solve;
* :mod:`.safety` -- :func:`strength_reduction`, the factor of safety of
  Mohr-Coulomb materials (:class:`SafetyResult`, :func:`reduced_strength`);
* :mod:`.loads` -- :func:`gravity_load`, the weight with the force of the
  pore water (drained analyses in effective stress);
* :mod:`.undrained` -- :class:`UndrainedStrength`, the undrained strengths
  an initial effective stress implies (:func:`undrained_materials`).
"""

from .analysis import LimitResult, limit_analysis
from .loads import gravity_load
from .safety import SafetyResult, reduced_strength, strength_reduction
from .undrained import (
    UndrainedStrength,
    mean_effective_stress,
    undrained_materials,
    undrained_strength,
)

__all__ = [
    "LimitResult",
    "SafetyResult",
    "UndrainedStrength",
    "gravity_load",
    "limit_analysis",
    "mean_effective_stress",
    "reduced_strength",
    "strength_reduction",
    "undrained_materials",
    "undrained_strength",
]
