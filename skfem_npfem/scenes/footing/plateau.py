"""Run a displacement-controlled limit-load scene to a detected load plateau.

The load ``q(s)`` of a rigid footing pushed down by a settlement ``s`` rises
elastically, bends at the onset of plastic flow and approaches the collapse load
from below.  Where the bend lies depends on the material (``s ~ N c b / E``: for
a large friction angle it comes at many times the settlement of a cohesive
soil), so a fixed settlement either wastes steps or stops on the rising branch.

:class:`PlateauRule` decides, from the load curve alone, the next settlement
increment and whether to stop:

* **Steps.** A first stage of ``steps`` equal increments reaches the minimum
  settlement ``settlement``.  After it, each increment is ``growth`` times the
  previous one while the curve is nearly straight (the secant slopes of the last
  two steps differ by at most ``BEND`` times the initial slope: the elastic
  branch and the plateau), and stays the same through the bend.
* **Plateau.** The plateau is reached when the load rose by at most ``tol``
  (relative) while the settlement doubled: ``|q(s) - q(s/2)| <= tol |q(s)|``,
  with ``q(s/2)`` interpolated on the curve.  The test does not depend on how
  the steps are spaced and never fires on a straight (elastic) branch, where the
  change is 100 %.  For a tail ``q_lim - C s^-a`` the load still missing at
  detection is ``tol / (2^a - 1)``: about ``tol`` for the measured ``a ~ 1``.
* **Cap.** The run stops without a plateau at ``max_settlement`` or after
  ``max_steps`` steps; :meth:`PlateauRule.outcome` then says so in a warning.

The rule reads only the ``(settlement, load)`` pairs, so a resumed run takes
the same steps as an uninterrupted one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import ParameterError

__all__ = ["BEND", "PlateauRule", "doubling_change"]

#: Largest change of the secant slope between two steps, relative to the
#: initial (elastic) slope, for which the increment still grows.
BEND = 0.1

#: Relative round-off allowance when comparing settlements.
_EPS = 1e-9


def doubling_change(curve: Sequence[Sequence[float]]) -> float | None:
    """Relative load change over the last doubling of the settlement.

    Parameters
    ----------
    curve : sequence of (settlement, load)
        The load curve, settlement increasing.

    Returns
    -------
    float or None
        ``|q(s_n) - q(s_n/2)| / |q(s_n)|`` with ``q(s_n/2)`` linearly
        interpolated between recorded points; None while ``s_n/2`` lies before
        the first point (or the last load is zero).

    Examples
    --------
    >>> doubling_change([(1.0, 1.0), (2.0, 2.0)])  # straight line through 0
    0.5
    >>> doubling_change([(1.0, 5.0), (2.0, 5.1), (4.0, 5.1)])
    0.0
    """
    if not curve:
        return None
    s = np.array([c[0] for c in curve], float)
    q = np.array([c[1] for c in curve], float)
    half = 0.5 * s[-1]
    if half < s[0] * (1 - _EPS) or q[-1] == 0.0:
        return None
    q_half = float(np.interp(half, s, q))
    return float(abs(q[-1] - q_half) / abs(q[-1]))


@dataclass(frozen=True)
class PlateauRule:
    """Settlement increments and the stop test of a limit-load run.

    Attributes
    ----------
    settlement : float
        Minimum settlement, reached by ``steps`` equal increments, m.
    steps : int
        Number of increments of the first stage.
    tol : float
        Plateau tolerance: largest relative load change over a doubling of the
        settlement; 0 switches detection off (exactly ``steps`` steps).
    growth : float
        Increment factor per step after the first stage (1: equal steps).
    max_settlement : float
        Cap on the settlement, m.
    max_steps : int
        Cap on the number of steps.
    """

    settlement: float
    steps: int
    tol: float = 1e-3
    growth: float = 1.5
    max_settlement: float = math.inf
    max_steps: int = 100

    def __post_init__(self) -> None:
        if self.tol > 0 and self.max_settlement < self.settlement * (1 - _EPS):
            raise ParameterError(
                "max_settlement",
                self.max_settlement,
                f"at least settlement = {self.settlement:g} m",
            )
        if self.tol > 0 and self.max_steps < self.steps:
            raise ParameterError(
                "max_steps", self.max_steps, f"at least steps = {self.steps}"
            )

    @property
    def detect(self) -> bool:
        """Whether the run continues to a detected plateau."""
        return self.tol > 0

    @property
    def step_cap(self) -> int:
        """Steps :meth:`Simulation.run` is allowed."""
        return self.max_steps if self.detect else self.steps

    @property
    def first_increment(self) -> float:
        """Settlement increment of the first stage, m."""
        return self.settlement / self.steps

    def plateau(self, curve: Sequence[Sequence[float]]) -> bool:
        """Whether the last point of ``curve`` is on the plateau."""
        change = doubling_change(curve)
        return change is not None and change <= self.tol

    def stop_reason(self, curve: Sequence[Sequence[float]]) -> str | None:
        """Why the run stops after the last point of ``curve`` (None: go on).

        One of ``"plateau"``, ``"max_settlement"``, ``"max_steps"`` and
        ``"steps"`` (detection off, the ``steps`` are done).
        """
        n, s = len(curve), curve[-1][0] if curve else 0.0
        if not self.detect:
            return "steps" if n >= self.steps else None
        if s >= self.settlement * (1 - _EPS) and self.plateau(curve):
            return "plateau"
        if s >= self.max_settlement * (1 - _EPS):
            return "max_settlement"
        if n >= self.max_steps:
            return "max_steps"
        return None

    def next_increment(self, curve: Sequence[Sequence[float]], last: float) -> float:
        """Settlement increment of the next step, m.

        Parameters
        ----------
        curve : sequence of (settlement, load)
            The curve so far (at least one point).
        last : float
            Increment of the last step, m.
        """
        s = curve[-1][0]
        if not self.detect or s < self.settlement * (1 - _EPS):
            # First stage: equal steps, landing on the minimum settlement.
            return min(self.first_increment, max(self.settlement - s, 0.0)) or last
        inc = last * self.growth if self._straight(curve) else last
        rest = self.max_settlement - s
        # Land on the cap rather than stopping a sliver short of it.
        return rest if inc > 0.99 * rest else inc

    def _straight(self, curve: Sequence[Sequence[float]]) -> bool:
        """The secant slopes of the last two steps differ by <= BEND k_0."""
        if len(curve) < 3:
            return True
        (s0, q0), (s1, q1), (s2, q2) = curve[-3], curve[-2], curve[-1]
        k_0 = abs(curve[0][1] / curve[0][0]) if curve[0][0] > 0 else 0.0
        k1, k2 = (q1 - q0) / (s1 - s0), (q2 - q1) / (s2 - s1)
        return k_0 > 0 and abs(k2 - k1) <= BEND * k_0

    def outcome(
        self, curve: Sequence[Sequence[float]], scene: str, locking: str = ""
    ) -> dict[str, Any]:
        """Plateau metrics of a finished run (and its warnings).

        Parameters
        ----------
        curve : sequence of (settlement, load)
            The load curve of the run.
        scene : str
            Scene name, at the start of each warning.
        locking : str
            Non-empty when the discretisation locks (why, e.g. "fem-remap with
            P1 elements under isochoric plastic flow"): its load keeps rising
            above the collapse load, so a cap before the plateau does not give
            a lower estimate, and a plateau is inflated.

        Returns
        -------
        dict
            ``plateau_reached`` (None when detection is off), ``plateau_change``,
            ``plateau_tolerance``, ``plateau_settlement``, ``stopped_by`` and
            ``warnings`` (a list of one-line messages).
        """
        change = doubling_change(curve) if curve else None
        reason = self.stop_reason(curve) if curve else None
        reached = (reason == "plateau") if self.detect else None
        warnings: list[str] = []
        if self.detect and not reached:
            s = curve[-1][0] if curve else 0.0
            what = (
                "the load rose by "
                + (f"{change:.2%}" if change is not None else "an unknown amount")
                + f" over the last doubling of the settlement (plateau_tol "
                f"{self.tol:g})"
            )
            cap = (
                f"max_steps = {self.max_steps}"
                if reason == "max_steps"
                else f"max_settlement = {self.max_settlement:g} m"
            )
            if locking:
                verdict = (
                    f"{locking} locks, so the load is inflated by locking and "
                    "unreliable (not a lower estimate of the collapse load); use "
                    "method=npfem or element=p2"
                )
            else:
                verdict = (
                    "the reported load is a lower estimate of the collapse load; "
                    "raise max_settlement/max_steps"
                )
            warnings.append(
                f"{scene}: no load plateau within {cap} ({len(curve)} steps, "
                f"settlement {s:.4g} m): {what}; {verdict}"
            )
        elif locking and curve:
            warnings.append(
                f"{scene}: {locking} locks, so the load is inflated by locking "
                "and unreliable; use method=npfem or element=p2"
            )
        return {
            "plateau_reached": reached,
            "plateau_change": change,
            "plateau_tolerance": self.tol,
            "plateau_settlement": curve[-1][0] if reached else None,
            "stopped_by": reason,
            "warnings": warnings,
        }
