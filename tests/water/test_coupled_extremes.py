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
  pore pressure;
* in between, the degree of consolidation U(T) of Terzaghi's series.

A Mohr-Coulomb footing loaded near collapse, coupled, at the same extremes:
every step solves, and the undrained and drained limits give the footing
load of an undrained and a drained step on the same block.
"""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshTri

import skfem_npfem as npfem

E, NU, Q0, GRAVITY, RHO_W = 1e7, 0.3, 1e4, 10.0, 1000.0
M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))
GAMMA_W = RHO_W * GRAVITY
ACCEPTED = ("Solved", "AlmostSolved")


def series_u(T: float) -> float:
    """Terzaghi's degree of consolidation U(T) (the exact series)."""
    m = np.arange(200)
    mm = np.pi * (2 * m + 1) / 2
    return float(1 - np.sum(2 / mm**2 * np.exp(-(mm**2) * T)))


def _column(k: float, dts: list[float], storage: float = 0.0):
    """Settlement / (q0 H / M), mean excess p / q0 below the top, statuses."""
    mesh = MeshTri.init_tensor(np.linspace(0, 0.2, 3), np.linspace(0, 1, 11))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = x[:, 1] < 1e-12
    fixed[:, 0] = (x[:, 0] < 1e-12) | (x[:, 0] > 0.2 - 1e-12) | fixed[:, 1]
    top = x[:, 1] > 1 - 1e-12
    loads = npfem.surface_load(x, top, Q0)
    soil = npfem.LinearElastic(E=E, nu=NU, rho=1e-9)  # weightless
    water = npfem.Water("coupled", None, rho_w=RHO_W, permeability=k, storage=storage)
    model = npfem.Model(
        dim=2,
        materials=[soil],
        mode="static",
        gravity=GRAVITY,
        loads=loads,
        water=water,
        update_geometry=False,
    )
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    state, statuses = None, []
    for dt in dts:
        p, step = npfem.advance(p, model, dt, mesh, start=state)
        state = step.state
        statuses.append(step.record.status)
    u = -np.sum(loads[:, 1] * p.u[:, 1]) / np.sum(loads[:, 1]) / (Q0 / M)
    vol = step.operator.volumes[~top]
    mean_p = np.sum(p.excess_pore_pressure[~top] * vol) / np.sum(vol) / Q0
    return u, mean_p, statuses


@pytest.mark.parametrize("k", [1e-12, 1e-2])
@pytest.mark.parametrize("dt", [1e-6, 1e3])
def test_column_reaches_its_limit_at_extreme_k_and_dt(k, dt):
    T = k * M / GAMMA_W * dt
    u, mean_p, statuses = _column(k, [dt])
    assert set(statuses) <= set(ACCEPTED)
    if T < 1e-4:  # undrained: the water carries the load below the top
        assert mean_p == pytest.approx(1.0, abs=0.01)
    else:  # T = 1.3e4: drained at once
        assert T > 1e3
        assert u == pytest.approx(1.0, abs=1e-3)
        assert abs(mean_p) < 1e-3


def test_column_follows_terzaghi_between_the_limits():
    # c_v = 1.3e-3 m^2/s: 20 steps of 100 s reach T = 0.27
    k, dt = 1e-7, 100.0
    u, _, statuses = _column(k, [dt] * 20)
    assert set(statuses) <= set(ACCEPTED)
    T = k * M / GAMMA_W * dt * 20
    assert u == pytest.approx(series_u(T), abs=0.03)


@pytest.mark.parametrize("storage", [1e-15, 1 / M, 1e-3])
def test_fluid_storage_shares_the_undrained_load(storage):
    # nearly incompressible (S M = 1e-8), as stiff as the skeleton (S M = 1)
    # and very compressible (S M = 1.3e4): p = q0 / (1 + M S) at once, and
    # the drained limit is the oedometric settlement whatever S
    _, mean_p, statuses = _column(1e-12, [1.0], storage)
    assert set(statuses) <= set(ACCEPTED)
    expected = 1 / (1 + M * storage)
    assert mean_p == pytest.approx(expected, rel=0.01, abs=1e-3 * expected)
    u, mean_p, _ = _column(1e-2, [1e3], storage)
    assert u == pytest.approx(1.0, abs=1e-3)
    assert abs(mean_p) < 1e-3


def _footing(drainage: str | None, k: float = 0.0, dt: float = 1.0):
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
    state, loads, statuses = None, [], []
    for _ in range(4):
        p, step = npfem.advance(p, model, dt, mesh, start=state)
        state = step.state
        loads.append(-step.solution.reaction[foot, 1].sum() / 0.5 / 1e4)
        statuses.append(step.record.status)
    return np.array(loads), statuses


@pytest.fixture(scope="module")
def footing_limits():
    """The dry (= drained: weightless, no water table) and undrained loads."""
    return _footing(None)[0], _footing("undrained")[0]


@pytest.mark.parametrize("k", [1e-12, 1e-2])
@pytest.mark.parametrize("dt", [1e-6, 1e3])
def test_footing_near_collapse_reaches_its_limit(k, dt, footing_limits):
    dry, undrained = footing_limits
    loads, statuses = _footing("coupled", k, dt)
    assert set(statuses) <= set(ACCEPTED)
    if k * M / GAMMA_W * dt < 1e-4:
        # no flow: the cells keep their volume as in the undrained step, but
        # for those at the drained free surface, which the undrained step
        # does not have (an O(h) layer: within 3 % of the load)
        assert loads == pytest.approx(undrained, rel=0.03)
    else:  # drained at once: the skeleton alone, as without water
        assert loads == pytest.approx(dry, rel=1e-3)
