"""The element-residual stabilisation in axisymmetry: the hoop terms.

References: the divergence of a body of revolution (hoop terms
``(s_rr - s_tt)/r`` and ``s_rz/r``) applied to closed-form fields; the
geostatic (K0) state of an axisymmetric column, an exact solution of the step;
Lamé's thick-walled cylinder (equilibrium without body force), whose
element residual must vanish under refinement; and the equal-order
checkerboard of the nodal mean stress at nu = 0.4999 that
tests/mesh/test_axisymmetric.py measures (28 % without stabilisation).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import RHO, assert_exact_geostatic_step, jittered_section
from skfem import MeshTri

from skfem_npfem import ConeInput, Contacts, LinearElastic, solve_step
from skfem_npfem.mesh.axisymmetric import axisymmetric_integration
from skfem_npfem.step.conic import build_program
from skfem_npfem.step.stabilisation import element_residual, hoop_matrix

E, NU, GRAV = 1.0e7, 0.3, 9.81


def section(r0, r1, h, nr, nz, seed=0):
    """Structured (r, z) mesh of [r0, r1] x [0, h], interior nodes jittered."""
    return jittered_section(r0, r1, h, nr, nz, amount=0.2, seed=seed)


def step_data(mesh, sigma, force, fixed, beta, du=None, nu=NU):
    n = mesh.p.shape[1]
    return ConeInput(
        operator=axisymmetric_integration(mesh),
        materials=[LinearElastic(E, nu, RHO)],
        material=np.zeros(n, int),
        sigma_n=sigma,
        force=force,
        fixed=fixed,
        du_prescribed=np.zeros((n, 2)) if du is None else du,
        contacts=Contacts.empty(2),
        stabilisation=beta,
    )


def geostatic(n, beta):
    """Solid cylinder R = 1, H = 1: K0 state under self-weight, rollers."""
    mesh = section(0.0, 1.0, 1.0, n, n)
    r, z = mesh.p
    sig = np.zeros((r.size, 4))
    sig[:, 1] = -RHO * GRAV * (1.0 - z)
    sig[:, 0] = sig[:, 2] = NU / (1 - NU) * sig[:, 1]
    ni = axisymmetric_integration(mesh)
    force = np.zeros((r.size, 2))
    force[:, 1] = -RHO * GRAV * ni.volumes  # ring masses from the cells
    fixed = np.zeros((r.size, 2), bool)
    fixed[np.isclose(z, 0.0)] = True
    fixed[np.isclose(r, 0.0) | np.isclose(r, 1.0), 0] = True
    return step_data(mesh, sig, force, fixed, beta)


def lame_stress(r, a=1.0, b=2.0, p=1.0, nu=NU):
    """Lamé's stresses (rr, zz, tt, rz) of an internal pressure, plane strain."""
    A = p * a * a / (b * b - a * a)
    B = A * b * b
    return np.column_stack([A - B / r**2, 2 * nu * A + 0 * r, A + B / r**2, 0 * r])


def test_hoop_terms_complete_the_divergence_of_a_body_of_revolution():
    # Linear fields s_rr = 2r + z, s_tt = r - z, s_rz = 3z + r: the 2 pi r-
    # weighted element means of (s_rr - s_tt)/r and s_rz/r are the centroid
    # values over the centroid radius (exact for P1 data, to round-off), and
    # the centroid radius is the one recovered from the ring volume and area.
    mesh = section(0.5, 1.5, 1.0, 4, 4)
    r, z = mesh.p
    s = np.column_stack([2 * r + z, 0 * r, r - z, 3 * z + r])  # linear fields
    ni = axisymmetric_integration(mesh)
    rc = r[mesh.t].mean(axis=0)
    radius = ni.element_volumes / (2 * math.pi * ni.element_areas)
    H = hoop_matrix(mesh.t, radius, (0, 1, 2, 3))
    got = (H @ s.ravel()).reshape(-1, 2)
    sm = s[mesh.t].mean(axis=0)  # (ne, 4) vertex means = centroid values
    np.testing.assert_allclose(radius, rc, rtol=1e-12)
    np.testing.assert_allclose(got[:, 0], (sm[:, 0] - sm[:, 2]) / rc, rtol=1e-12)
    np.testing.assert_allclose(got[:, 1], sm[:, 3] / rc, rtol=1e-12)


