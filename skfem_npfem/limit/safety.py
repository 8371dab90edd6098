"""The factor of safety by strength reduction.

The cohesion and the friction coefficient are divided by F until the gravity
multiplier of the limit analysis (:mod:`.analysis`) is 1.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import NpfemError, ParameterError
from ..materials import Material
from ..step.solver import SolverOptions
from .analysis import LimitResult, associated, limit_analysis

__all__ = [
    "BISECTION_TOL",
    "CAP",
    "FLOOR",
    "MIN_FACTOR",
    "SafetyResult",
    "reduced_strength",
    "strength_reduction",
]


def reduced_strength(material: Material, factor: float) -> Material:
    """A copy of a Mohr-Coulomb-type material with ``c/F`` and ``tan(phi)/F``.

    Parameters
    ----------
    material : Material
        A material with ``c`` and ``phi`` (Mohr-Coulomb, Tresca,
        Drucker-Prager).
    factor : float
        Strength reduction factor ``F > 0``.

    Raises
    ------
    ParameterError
        If the material has no ``c``/``phi`` or ``factor`` is not positive.
    """
    if not (hasattr(material, "c") and hasattr(material, "phi")):
        raise ParameterError(
            "material",
            type(material).__name__,
            "a material with c and phi (MohrCoulomb, Tresca, DruckerPrager)",
        )
    if not (math.isfinite(factor) and factor > 0):
        raise ParameterError("factor", factor, "a finite number > 0")
    out = copy.copy(associated(material))
    out.c = material.c / factor
    out.phi = math.degrees(math.atan(math.tan(math.radians(material.phi)) / factor))
    out.psi = out.phi
    return out


@dataclass
class SafetyResult:
    """Factor of safety by strength reduction (:func:`strength_reduction`).

    Attributes
    ----------
    factor_of_safety : float
        ``F`` with gravity multiplier 1 for ``c/F``, ``tan(phi)/F``.
    limit : LimitResult
        The limit analysis at ``F`` (its mechanism is the failure mechanism);
        after a bisection, the one just above ``F`` (on the failing side).
    programs : int
        Cone programs solved.
    iterates : list of (F, multiplier)
        Every iterate.
    multiplier_unreduced : float
        The load multiplier of the unreduced strengths (the first iterate).
    iterations : int
        Interior-point iterations of all the programs.
    statuses : list of str
        Clarabel's status of every program (``Solved`` or ``AlmostSolved``).
    """

    factor_of_safety: float
    limit: LimitResult
    programs: int
    iterates: list
    multiplier_unreduced: float
    iterations: int = 0
    statuses: list = field(default_factory=list)


def strength_reduction(
    operator: Any,
    materials: list[Material],
    material: np.ndarray,
    load: np.ndarray,
    *,
    fixed: np.ndarray | None = None,
    tied: list[np.ndarray] | None = None,
    tol: float = 1e-4,
    max_programs: int = 30,
    options: SolverOptions | None = None,
    strength: np.ndarray | None = None,
) -> SafetyResult:
    """Factor of safety ``F``: the strength reduction with collapse multiplier 1.

    Solves ``lambda(F) = 1`` for the multiplier of :func:`limit_analysis` on
    ``load`` (gravity) with every material reduced by
    :func:`reduced_strength`.  ``lambda`` decreases with ``F`` and is exactly
    ``lambda(1) / F`` for purely cohesive materials; the iteration works on
    ``y = log lambda`` against ``x = log F``: the first step assumes that
    slope (-1), which ends a cohesive problem in two programs, and the
    following ones are secant steps through the last two iterates, kept inside
    the bracket ``lambda >= 1 > lambda`` once one is known.  It stops when
    ``|log lambda| <= tol``.

    A cohesionless part carries any multiple of its weight or none, so
    ``lambda`` can jump between 0 and infinity (the programs cap it at
    :data:`CAP`).  Where an iterate is at 0 or at the cap, the next one halves
    or doubles ``F`` until the bracket is found, then bisects it
    (geometrically) down to a relative width ``max(tol, 2e-3)``: 9-12
    programs for a dry sand slope.

    With pore water the cones carry effective stress and ``load`` is the
    load of gravity on the skeleton: the weight with the saturated density
    plus the force of the pore pressure,
    :func:`~skfem_npfem.water.water_force` (:func:`~.loads.gravity_load`
    builds it).  Both are proportional to ``g`` (the pore pressure of a
    water table is ``rho_w g`` times a head), so the multiplier scales
    weight and water force together and ``lambda(F) = 1`` is the real state
    of the wet soil.  An undrained analysis passes
    :func:`~.undrained.undrained_materials`: ``c'`` and ``tan(phi')`` are
    reduced and the undrained strengths follow, ``s'_0`` kept.

    Parameters
    ----------
    operator, materials, material, load, fixed, tied, options, strength
        As :func:`limit_analysis` (``load``: the body's weight, with the
        water's force when there is water; the cohesion that ``strength``
        scales is reduced with the rest).
    tol : float
        Tolerance on ``|log lambda|`` (about the relative error of ``F``).
    max_programs : int
        Cap on the cone programs solved.

    Returns
    -------
    SafetyResult

    Raises
    ------
    ParameterError
        If a material has no ``c``/``phi``.
    NpfemError
        If the iteration finds no ``F`` within ``max_programs`` programs (its
        message says what usually causes it, not which argument to raise:
        the scenes do not have one).
    """

    def solve(F: float) -> LimitResult:
        mats = [reduced_strength(m, F) for m in materials]
        return limit_analysis(
            operator,
            mats,
            material,
            load,
            fixed=fixed,
            tied=tied,
            options=options,
            max_multiplier=CAP,
            strength=strength,
        )

    def interior(lam: float) -> bool:
        return FLOOR < lam < (1 - 1e-6) * CAP

    iterates: list = []
    runs: list[tuple[str, int]] = []  # (status, iterations) of every program
    points: list[tuple[float, float]] = []  # (log F, log lambda), interior only
    lo = hi = None  # log F with lambda >= 1, and with lambda < 1
    best = failing = None
    x = 0.0
    width = math.log1p(max(tol, BISECTION_TOL))
    while True:
        if len(iterates) >= max_programs or x < math.log(MIN_FACTOR):
            # (Below MIN_FACTOR: a part with no strength at all, e.g. undrained
            # points at zero effective stress, carries nothing at any F.)
            raise _no_factor(len(iterates), *iterates[-1])
        res = solve(math.exp(x))
        lam = res.multiplier
        iterates.append((math.exp(x), lam))
        runs.append((res.status, res.iterations))
        if lam >= 1.0:
            lo, best = x, res
        else:
            hi, failing = x, res
        inside = interior(lam)
        if inside:
            y = math.log(lam)
            if abs(y) <= tol:
                F, best = math.exp(x), res
                break
            points.append((x, y))
        if lo is not None and hi is not None and hi - lo <= width:
            # The mechanism: the one of the failing side (at the cap the
            # feasible side's duals describe the cap, not a collapse).
            F, best = math.exp(0.5 * (lo + hi)), failing
            break
        if inside and len(points) >= 2 and points[-1][1] != points[-2][1]:
            (x0, y0), (x1, y1) = points[-2], points[-1]
            x_new = x1 - y1 * (x1 - x0) / (y1 - y0)
        elif inside:
            x_new = x + y  # lambda ~ 1/F
        else:
            x_new = x + (math.log(2.0) if lam >= 1.0 else -math.log(2.0))
        if lo is not None and hi is not None:
            if not (inside and lo < x_new < hi):
                x_new = 0.5 * (lo + hi)
        x = x_new
    return SafetyResult(
        factor_of_safety=F,
        limit=best if best is not None else res,
        programs=len(iterates),
        iterates=iterates,
        multiplier_unreduced=iterates[0][1],
        iterations=sum(n for _, n in runs),
        statuses=[status for status, _ in runs],
    )


def _no_factor(programs: int, F: float, lam: float) -> NpfemError:
    """The error of a strength reduction that ran out of cone programs."""
    return NpfemError(
        f"strength reduction found no factor of safety in {programs} cone "
        f"programs (last F = {F:.6g}, multiplier {lam:.6g}): no reduction F "
        "brings the gravity multiplier to 1, as for a body that its supports do "
        "not carry (a region resting on nothing) or one whose multiplier jumps "
        "between 0 and the cap; check the supports and regions (undrained: "
        "points at zero effective stress have no strength unless c' > 0)"
    )


#: Multiplier cap of the programs of :func:`strength_reduction` (a
#: cohesionless body's multiplier is otherwise unbounded when it stands).
CAP = 1.0e3


#: Multipliers below this count as "carries nothing" in :func:`strength_reduction`.
FLOOR = 1.0e-3


#: Relative width at which a bisection of :func:`strength_reduction` stops.
BISECTION_TOL = 2e-3


#: Smallest factor of safety :func:`strength_reduction` tries.
MIN_FACTOR = 1.0e-6
