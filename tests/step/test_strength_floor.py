"""``SolverOptions(strength_floor=...)``: tiny yield strengths raised to a floor.

References: the definition (``k >= floor * max k`` per cone, other strengths
untouched), bit-identity when the floor does not bind, and the closed-form
Drucker-Prager return of a uniformly strained body (the same gate as without
the floor).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from skfem import MeshTri

from skfem_npfem import (
    ConeInput,
    Contacts,
    DruckerPrager,
    ParameterError,
    SolverOptions,
    nodal_integration,
    solve_step,
)
from skfem_npfem.step.program import Program


def uniform_step(mesh, mat, sigma_n, du):
    n = mesh.p.shape[1]
    return ConeInput(
        operator=nodal_integration(mesh, (0, 1, 2, 3)),
        materials=[mat],
        material=np.zeros(n, int),
        sigma_n=sigma_n,
        force=np.zeros((n, 2)),
        fixed=np.ones((n, 2), bool),
        du_prescribed=du,
        contacts=Contacts.empty(2),
    )


@pytest.mark.parametrize("bad", [-1e-6, 1e-2, math.nan, True, "1e-6"])
def test_strength_floor_is_validated(bad):
    with pytest.raises(ParameterError, match="strength_floor"):
        SolverOptions(strength_floor=bad)


def test_floor_raises_only_the_strengths_below_it():
    # Cohesionless Drucker-Prager, psi = 0: k_i = alpha * (-I1_i) of the lagged
    # stress.  Stresses spanning 12 decades: after the floor 1e-6, k_i =
    # max(k_i, 1e-6 max k) exactly, the others bit-identical.
    mesh = MeshTri().refined(2)
    n = mesh.p.shape[1]
    p = np.logspace(-8.05, 4.0, n)  # no stress exactly at the floor
    sigma = np.zeros((n, 4))
    sigma[:, :3] = -p[:, None]
    mat = DruckerPrager(1e7, 0.3, phi=30.0, psi=0.0, match="plane-strain")
    data = uniform_step(mesh, mat, sigma, np.zeros((n, 2)))
    k0 = Program(data).yield_cones[0][1].k
    k1 = Program(data, 1e-6).yield_cones[0][1].k
    floor = 1e-6 * k0.max()
    assert np.array_equal(k1, np.maximum(k0, floor))
    assert np.sum(k0 < floor) == np.sum(p < 1e-6 * p.max()) > 0
    assert np.array_equal(k1[k0 >= floor], k0[k0 >= floor])


@pytest.mark.parametrize("factor", [0.5, 10.0])
def test_floor_keeps_the_closed_form_return(factor):
    # A uniform strain increment from a uniform stress inside the cone: every
    # node is the closed-form return (plane strain; the stress is far above
    # the floor, so the program is the same and the solution bit-identical).
    E, nu, c = 1e7, 0.3, 1e4
    mat = DruckerPrager(E, nu, c=c, phi=30.0, match="plane-strain")
    mesh = MeshTri().refined(3)
    n = mesh.p.shape[1]
    sig_n = np.tile([-5e4, -8e4, -6e4, 1e3], (n, 1))
    e = np.array([0.4e-3, -1.2e-3]) * factor
    du = mesh.p.T * e[None, :]
    data = uniform_step(mesh, mat, sig_n, du)
    a = solve_step(data, SolverOptions(linear_solver="qdldl"))
    b = solve_step(data, SolverOptions(linear_solver="qdldl", strength_floor=1e-6))
    assert np.array_equal(a.sigma, b.sigma) and a.iterations == b.iterations
    # Closed form: elastic trial, then the radial return of the plane-strain
    # DP cone (q + alpha I1 <= k, q = sqrt(J2)) when it is outside.
    G, K = E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))
    alpha, k = mat.alpha_k(30.0)
    trial = sig_n[0].copy()
    ev = e.sum()
    trial[:3] += K * ev + 2 * G * (np.array([e[0], e[1], 0.0]) - ev / 3)
    I1 = trial[:3].sum()
    s = trial[:3] - I1 / 3
    q = math.sqrt(0.5 * s @ s + trial[3] ** 2)
    f = q + alpha * I1 - k
    if f > 0:
        dlam = f / (G + 9 * K * alpha**2)
        scale = 1 - G * dlam / q
        s, tau, I1 = s * scale, trial[3] * scale, I1 - 9 * K * alpha * dlam
        trial = np.array([*(s + I1 / 3), tau])
    assert np.max(np.abs(b.sigma - trial[None])) < 5e-5 * c
