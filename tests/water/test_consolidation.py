"""Coupled (consolidating) steps against Terzaghi's one-dimensional solution.

Terzaghi's column: a layer of height H on an impermeable, fixed base between
smooth impermeable walls, drained at its top, loaded suddenly by q0.  With
the constrained modulus M and c_v = k M / gamma_w, the degree of
consolidation is U(T) = 1 - sum 2/M_m^2 exp(-M_m^2 T), M_m = pi (2m+1)/2,
T = c_v t / H^2 (the exact series), and just after the load the excess pore
pressure is q0 everywhere below the drained top.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay
from skfem import MeshTri

import skfem_npfem as npfem

E, NU, Q0, GRAVITY, RHO_W = 1e7, 0.3, 1e4, 10.0, 1000.0
M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))
K = RHO_W * GRAVITY / M  # c_v = k M / gamma_w = 1 m^2/s, so T = t


def exact_u(T: np.ndarray) -> np.ndarray:
    m = np.arange(200)
    mm = np.pi * (2 * m + 1) / 2
    return 1 - np.sum(2 / mm**2 * np.exp(-np.outer(T, mm**2)), axis=1)


def _column(nx: int, ny: int, delaunay: bool) -> MeshTri:
    width = nx / ny
    mesh = MeshTri.init_tensor(np.linspace(0, width, nx + 1), np.linspace(0, 1, ny + 1))
    if not delaunay:
        return mesh
    x = mesh.p.T.copy()
    inner = (x[:, 0] > 0) & (x[:, 0] < width - 1e-12) & (x[:, 1] > 0)
    inner &= x[:, 1] < 1 - 1e-12
    rng = np.random.default_rng(1)
    x[inner] += rng.uniform(-0.3, 0.3, (inner.sum(), 2)) / ny
    return MeshTri(x.T, Delaunay(x).simplices.T)


def _consolidate(mesh, dts, projection=1.0, drainage="coupled", k=K, storage=0.0):
    x = mesh.p.T
    width = x[:, 0].max()
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = x[:, 1] < 1e-12
    fixed[:, 0] = (x[:, 0] < 1e-12) | (x[:, 0] > width - 1e-12) | fixed[:, 1]
    top = x[:, 1] > 1 - 1e-12
    loads = npfem.surface_load(x, top, Q0)
    soil = npfem.LinearElastic(E=E, nu=NU, rho=1e-9)  # weightless
    kwargs = {"permeability": k} if drainage == "coupled" else {}
    water = npfem.Water(
        drainage, None, rho_w=RHO_W, projection=projection, storage=storage, **kwargs
    )
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
    state, history = None, []
    for dt in dts:
        p, step = npfem.advance(p, model, dt, mesh, start=state)
        state = step.state
        settlement = -np.sum(loads[:, 1] * p.u[:, 1]) / np.sum(loads[:, 1])
        history.append((state.time, settlement / (Q0 / M), p, step))
    return top, history


@pytest.mark.parametrize("delaunay", [False, True])
def test_degree_of_consolidation_follows_terzaghi(delaunay):
    dts = [1e-3] * 50 + [1e-2] * 95
    _, history = _consolidate(_column(4, 20, delaunay), dts)
    times = np.array([0.05, 0.1, 0.2, 0.5, 1.0])
    got = {round(t, 9): u for t, u, _, _ in history}
    u = np.array([got[round(t, 9)] for t in times])
    assert np.abs(u - exact_u(times)).max() < 0.02


@pytest.mark.parametrize("delaunay", [False, True])
def test_first_step_pressure_has_no_oscillation_at_a_tiny_step(delaunay):
    # c_v dt / h^2 = 1e-4: the exact excess pore pressure is q0 below the
    # top to within 1e-3 of the height; equal-order nodal pressures
    # overshoot there without the pressure projection (to 2.3 q0 and below
    # zero on this lattice), and stay within [0, 1.15 q0] with it.
    mesh = _column(4, 20, delaunay)
    dt = 1e-4 * (1 / 20) ** 2
    top, history = _consolidate(mesh, [dt])
    p = history[0][2].excess_pore_pressure / Q0
    below = ~top
    assert p[below].max() < 1.15 and p[below].min() > 0.0
    volumes = history[0][3].operator.volumes
    mean = np.sum(p[below] * volumes[below]) / np.sum(volumes[below])
    assert mean == pytest.approx(1.0, abs=0.01)
    assert np.all(p[top] == 0.0)


def test_coupled_step_reduces_to_undrained_and_to_drained():
    mesh = _column(4, 20, False)
    # k -> 0: no flow, so every cell that is not drained keeps its volume,
    # which is the undrained step's constraint (the undrained mode itself
    # has no drained boundary at all); the column then barely settles.
    top, closed = _consolidate(mesh, [1.0], projection=0.0, k=1e-25)
    _, u, p, step = closed[0]
    strain = step.operator.strain(p.u)
    volumetric = strain[:, 0] + strain[:, 1]
    assert np.abs(volumetric[~top]).max() < 1e-9 * Q0 / M
    assert u < 0.05  # only the drained top cells give (O(h) of the layer)
    # k -> infinity (or a step much longer than H^2 / c_v): drained at once,
    # the oedometric settlement q0 H / M
    _, drained = _consolidate(mesh, [1e3])
    assert drained[0][1] == pytest.approx(1.0, abs=2e-3)
    assert np.abs(drained[0][2].excess_pore_pressure).max() < 1e-3 * Q0
