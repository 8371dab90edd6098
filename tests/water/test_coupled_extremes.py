"""Coupled steps at extreme conductivity, time step and fluid storage.

Terzaghi's column (a weightless layer of height H = 1 m on a fixed,
impermeable base between smooth impermeable walls, drained at its top,
loaded suddenly by q0) on a coarse 2 x 10 lattice: k from 1e-12 to 1e-2 m/s
and dt from 1e-6 to 1e3 s span the time factor T = c_v dt / H^2 (c_v = k M /
gamma_w) from 1e-15 to 1e4.  Each step must solve, and its answer is the
physical limit it reaches or Terzaghi's series:

* T << (h/H)^2 (undrained limit): no water leaves the cells below the drained
  top, so the excess pore pressure carries the load, q0 / (1 + M S) with the
  fluid's storage S = n / K_w (the 1D loading efficiency: the skeleton's
  strain q_s / M equals the fluid's S p);
* T >> 1 (drained limit): the oedometric settlement q0 H / M and no excess
  pore pressure; so too at T = 1 for a fluid far more compressible than the
  skeleton (M S = 1.3e4: the water never carried more than q0 / (1 + M S));
  with storage, c_v = k / (gamma_w (1/M + S));
* in between, the degree of consolidation U(T) of Terzaghi's series.

A Mohr-Coulomb footing loaded near collapse, coupled, at the same extremes:
every step solves, and the undrained and drained limits give the footing
load of an undrained and a drained step on the same block.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import numpy as np
import pytest
from skfem import MeshTri
from water.test_consolidation import (
    GRAVITY,
    NU,
    Q0,
    RHO_W,
    E,
    M,
    _column,
    _consolidate,
    exact_u,
)

import skfem_npfem as npfem

GAMMA_W = RHO_W * GRAVITY
ACCEPTED = ("Solved", "AlmostSolved")


def series_u(T: float) -> float:
    """Terzaghi's degree of consolidation U(T) (the exact series)."""
    return float(exact_u(np.array([T]))[0])


def time_factor(k: float, dt: float, storage: float = 0.0) -> float:
    """``T = c_v dt / H^2`` of Terzaghi's column (H = 1 m).

    ``c_v = k / (gamma_w (1/M + S))``: the fluid's storage S slows it.
    """
    return k / (GAMMA_W * (1 / M + storage)) * dt


@dataclass
class Run:
    """What a case's steps gave: the numbers its check reads, per step too."""

    u: float = 0.0  # settlement / (q0 H / M) (column)
    mean_p: float = 0.0  # mean excess pore pressure / q0 below the top (column)
    loads: np.ndarray = field(default_factory=lambda: np.zeros(0))  # q / c (footing)
    statuses: list[str] = field(default_factory=list)
    iterations: list[int] = field(default_factory=list)


@cache
def column(k: float, dt: float, steps: int = 1, storage: float = 0.0) -> Run:
    """Terzaghi's column on a 2 x 10 lattice, coupled, ``steps`` steps of ``dt``."""
    top, history = _consolidate(
        _column(2, 10, False), [dt] * steps, k=k, storage=storage
    )
    run = Run()
    for _, _, _, step in history:
        run.statuses.append(step.record.status)
        run.iterations.append(step.record.iterations)
    _, run.u, p, step = history[-1]
    vol = step.operator.volumes[~top]
    run.mean_p = np.sum(p.excess_pore_pressure[~top] * vol) / np.sum(vol) / Q0
    return run


@cache
def footing(drainage: str | None, k: float = 0.0, dt: float = 1.0) -> Run:
    """q / c of a rigid smooth footing after each of 4 settlements of 5 mm.

    A weightless Mohr-Coulomb block (c = 10 kPa, phi = 20 deg, psi = 0), 2 m
    x 1 m, 17 x 9 nodes, a footing of half-width 0.5 m on the symmetry line.
    """
    mesh = MeshTri.init_tensor(np.linspace(0, 2, 17), np.linspace(0, 1, 9))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = x[:, 1] < 1e-12
    fixed[:, 0] = (x[:, 0] < 1e-12) | (x[:, 0] > 2 - 1e-12) | fixed[:, 1]
    foot = (x[:, 1] > 1 - 1e-12) & (x[:, 0] < 0.5 + 1e-12)
    fixed[foot, 1] = True
    soil = npfem.MohrCoulomb(E=E, nu=NU, rho=1e-9, c=1e4, phi=20.0, psi=0.0)
    water = None
    if drainage is not None:
        kwargs = {"permeability": k} if drainage == "coupled" else {}
        water = npfem.Water(drainage, None, rho_w=RHO_W, **kwargs)
    model = npfem.Model(
        dim=2,
        materials=[soil],
        mode="static",
        gravity=GRAVITY,
        water=water,
        update_geometry=False,
    )
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    p.v_prescribed[foot, 1] = -5e-3 / dt
    state, run, loads = None, Run(), []
    for _ in range(4):
        p, step = npfem.advance(p, model, dt, mesh, start=state)
        state = step.state
        loads.append(-step.solution.reaction[foot, 1].sum() / 0.5 / 1e4)
        run.statuses.append(step.record.status)
        run.iterations.append(step.record.iterations)
    run.loads = np.array(loads)
    return run


