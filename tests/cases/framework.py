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
    "ENERGY_TOLERANCE",
    "Case",
    "EnergyBudget",
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
    (a collapse load was reached).  ``energy`` is the largest
    :attr:`EnergyBudget.excess` of the case's runs (nan: no step was taken,
    a documented error came first).
    """

    passed: bool
    outcome: str
    error: float
    iterations: list[int] = field(default_factory=list)
    plastic: bool = False
    yielding: bool = False
    energy: float = float("nan")


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


#: Largest energy excess a case may show (:attr:`EnergyBudget.excess`): the
#: mechanical energy may not grow by more than 1 % of the energy turned over.
#: Measured: at most 2e-10 in the matrix (columns at rest), +8.8e-4 for the
#: column collapse at E = 1 kPa (before the stabilisation's weight took the
#: inertial scale: 1.0, the run created all the energy it turned over).
ENERGY_TOLERANCE = 0.01

_BUDGETS: list[EnergyBudget] = []


@functools.cache
def result(name: str) -> Outcome:
    """Run a case once per session (tests and the iteration summary share it).

    Every run of the case keeps an :class:`EnergyBudget` (:func:`run_built`
    and :func:`EnergyBudget.watch` register them); the outcome's ``energy`` is
    the largest excess among them.
    """
    _BUDGETS.clear()
    out = next(c for c in CASES if c.name == name).fn()
    excess = [b.excess for b in _BUDGETS if b.steps]
    out.energy = max(excess) if excess else float("nan")
    _BUDGETS.clear()
    return out


def complementary_energy(p: Particles, materials, volumes, index) -> float:
    """Elastic energy ``sum V 1/2 s C^-1 s`` of the particles ``index``, J.

    ``volumes`` are their nodal volumes; the first three stress components are
    the normal ones, the others shears (every Voigt layout of the package).
    """
    s = p.stress[index]
    E = np.array([m.E for m in materials])[p.material[index]]
    nu = np.array([m.nu for m in materials])[p.material[index]]
    n, t = s[:, :3], s[:, 3:]
    cross = n[:, 0] * n[:, 1] + n[:, 1] * n[:, 2] + n[:, 2] * n[:, 0]
    w = (np.sum(n * n, 1) - 2 * nu * cross + 2 * (1 + nu) * np.sum(t * t, 1)) / (2 * E)
    return float(np.sum(np.asarray(volumes, float) * w))


@dataclass
class EnergyBudget:
    """The energy balance of a run, step by step.

    Backward Euler with an elastic-plastic (dissipative) material cannot create
    energy: after every step ``n``

        K_n + (P_n - P_0) + (Psi_n - Psi_0) <= W_n,

    with ``K`` the kinetic energy (0 in quasi-static steps, which have no
    inertia), ``P`` the potential energy of gravity, ``Psi`` the elastic energy
    stored in the stresses (the initial geostatic stress stores some: its
    release is a source like the potential energy's) and ``W`` the work of the
    prescribed motions and loads (``reaction . du``; the supports' is 0).  The
    step changes ``Psi`` on its own mesh: ``sum V_i (psi(s_n+1) - psi(s_n))``
    over its nodes, ``V_i`` their volumes (a grain leaving the mesh takes its
    stress with it: released, a loss).  :attr:`excess` is the largest left
    side minus ``W`` over the run, divided by the energy turned over (the
    largest of ``Psi_0`` and of ``K + |P - P_0| + |Psi - Psi_0| + |W|``).
    """

    model: object
    particles: Particles
    potential0: float = 0.0
    stored: float = 0.0
    work: float = 0.0
    turnover: float = 0.0
    worst: float = -math.inf
    steps: int = 0

    def __post_init__(self) -> None:
        g, x = self.model.gravity, self.particles.x
        self.potential0 = float(g * np.sum(self.particles.mass * x[:, -1]))
        _BUDGETS.append(self)

    @classmethod
    def watch(cls, sim) -> EnergyBudget:
        """A budget fed by every step of a :class:`~skfem_npfem.Simulation`."""
        budget = cls(sim.model, sim.particles)
        sim.callbacks.append(budget)
        return budget

    def __call__(self, sim, new: Particles, step) -> bool:
        self.add(new, step)
        return False

    def add(self, new: Particles, step) -> None:
        """Account for one step (the particles after it and its Step)."""
        old, act, mats = self.particles, step.active, self.model.materials
        vol = step.operator.volumes
        before = complementary_energy(old, mats, vol, act)
        if not self.steps:
            self.turnover = before  # the energy stored at the start
        self.stored += complementary_energy(new, mats, vol, act) - before
        du = (new.u - old.u)[act]
        self.work += float(np.sum(step.solution.reaction * du))
        kinetic = 0.0
        if self.model.mode == "dynamic":
            kinetic = float(0.5 * np.sum(new.mass * np.sum(new.v * new.v, 1)))
        g = self.model.gravity
        released = self.potential0 - float(g * np.sum(new.mass * new.x[:, -1]))
        self.worst = max(self.worst, kinetic - released + self.stored - self.work)
        turned = kinetic + abs(released) + abs(self.stored) + abs(self.work)
        self.turnover = max(self.turnover, turned)
        self.particles = new
        self.steps += 1

    @property
    def excess(self) -> float:
        """Largest energy created, relative to the energy turned over."""
        return self.worst / self.turnover if self.turnover > 0 else 0.0


def within(value: float, lo: float, hi: float) -> bool:
    """Whether ``value`` is finite and in ``[lo, hi]``."""
    return bool(np.isfinite(value) and lo <= value <= hi)


def run_built(name: str, overrides: dict, prepare=None):
    """Build and run a scene; return (simulation, metrics, iterations per step).

    The run keeps an :class:`EnergyBudget` (its case's ``Outcome.energy``).
    """
    scene = get_scene(name)
    srun = scene.build(scene.resolve(overrides), out=None, progress=False)
    if prepare is not None:
        prepare(srun.simulation)
    EnergyBudget.watch(srun.simulation)
    srun.simulation.run(**srun.run_kwargs)
    sim = srun.simulation
    return sim, srun.metrics(sim), [r.iterations for r in sim.records]


def all_finite(p: Particles) -> bool:
    """Whether every particle state array is finite."""
    return all(np.all(np.isfinite(a)) for a in (p.x, p.v, p.a, p.u, p.stress))


def constrained_modulus(E: float, nu: float) -> float:
    """Oedometric modulus ``E (1-nu) / ((1+nu)(1-2nu))``, Pa."""
    return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
