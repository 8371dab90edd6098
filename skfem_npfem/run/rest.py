"""The at-rest stop rule of the time loop.

A run ends when its kinetic energy has fallen to a small fraction of its peak
and stayed there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from ..errors import ParameterError

__all__ = ["AtRest"]


@dataclass
class AtRest:
    """Stop rule for :meth:`Simulation.run`: the flow has come to rest.

    Stops once ``time >= min_time`` and the kinetic energy of the last step is
    at most ``fraction`` times a reference energy:

    * ``"max_kinetic"``: the largest kinetic energy of the run so far;
    * ``"potential_drop"``: the potential energy released since the start,
      ``E_p(0) - E_p(t)`` (never stops while nothing has fallen).

    It reads only :attr:`Simulation.records`, so a resumed run stops at the same
    step as an uninterrupted one.

    Parameters
    ----------
    fraction : float
        Kinetic energy at rest as a fraction of the reference, in (0, 1);
        default 1e-3.
    min_time : float
        Earliest time to stop, s, >= 0; default 0.
    reference : {"max_kinetic", "potential_drop"}
        The reference energy (above); default ``"max_kinetic"``.

    Raises
    ------
    ParameterError
        If ``fraction``, ``min_time`` or ``reference`` is outside the ranges
        above.

    Examples
    --------
    >>> rule = AtRest(fraction=0.01, min_time=0.2)
    >>> rule.reference
    'max_kinetic'
    """

    fraction: float = 1e-3
    min_time: float = 0.0
    reference: str = "max_kinetic"
    #: How the progress report names this reason to stop.
    label: ClassVar[str] = "at rest"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.fraction) and 0 < self.fraction < 1):
            raise ParameterError("fraction", self.fraction, "a number in (0, 1)")
        if not (math.isfinite(self.min_time) and self.min_time >= 0):
            raise ParameterError("min_time", self.min_time, "a time >= 0 (s)")
        if self.reference not in ("max_kinetic", "potential_drop"):
            raise ParameterError(
                "reference", self.reference, "'max_kinetic' or 'potential_drop'"
            )

    def __call__(self, sim: Any) -> bool:  # noqa: D102
        recs = sim.records
        if not recs or sim.time < self.min_time * (1 - 1e-12):
            return False
        if self.reference == "max_kinetic":
            ref = max(r.kinetic_energy for r in recs)
        else:
            ref = sim.initial["potential_energy"] - recs[-1].potential_energy
        return ref > 0 and recs[-1].kinetic_energy <= self.fraction * ref