def test_the_axisymmetric_geostatic_state_is_an_exact_solution():
    # sigma_rr = sigma_tt = K0 sigma_zz, linear in z, with ring loads from the
    # cells: zero element residual (1e-9 of rho g), and the stabilised static
    # step (beta = 30) keeps it: du below 1e-8 of the settlement scale
    # rho g H^2 / E = 2e-3 m, stresses to 1e-6 rho g H.
    assert_exact_geostatic_step(geostatic(4, beta=30.0))


def lame_penalty(n, with_hoop=True):
    """Penalty of Lamé's exact stresses relative to their elastic energy."""
    mesh = section(1.0, 2.0, 1.0, n, n, seed=3)
    s = lame_stress(mesh.p[0])
    n_nodes = s.shape[0]
    data = step_data(
        mesh, s, np.zeros((n_nodes, 2)), np.zeros((n_nodes, 2), bool), beta=1.0
    )
    prog, _ = build_program(data)
    _, c, w = element_residual(prog)
    if not with_hoop:
        ni = data.operator
        rc = ni.element_volumes / (2 * math.pi * ni.element_areas)
        c = c - hoop_matrix(mesh.t, rc, (0, 1, 2, 3)) @ s.ravel()
    energy = 0.5 * np.sum(data.operator.volumes * (s**2).sum(axis=1)) / (E / 2.6)
    return 0.5 * np.sum(w * c**2) / energy


def test_lame_stresses_have_a_residual_that_vanishes_with_h():
    # Lamé's field is in equilibrium only with its hoop terms.  With them, the
    # element residual of its P1 interpolant is O(h) and the penalty (weight
    # ~ h^2) O(h^4) relative to the elastic energy: 1/16 per halving of h
    # (measured 0.0637 and 0.0655; gate +-20 %).  Without them the residual is
    # the O(1) divergence 2B/r^3 alone: the penalty falls only with the weight,
    # 1/4 per halving (measured 0.254, 0.253), and is 1400x larger at n = 16.
    p8, p16, p32 = (lame_penalty(n) for n in (8, 16, 32))
    assert p16 / p8 == pytest.approx(1 / 16, rel=0.2)
    assert p32 / p16 == pytest.approx(1 / 16, rel=0.2)
    q8, q16 = (lame_penalty(n, with_hoop=False) for n in (8, 16))
    assert q16 / q8 == pytest.approx(0.25, rel=0.1)
    assert q16 > 100 * p16


def lame_displacement(nu, beta, n=16, a=1.0, b=2.0, ua=1e-3):
    """Thick cylinder, prescribed u_r = ua at r = a, free at r = b, eps_zz = 0."""
    hz = b - a
    mesh = MeshTri.init_tensor(np.linspace(a, b, n + 1), np.linspace(0, hz, n + 1))
    r, z = mesh.p
    N = r.size
    fixed = np.zeros((N, 2), bool)
    fixed[:, 1] = np.isclose(z, 0) | np.isclose(z, hz)
    inner = np.isclose(r, a)
    fixed[inner, 0] = True
    du = np.zeros((N, 2))
    du[inner, 0] = ua
    data = step_data(
        mesh, np.zeros((N, 4)), np.zeros((N, 2)), fixed, beta, du=du, nu=nu
    )
    sol = solve_step(data)
    # Pressure giving u_r(a) = ua: u_r = (1+nu)/E ((1-2nu) A r + B/r), A = p a^2
    # / (b^2 - a^2), B = A b^2.
    unit = (1 + nu) / E * ((1 - 2 * nu) * a + b * b / a) * a * a / (b * b - a * a)
    exact = lame_stress(r, a, b, ua / unit, nu)
    mean, mean_ex = sol.sigma[:, :3].mean(axis=1), exact[:, :3].mean(axis=1)
    dev, dev_ex = sol.sigma[:, 2] - sol.sigma[:, 0], exact[:, 2] - exact[:, 0]
    return (
        float(np.linalg.norm(mean - mean_ex) / np.linalg.norm(mean_ex)),
        float(np.linalg.norm(dev - dev_ex) / np.linalg.norm(dev_ex)),
    )


