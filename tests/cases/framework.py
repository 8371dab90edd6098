"""Framework of the extremes matrix: cases, outcomes, the registry and helpers.

A case is a function registered with :func:`case` that runs short simulations
and returns an :class:`Outcome`: whether the physical answer stated in its
``expected`` text (or a documented error) was met, and what was measured.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from skfem_npfem.particles import Particles
from skfem_npfem.scenes import get_scene

__all__ = [
    "CASES",
    "Case",
    "Outcome",
    "all_finite",
    "case",
    "constrained_modulus",
    "result",
    "run_built",
    "within",
]

RHO, G, H, W, NU, E_COL = 2000.0, 9.81, 4.0, 1.0, 0.3, 1.0e7  # column defaults
C_FOOT = 1.0e4  # footing default cohesion, Pa
PRANDTL = 2.0 + math.pi
N_GAMMA_30 = {"smooth": 7.653, "rough": 14.75}  # N_gamma footing (Martin 2005)


@dataclass
class Outcome:
    """What a case measured.

    ``error`` is the case's main error measure (relative unless stated in the
    table), ``iterations`` the interior-point iterations of every step, and
    ``plastic`` whether the program had yield cones (elastic programs are one
    KKT solve: 0 iterations) and ``yielding`` whether the cones became active
    (a collapse load was reached).
    """

    passed: bool
    outcome: str
    error: float
    iterations: list[int] = field(default_factory=list)
    plastic: bool = False
    yielding: bool = False


@dataclass(frozen=True)
class Case:
    """One cell of the matrix."""

    name: str
    group: str
    scene: str
    params: dict
    expected: str
    fn: Callable[[], Outcome]
    slow: bool = False


CASES: list[Case] = []


def case(name, group, scene, params, expected, slow=False):
    """Register a case function (returns an :class:`Outcome`)."""

    def deco(fn):
        CASES.append(Case(name, group, scene, params, expected, fn, slow))
        return fn

    return deco


@functools.cache
def result(name: str) -> Outcome:
    """Run a case once per session (tests and the iteration summary share it)."""
    return next(c for c in CASES if c.name == name).fn()


def within(value: float, lo: float, hi: float) -> bool:
    """Whether ``value`` is finite and in ``[lo, hi]``."""
    return bool(np.isfinite(value) and lo <= value <= hi)


def run_built(name: str, overrides: dict, prepare=None):
    """Build and run a scene; return (simulation, metrics, iterations per step)."""
    scene = get_scene(name)
    srun = scene.build(scene.resolve(overrides), out=None, progress=False)
    if prepare is not None:
        prepare(srun.simulation)
    srun.simulation.run(**srun.run_kwargs)
    sim = srun.simulation
    return sim, srun.metrics(sim), [r.iterations for r in sim.records]


def all_finite(p: Particles) -> bool:
    """Whether every particle state array is finite."""
    return all(np.all(np.isfinite(a)) for a in (p.x, p.v, p.a, p.u, p.stress))


def constrained_modulus(E: float, nu: float) -> float:
    """Oedometric modulus ``E (1-nu) / ((1+nu)(1-2nu))``, Pa."""
    return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