@dataclass(frozen=True)
class Case:
    """One row of the matrix: its parameters and the answer it must give."""

    name: str
    params: dict
    expected: str


@dataclass
class Outcome:
    """A case's result: the measured text, its main error, pass or fail."""

    outcome: str
    error: float
    passed: bool
    iterations: list[int]


UNDRAINED = (
    "undrained limit (T < 1e-4): mean excess p below the top q0/(1+M S) within 1 %"
)
DRAINED = (
    "drained limit (T >> 1, or T = 1 with M S >> 1): settlement q0 H/M within "
    "1e-3, excess p < 1e-3 q0"
)
CASES = [
    *(
        Case(
            f"column-k-{k:g}-dt-{dt:g}",
            {"k": k, "dt": dt},
            UNDRAINED if time_factor(k, dt) < 1e-4 else DRAINED,
        )
        for k in (1e-12, 1e-2)
        for dt in (1e-6, 1e3)
    ),
    Case(
        "column-terzaghi",
        {"k": 1e-7, "dt": 100.0, "steps": 20},
        "between the limits: U(T = 0.27) of Terzaghi's series within 0.03",
    ),
    *(
        Case(f"column-storage-{label}-{limit}", {"storage": s, "k": k, "dt": dt}, text)
        for s, label in ((1e-15, "tiny"), (1 / M, "1-over-M"), (1e-3, "large"))
        for k, dt, text, limit in (
            (1e-12, 1.0, UNDRAINED, "undrained"),
            (1e-2, 1e3, DRAINED, "drained"),
        )
    ),
    *(
        Case(
            f"footing-k-{k:g}-dt-{dt:g}",
            {"k": k, "dt": dt},
            "undrained limit: q/c of the undrained step within 3 % (the coupled "
            "step drains the free surface: an O(h) layer)"
            if time_factor(k, dt) < 1e-4
            else "drained limit: q/c of the dry step (weightless, no table) "
            "within 0.1 %",
        )
        for k in (1e-12, 1e-2)
        for dt in (1e-6, 1e3)
    ),
]


def _solved(run: Run) -> bool:
    return set(run.statuses) <= set(ACCEPTED)


def result(case: Case) -> Outcome:
    """Run a case and check it against its limit or series."""
    k, dt, storage = case.params["k"], case.params["dt"], case.params.get("storage", 0)
    if case.name.startswith("footing"):
        run = footing("coupled", k, dt)
        undrained = time_factor(k, dt) < 1e-4
        ref = footing("undrained" if undrained else None).loads
        error = float(np.max(np.abs(run.loads / ref - 1)))
        passed = _solved(run) and error <= (0.03 if undrained else 1e-3)
        text = f"q/c {run.loads[-1]:.4f} vs {ref[-1]:.4f}, max rel. gap {error:.1e}"
        return Outcome(text, error, passed, run.iterations)
    run = column(k, dt, case.params.get("steps", 1), storage)
    if case.name == "column-terzaghi":
        T = time_factor(k, dt) * case.params["steps"]
        error = run.u - series_u(T)
        passed = _solved(run) and abs(error) <= 0.03
        text = f"U = {run.u:.4f} vs {series_u(T):.4f} at T = {T:.3f}"
    elif time_factor(k, dt, storage) < 1e-4:
        expected = 1 / (1 + M * storage)
        error = run.mean_p / expected - 1
        passed = _solved(run) and abs(error) <= 0.01
        text = (
            f"T = {time_factor(k, dt):.1e}: p/q0 = {run.mean_p:.4g} vs {expected:.4g}"
        )
    else:
        error = run.u - 1
        passed = _solved(run) and abs(error) <= 1e-3 and abs(run.mean_p) < 1e-3
        T = time_factor(k, dt, storage)
        text = f"T = {T:.1e}: U = {run.u:.6f}, p/q0 = {run.mean_p:.1e}"
    return Outcome(text, float(error), passed, run.iterations)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_coupled_step_at_the_extremes(case):
    o = result(case)
    assert o.passed, f"{case.name}: {o.outcome}; expected {case.expected}"