def test_stabilisation_removes_the_checkerboard_of_nearly_incompressible_lame():
    # nu = 0.4999: without stabilisation the nodal mean stress carries the
    # equal-order checkerboard; with beta = 30 (the plane-strain default) it
    # is 7.5x smaller while the deviatoric stress stays as accurate.  Measured
    # (16 x 16 mesh, relative L2 over the nodes): mean 0.293 -> 0.039, deviator
    # s_tt - s_rr 0.0183 -> 0.0195.
    m0, d0 = lame_displacement(0.4999, 0.0)
    m1, d1 = lame_displacement(0.4999, 30.0)
    assert m1 < 0.2 * m0
    assert d1 < 1.5 * d0


def test_the_axisymmetric_seed_collapse_runs_stabilised_and_smoother():
    # The seed column in axisymmetry at r0/8 (153 particles), 50 steps of
    # 2 ms: the scene passes beta through, mass stays exact, and the stress
    # roughness of the reference measure falls (measured R at t = 0.1 s: 0.377
    # without, 0.066 with beta = 30; max 0.464 / 0.073) while the front moves
    # alike (run-out 0.611 / 0.620 r0).
    from skfem_npfem import run_scene

    def run(beta):
        over = {
            "geometry": "axisymmetric",
            "spacing": 0.039 / 8,
            "t_end": 0.1,
            "rest_fraction": 0.0,
            "stabilisation": beta,
            "threads": 1,
        }
        return run_scene("column-collapse", over)

    plain, stab = run(0.0), run(30.0)
    assert stab["parameters"]["stabilisation"] == 30.0
    assert stab["metrics"]["mass_change"] == 0.0
    assert (
        stab["metrics"]["stress_roughness"] < 0.5 * plain["metrics"]["stress_roughness"]
    )
    assert stab["metrics"]["stress_roughness_max"] < 0.15
    runout = plain["metrics"]["normalised_runout"]
    assert stab["metrics"]["normalised_runout"] == pytest.approx(runout, rel=0.05)


def test_the_axisymmetric_seed_column_is_smooth_and_keeps_its_volume_by_default():
    # The seed column in axisymmetry at its defaults (stabilisation beta = 100,
    # volume correction kappa = 0.05; docs/seed_column.md) at r0/8 (153
    # particles), to rest.  Targets of the default spacing r0/18: stress
    # roughness R <= 0.10 at every output step, volume within 3 % at rest
    # (measured there: R max 0.081, volume +0.4 %).  At r0/8 the measure's
    # floor is higher (about 50 interior particles, an irregular coarse
    # lattice), so the tolerance on R max is doubled, 0.20; R at rest keeps
    # 0.10.  Measured here: R max 0.188, at rest 0.085, volume -2.2 %; with
    # --set stabilisation=0 --set volume_correction=0: R max 0.554, at rest 0.244.
    from skfem_npfem import run_scene

    res = run_scene(
        "column-collapse",
        {"geometry": "axisymmetric", "spacing": 0.039 / 8, "threads": 1},
    )
    m = res["metrics"]
    assert m["at_rest"]
    assert m["stress_roughness_max"] <= 0.20
    assert m["stress_roughness"] <= 0.10
    assert abs(m["volume_change"]) <= 0.03
    assert m["mass_change"] == 0.0
