"""FEM-remap verified on its own (docs/verification.md, "The reference cases").

* The elastic column under self-weight (H = 10 m, E = 10 MPa, nu = 0.3,
  rho = 2000): P2 reproduces the exact linear stress and quadratic settlement
  (inside the space: round-off); gates 1 % (sigma_yy, rel. L2 at the Gauss
  points and at the recovered nodes) and 0.5 % (top settlement).  P1 is not
  exact: its error must fall at least linearly with h.
* The Prandtl footing, weightless Tresca soil, smooth
  footing, displacement control, the strip-footing scene's mesh: P2 within
  3 % of 2 + pi.  P1 elements lock (constant-strain triangles with isochoric
  plastic flow, Nagtegaal et al. 1974): the pressure overshoots 2 + pi by more
  than 10 % and keeps rising - asserted, so that a change that removes the
  locking shows up.
* Dynamic steps with remeshing: free fall is exact (v = g t with theta = 1,
  no stress); a block at rest on a rough floor stays at rest with the floor
  carrying the weight.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skfem_npfem.baseline import FemRemap
from skfem_npfem.boundary import floor
from skfem_npfem.materials import LinearElastic, MohrCoulomb
from skfem_npfem.mesh.smoothing import nodal_integration
from skfem_npfem.mesh.sources import AlphaShapeMesher
from skfem_npfem.particles import Particles
from skfem_npfem.scenes import get_scene
from skfem_npfem.step.model import Model

H, RHO, G, E, NU = 10.0, 2000.0, 9.81, 1.0e7, 0.3


def column(spacing: float):
    scene = get_scene("elastic-column")
    values = scene.resolve({"height": H, "spacing": spacing, "E": E, "nu": NU})
    sim = scene.build(values).simulation
    return sim.particles, sim.model, sim.mesh_source


def gauss_points(x, cells, element):
    from skfem_npfem.baseline.fem_nodes import gauss_points as points

    return points(x, cells, element)


def column_errors(element: str, spacing: float) -> dict[str, float]:
    p, model, mesh_source = column(spacing)
    method = FemRemap(element)
    state = method.initial_state(p, mesh_source)
    new, res = method.advance(state, model, 1.0, mesh_source)
    assert res.record.status == "Solved" and res.record.iterations == 0
    gp = gauss_points(p.x, new.cells, element)
    ex_gp = -RHO * G * (H - gp[:, 1])
    ex_n = -RHO * G * (H - p.x[:, 1])
    M = model.materials[0].p_wave_modulus
    top = np.isclose(p.x[:, 1], H)
    rel = np.linalg.norm
    return {
        "gp": rel(new.gp_stress[:, 1] - ex_gp) / rel(ex_gp),
        "nodal": rel(new.stress[:, 1] - ex_n) / rel(ex_n),
        "horizontal": rel(new.stress[:, 0] - NU / (1 - NU) * ex_n) / rel(ex_n),
        "settlement": -new.u[top, 1].mean() / (RHO * G * H**2 / (2 * M)) - 1,
    }


def test_p2_elastic_column_is_exact():
    err = column_errors("p2", 1.0)
    assert err["gp"] < 0.01 and err["nodal"] < 0.01 and err["horizontal"] < 0.01
    assert abs(err["settlement"]) < 0.005
    # The exact solution lies in the P2 space: round-off (measured 2e-12).
    assert max(abs(v) for v in err.values()) < 1e-9


def test_p1_elastic_column_converges():
    coarse, fine = column_errors("p1", 1.0), column_errors("p1", 0.5)
    # Measured: Gauss-point error 2.7e-2 -> 1.4e-2 (order 0.93).
    assert math.log2(coarse["gp"] / fine["gp"]) > 0.8
    assert fine["gp"] < 0.02
    assert abs(fine["settlement"]) < 0.005


def footing(element: str, spacing: float, steps: int) -> list[float]:
    scene = get_scene("strip-footing")
    values = scene.resolve({"spacing": spacing, "steps": steps})
    sim = scene.build(values).simulation
    p, model, mesh_source = sim.particles, sim.model, sim.mesh_source
    b = values["width"] / 2
    L = values["domain_width"] * b
    foot = np.isclose(p.x[:, 1], L) & (p.x[:, 0] <= b * (1 + 1e-9))
    method = FemRemap(element)
    state = method.initial_state(p, mesh_source)
    q = []
    for k in range(steps):  # equal settlement steps to 0.01 b (sim.dt each)
        state, res = method.advance(state, model, sim.dt, mesh_source, step=k + 1)
        q.append(-res.solution.reaction[foot, 1].sum() / b / values["c"])
    return q


def test_prandtl_footing_p2_within_three_percent():
    # 16 elements across the half-footing, the whole settlement (0.01 b) in
    # one static step: measured q/c = 5.2245 (+1.61 %); 8 elements: +3.11 %.
    q = footing("p2", 0.0625, 1)
    assert abs(q[-1] / (2 + math.pi) - 1) < 0.03


def test_prandtl_footing_p1_locks():
    # Constant-strain triangles lock under isochoric (Tresca) flow: measured
    # q/c = 5.37, 6.01, 6.23, 6.39 over 4 steps to 0.01 b (+24 % and rising),
    # where N-PFEM gives 5.1614 (+0.39 %) on the same mesh.
    q = footing("p1", 0.125, 4)
    assert q[-1] > 1.10 * (2 + math.pi)
    assert q[-1] > 1.01 * q[-2]


@pytest.mark.slow
def test_prandtl_footing_p2_converges_from_above():
    # Measured (8 steps to 0.01 b): 5.4495, 5.3027, then 5.2249 (2 steps).
    qs = [footing("p2", h, 2)[-1] for h in (0.25, 0.125, 0.0625)]
    assert qs[0] > qs[1] > qs[2] > 2 + math.pi
    assert abs(qs[2] / (2 + math.pi) - 1) < 0.02


def block(n: int = 6, h: float = 0.1, n_walls: int = 0, stress: bool = False):
    g = np.arange(n + 1) * h
    x = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    mesher = AlphaShapeMesher(h=h, alpha=1.3)
    _active, t = mesher(x)
    from skfem import MeshTri

    ni = nodal_integration(MeshTri(x.T.copy(), t))
    sig = None
    if stress:
        sig = np.zeros((x.shape[0], 4))
        sig[:, 1] = -RHO * G * (n * h - x[:, 1])
        sig[:, 0] = sig[:, 2] = 0.5 * sig[:, 1]
    p = Particles.create(x, RHO * ni.volumes, stress=sig, n_walls=n_walls)
    return p, mesher


@pytest.mark.parametrize("element", ["p1", "p2"])
def test_free_fall_is_exact_with_remeshing(element):
    p, mesher = block()
    model = Model(dim=2, materials=[LinearElastic(E, NU, RHO)], gravity=G)
    method = FemRemap(element, "nearest")
    state = method.initial_state(p, mesher)
    dt = 0.01
    for k in range(5):
        state, _ = method.advance(state, model, dt, mesher, step=k + 1)
    # Backward Euler (theta = 1): v = n g dt exactly; no stress (1e-9 rho g h).
    assert np.allclose(state.v[:, 1], -5 * G * dt, rtol=1e-9, atol=0)
    assert np.allclose(state.v[:, 0], 0.0, atol=1e-12)
    assert np.max(np.abs(state.gp_stress)) < 1e-9 * RHO * G * 0.1


# Floor force / weight - 1 and max |v| / (g dt) after 10 steps: P1 measured
# 7e-13 and 7e-10 (as N-PFEM); P2 7e-4 and 2.7e-3: dynamic P2 steps load the
# lumped weight (exact free fall) while the initial stress is the exact
# geostatic one, so the body settles by micrometres towards the lumped-load
# equilibrium, which flips lattice diagonals: from step 2 on it is remapped
# every step, and each transfer disturbs the equilibrium again.
REST_TOL = {"p1": (1e-6, 1e-7), "p2": (5e-3, 5e-3)}


@pytest.mark.parametrize("element", ["p1", "p2"])
def test_block_at_rest_on_a_rough_floor(element):
    # A free-standing elastic-range block (sigma_yy geostatic, sigma_xx = 0,
    # an exact equilibrium) on a floor with Coulomb friction (lagged floor
    # forces initialised to the weight per base particle): after 10 dynamic
    # steps with remeshing it is at rest and the floor carries the weight.
    p, mesher = block(n_walls=1, stress=True)
    p = p.replace(stress=p.stress * np.array([0.0, 1.0, 0.0, 0.0]))
    base = np.isclose(p.x[:, 1], 0.0)
    weight = p.mass.sum() * G
    wf = np.zeros((p.n, 1))
    wf[base, 0] = weight / base.sum()
    p = p.replace(wall_force=wf)
    mat = MohrCoulomb(E, NU, RHO, c=1e5, phi=30.0, psi=0.0, tension_cutoff=True)
    model = Model(
        dim=2, materials=[mat], gravity=G, walls=[floor(2, friction_angle=30.0)]
    )
    method = FemRemap(element, "recovery")
    state = method.initial_state(p, mesher)
    dt = 0.01
    for k in range(10):
        state, _ = method.advance(state, model, dt, mesher, step=k + 1)
    tol_f, tol_v = REST_TOL[element]
    assert abs(state.wall_force.sum() / weight - 1) < tol_f
    assert np.max(np.abs(state.v)) < tol_v * G * dt
    assert np.max(state.gp_eps_p) < 1e-9


def test_mapped_stresses_outside_the_cone_are_returned_and_counted():
    # Tresca stresses on the yield surface (R = c) with a direction that turns
    # across the body: recovery fits and interpolates them, and near the
    # boundary the fitted planes overshoot the cone.  Every mapped stress with
    # R > c must come back to R = c (1e-12); those returned by more than 1e-6
    # of the largest stress are counted (every one outside by 1e-4 c, none
    # inside); the others must be the transferred values unchanged.
    from skfem_npfem.baseline.transfer import transfer_values
    from skfem_npfem.materials import Tresca

    c = 1.0e4
    p, _ = block(n=8, h=0.125)
    model = Model(dim=2, materials=[Tresca(E, NU, RHO, c=c)])
    method = FemRemap("p2", "recovery")
    state = method.initial_state(p, AlphaShapeMesher(h=0.125, seed=0))
    gp = gauss_points(state.x, state.cells, "p2")
    angle = 3.0 * gp[:, 0] ** 2 + 2.0 * gp[:, 1]
    sig = np.zeros((gp.shape[0], 4))
    sig[:, 0] = -2 * c + c * np.cos(angle)
    sig[:, 1] = -2 * c - c * np.cos(angle)
    sig[:, 2] = -2 * c
    sig[:, 3] = c * np.sin(angle)
    state = state.replace(gp_stress=sig)
    act, loc = AlphaShapeMesher(h=0.125, seed=7)(state.x)
    cells = np.ascontiguousarray(act[loc].T)
    moved, _, info = method.remap(state, cells, model)
    raw, _ = transfer_values(
        "recovery", state.x, state.cells, gp, sig, gauss_points(state.x, cells, "p2")
    )
    R_raw = np.hypot(0.5 * (raw[:, 0] - raw[:, 1]), raw[:, 3])
    outside = R_raw > c * (1 + 1e-12)
    clearly = R_raw > c * (1 + 1e-4)
    assert info["remapped"] and clearly.sum() > 0
    assert clearly.sum() <= info["yield_violations"] <= outside.sum()
    R = np.hypot(0.5 * (moved[:, 0] - moved[:, 1]), moved[:, 3])
    assert np.all(R <= c * (1 + 1e-12))
    assert np.allclose(R[outside], c, rtol=1e-12)
    assert np.array_equal(moved[~outside], raw[~outside])


@pytest.mark.slow
def test_recovery_transfer_stays_bounded_in_the_collapse():
    # The a = 2 collapse at L0/12 with FEM-remap P1 and recovery transfer:
    # with ill-conditioned patch fits accepted (eigenvalue ratio 1e-8) a thin
    # element at the wall grew its stress to 1e5 rho g H0 by t = 0.6 s and the
    # body exploded.  Now it comes to rest (at 0.76 s) with the largest
    # Gauss-point stress within 5 rho g H0 (measured 3.7: the corner at the
    # wall and the floor, where recovery extrapolates), the area kept within
    # 10 % (measured -0.2 %) and the run-out in the band of the experiments
    # and continuum codes, 2.0-4.4 (measured 3.03; N-PFEM 3.37).
    scene = get_scene("column-collapse")
    values = scene.resolve(
        {"spacing": 0.2 / 12, "method": "fem-remap", "element": "p1"}
    )
    srun = scene.build(values)
    sim, peaks = srun.simulation, []
    sim.callbacks.append(lambda s, p, r: peaks.append(np.abs(p.gp_stress).max()))
    sim.run(**srun.run_kwargs)
    m = srun.metrics(sim)
    assert m["at_rest"] and abs(m["volume_change"]) < 0.1
    assert max(peaks) < 5 * 1800 * 9.81 * 0.4
    assert 2.0 < m["normalised_runout"] < 4.4
