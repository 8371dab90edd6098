"""The Clarabel step: duals vs a direct solve, cone algebra, returns, errors.

References: docs/theory.md, "The mixed step", "The displacement from the duals"
and "Scaling" (Δu = -z_eq, reactions, scaling; the cones; elastic programs take 0
IPM iterations), "Non-associated flow: frozen friction"; docs/verification.md,
"The reference cases" (cone algebra, single-point return, simple shear).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from skfem import MeshTet, MeshTri

from skfem_npfem import (
    ConeInput,
    Contacts,
    DruckerPrager,
    LinearElastic,
    Model,
    MohrCoulomb,
    ParameterError,
    Particles,
    SolverError,
    SolverOptions,
    Tresca,
    VonMises,
    solve_step,
)
from skfem_npfem.materials import compliance_matrix
from skfem_npfem.mesh.smoothing import nodal_integration

E, NU, RHO, GRAV = 1.0e7, 0.3, 2000.0, 9.81
C_COH = 1.0e4
SHEAR_MOD = E / (2 * (1 + NU))
LAME = E * NU / ((1 + NU) * (1 - 2 * NU))
BULK = E / (3 * (1 - 2 * NU))


# ----------------------------------------------------------------- helpers ----
def jittered_block(dim: int, n: int = 5, size=(2.0, 1.0, 1.0), seed: int = 0):
    """Structured block [0,Lx]x[0,Ly](x[0,Lz]) with interior nodes jittered."""
    rng = np.random.default_rng(seed)
    axes = [np.linspace(0.0, size[k], n if k else 2 * n - 1) for k in range(dim)]
    m = MeshTri.init_tensor(*axes) if dim == 2 else MeshTet.init_tensor(*axes)
    p = m.p.copy()
    h = min(size[k] / (len(axes[k]) - 1) for k in range(dim))
    interior = np.setdiff1d(np.arange(p.shape[1]), m.boundary_nodes())
    p[:, interior] += 0.25 * h * rng.uniform(-1, 1, (dim, interior.size))
    return (MeshTri if dim == 2 else MeshTet)(p, m.t)


def step_data(mesh, mat, comps, *, fixed, du=None, force=None, sigma_n=None, **kw):
    d, n = mesh.dim(), mesh.p.shape[1]
    nfull = 4 if d == 2 else 6
    return ConeInput(
        operator=nodal_integration(mesh, comps),
        materials=[mat],
        material=np.zeros(n, int),
        sigma_n=np.zeros((n, nfull)) if sigma_n is None else sigma_n,
        force=np.zeros((n, d)) if force is None else force,
        fixed=fixed,
        du_prescribed=np.zeros((n, d)) if du is None else du,
        contacts=Contacts.empty(d),
        **kw,
    )


def assert_finite(sol):
    for arr in (sol.du, sol.sigma, sol.deps_p, sol.reaction):
        assert np.all(np.isfinite(arr))


def direct_stiffness(ni, mat, comps):
    """K = G (V^-1 ⊗ D) G^T, built densely and independently of conic.py."""
    D = np.linalg.inv(compliance_matrix(mat.E, mat.nu, ni.dim, comps))
    G = ni.G.toarray()
    ns = len(comps)
    Dblk = np.zeros((G.shape[1], G.shape[1]))
    for i, V in enumerate(ni.volumes):
        Dblk[i * ns : (i + 1) * ns, i * ns : (i + 1) * ns] = D / V
    return G @ Dblk @ G.T, D


def gravity_block(dim, comps, prescribe_top: bool):
    mesh = jittered_block(dim, n=4)
    mat = LinearElastic(E, NU, RHO)
    ni = nodal_integration(mesh, comps)
    n = mesh.p.shape[1]
    x = mesh.p.T
    force = np.zeros((n, dim))
    force[:, -1] = -RHO * GRAV * ni.volumes
    fixed = np.zeros((n, dim), bool)
    fixed[np.isclose(x[:, -1], 0.0)] = True
    du = np.zeros((n, dim))
    if prescribe_top:
        top = np.isclose(x[:, -1], x[:, -1].max())
        fixed[top, -1] = True
        du[top, -1] = -2e-4
        du[top, 0] = 5e-5  # ignored: x dof of the top nodes stays free
    data = step_data(mesh, mat, comps, fixed=fixed, du=du, force=force)
    return data, mat


# ----------------------------------------------- (a) duals vs direct solve ----
@pytest.mark.parametrize(
    ("dim", "comps"),
    [(2, (0, 1, 3)), (2, (0, 1, 2, 3)), (3, (0, 1, 2, 3, 4, 5))],
)
@pytest.mark.parametrize("prescribe_top", [False, True])
def test_duals_equal_direct_displacement_solve(dim, comps, prescribe_top):
    data, mat = gravity_block(dim, comps, prescribe_top)
    sol = solve_step(data)
    assert_finite(sol)
    K, D = direct_stiffness(data.operator, mat, comps)
    f = data.force.ravel()
    fix = data.fixed.ravel()
    F, P = np.flatnonzero(~fix), np.flatnonzero(fix)
    u = np.zeros(f.size)
    u[P] = data.du_prescribed.ravel()[P]
    # Condensed direct solve K_FF u_F = f_F - K_FP u_P.
    u[F] = np.linalg.solve(K[np.ix_(F, F)], f[F] - K[np.ix_(F, P)] @ u[P])
    # Δu from the equilibrium duals vs the direct solve (1e-8 relative).
    assert np.linalg.norm(sol.du.ravel() - u) < 1e-8 * np.linalg.norm(u)
    # Stresses sigma_i = D Bbar_i u (1e-8 relative).
    sig = data.operator.strain(u) @ D.T
    s_lib = sol.sigma[:, list(comps)]
    assert np.linalg.norm(s_lib - sig) < 1e-8 * np.linalg.norm(sig)
    # Reactions on prescribed dofs equal K u - f there (1e-8 relative).
    R = K @ u - f
    assert np.linalg.norm(sol.reaction.ravel()[P] - R[P]) < 1e-8 * np.linalg.norm(R[P])
    assert np.all(sol.reaction.ravel()[F] == 0.0)
    # Global equilibrium: reactions carry the whole weight (1e-8 relative).
    W = RHO * GRAV * data.operator.volumes.sum()
    assert abs(sol.reaction[:, -1].sum() - W) < 1e-8 * W


def test_dynamic_theta_step_equals_direct_solve():
    # θ1 = θ2 = ½ with nonzero σ_n and v_n.  With σ = σ_n + D Bbar Δu and
    # r = M~ Δu/Δt², the equilibrium G σ + r = f~ (docs/theory.md) reads
    # (K + M~/Δt²) Δu = f/θ1 + M~ v_n/Δt - G σ_n/θ1,  M~ = M/(θ1θ2)
    # (G σ_n from σ plus ((1-θ1)/θ1) G σ_n from f~).
    dim, comps = 2, (0, 1, 3)
    mesh = jittered_block(dim, n=4, seed=5)
    mat = LinearElastic(E, NU, RHO)
    rng = np.random.default_rng(6)
    n = mesh.p.shape[1]
    ni = nodal_integration(mesh, comps)
    mass = RHO * ni.volumes
    force = np.zeros((n, dim))
    force[:, 1] = -GRAV * mass
    fixed = np.zeros((n, dim), bool)
    fixed[np.isclose(mesh.p[1], 0.0)] = True
    sigma_n = np.zeros((n, 4))
    sigma_n[:, [0, 1, 3]] = 1e4 * rng.normal(size=(n, 3))
    v_n = 1e-2 * rng.normal(size=(n, dim))
    dt, th1, th2 = 2e-3, 0.5, 0.5
    data = step_data(
        mesh,
        mat,
        comps,
        fixed=fixed,
        force=force,
        sigma_n=sigma_n,
        dynamic=True,
        dt=dt,
        mass=mass,
        v_n=v_n,
        theta1=th1,
        theta2=th2,
    )
    sol = solve_step(data)
    assert_finite(sol)
    K, D = direct_stiffness(ni, mat, comps)
    mt = np.repeat(mass, dim) / (th1 * th2)
    rhs = force.ravel() / th1 + mt * v_n.ravel() / dt
    rhs -= ni.G.toarray() @ sigma_n[:, list(comps)].ravel() / th1
    F = np.flatnonzero(~fixed.ravel())
    u = np.zeros(n * dim)
    A = K + np.diag(mt / dt**2)
    u[F] = np.linalg.solve(A[np.ix_(F, F)], rhs[F])
    # Relative 1e-8 against the independent dense solve.
    assert np.linalg.norm(sol.du.ravel() - u) < 1e-8 * np.linalg.norm(u)
    sig = sigma_n[:, list(comps)] + ni.strain(u) @ D.T
    assert np.linalg.norm(sol.sigma[:, list(comps)] - sig) < 1e-8 * np.linalg.norm(sig)


# ---------------------------------------- (b) elastic program, (c) scaling ----
def test_elastic_program_has_only_equilibrium_rows_and_zero_iterations():
    data, _ = gravity_block(2, (0, 1, 3), prescribe_top=False)
    sol = solve_step(data)
    n_free = int((~data.fixed).sum())
    # Only the zero cone of the free-dof equilibrium rows (no SOC, no cut-off).
    assert sol.sizes["rows"] == n_free
    assert sol.sizes["variables"] == 3 * data.operator.n_nodes
    # Elastic-only programs are one KKT solve: 0 IPM iterations.
    assert sol.iterations == 0
    assert sol.status == "Solved"


@pytest.mark.parametrize("prescribe_top", [False, True])
def test_scaling_does_not_change_the_answer(prescribe_top):
    data, _ = gravity_block(2, (0, 1, 3), prescribe_top)
    on = solve_step(data, SolverOptions(scaling=True))
    off = solve_step(data, SolverOptions(scaling=False))
    assert_finite(off)
    # Same answer with and without non-dimensionalisation (1e-6 relative).
    assert np.linalg.norm(on.du - off.du) < 1e-6 * np.linalg.norm(on.du)
    assert np.linalg.norm(on.sigma - off.sigma) < 1e-6 * np.linalg.norm(on.sigma)


# -------------------------------------------------------- (d) cone algebra ----
def cone_residual(mat, dim, comps, sigma_full, sigma_n=None):
    """(k - a^T s - ||M s||) / k for one stress point, via material.cone()."""
    sigma_full = np.atleast_2d(sigma_full)
    sn = sigma_full if sigma_n is None else np.atleast_2d(sigma_n)
    rows = mat.cone(dim, comps, sn)
    s = sigma_full[0, list(comps)]
    k = float(rows.k[0])
    return (k - rows.a[0] @ s - np.linalg.norm(rows.M @ s)) / k


def in_plane(s1, s3, angle):
    """Voigt (xx, yy, zz=0, xy) of in-plane principal stresses rotated by angle."""
    c, s = math.cos(angle), math.sin(angle)
    Q = np.array([[c, -s], [s, c]])
    T = Q @ np.diag([s1, s3]) @ Q.T
    return np.array([T[0, 0], T[1, 1], 0.0, T[0, 1]])


def rotated_voigt3(principal, seed):
    """3D full Voigt of diag(principal) under a random rotation."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    T = Q @ np.diag(principal) @ Q.T
    return np.array([T[0, 0], T[1, 1], T[2, 2], T[0, 1], T[1, 2], T[2, 0]])


@pytest.mark.parametrize("phi", [0.0, 20.0, 30.0])
@pytest.mark.parametrize("p3", [0.0, 3.0e4, 2.0e5])  # minor compression magnitude
@pytest.mark.parametrize("angle", [0.0, 0.4, 2.0])
def test_mohr_coulomb_and_tresca_biaxial_peak_on_cone(phi, p3, angle):
    f = math.radians(phi)
    N = (1 + math.sin(f)) / (1 - math.sin(f))
    p1 = N * p3 + 2 * C_COH * math.sqrt(N)  # |σ1| = N|σ3| + 2c√N
    sig = in_plane(-p3, -p1, angle)
    mat = Tresca(E, NU, c=C_COH) if phi == 0 else MohrCoulomb(E, NU, c=C_COH, phi=phi)
    # Point on the analytic surface makes the cone active (1e-12 relative to k).
    assert abs(cone_residual(mat, 2, (0, 1, 3), sig)) < 1e-12
    # A point 1 % inside the surface is strictly inside the cone.
    assert cone_residual(mat, 2, (0, 1, 3), in_plane(-p3, -0.99 * p1, angle)) > 1e-4


@pytest.mark.parametrize("phi", [0.0, 20.0, 30.0])
@pytest.mark.parametrize("angle", [0.0, 0.7])
def test_drucker_prager_plane_strain_match_reproduces_mc_peak(phi, angle):
    # At the plane-strain flow value of σ_zz (ε^p_zz = 0 ⇒ s_zz = -2α√J2, i.e.
    # σ_zz = p_m - 3α√J2 with √J2 = R/√(1-3α²)), the plane-strain DP match passes
    # through the MC biaxial peak |σ1| = N|σ3| + 2c√N.
    f = math.radians(phi)
    N = (1 + math.sin(f)) / (1 - math.sin(f))
    p3 = 5.0e4
    p1 = N * p3 + 2 * C_COH * math.sqrt(N)
    sig = in_plane(-p3, -p1, angle)
    t = math.tan(f)
    alpha = t / math.sqrt(9 + 12 * t * t)  # the plane-strain match
    R = (p1 - p3) / 2
    pm = -(p1 + p3) / 2
    sig[2] = pm - 3 * alpha * R / math.sqrt(1 - 3 * alpha**2)
    mat = DruckerPrager(E, NU, c=C_COH, phi=phi, match="plane-strain")
    assert abs(cone_residual(mat, 2, (0, 1, 2, 3), sig)) < 1e-12
    # Independent check of the same point: √J2 + α I1 = k (1e-12 relative).
    T = np.array([[sig[0], sig[3], 0], [sig[3], sig[1], 0], [0, 0, sig[2]]])
    s = T - np.trace(T) / 3 * np.eye(3)
    k = 3 * C_COH / math.sqrt(9 + 12 * t * t)
    assert abs(math.sqrt(0.5 * np.sum(s * s)) + alpha * np.trace(T) - k) < 1e-12 * k


@pytest.mark.parametrize("match", ["compression", "extension"])
@pytest.mark.parametrize("phi", [20.0, 35.0])
def test_drucker_prager_3d_triaxial_match(match, phi):
    # Compression cone touches MC where σ1 = σ2 > σ3 (σ3 = N σ1 - 2c√N);
    # extension cone where σ1 > σ2 = σ3 (σ2 = σ3 = N σ1 - 2c√N); tension +.
    f = math.radians(phi)
    N = (1 + math.sin(f)) / (1 - math.sin(f))
    mat = DruckerPrager(E, NU, c=C_COH, phi=phi, match=match)
    for sig1 in (0.0, -4.0e4, -3.0e5):
        sig3 = N * sig1 - 2 * C_COH * math.sqrt(N)
        principal = [sig1, sig1, sig3] if match == "compression" else [sig1, sig3, sig3]
        for seed in range(3):  # random rotations exercise the shear rows
            sig = rotated_voigt3(principal, seed)
            assert abs(cone_residual(mat, 3, tuple(range(6)), sig)) < 1e-12


@pytest.mark.parametrize("dim", [2, 3])
def test_von_mises_and_generic_drucker_prager_on_surface(dim):
    rng = np.random.default_rng(7)
    comps = (0, 1, 2, 3) if dim == 2 else tuple(range(6))
    sy = math.sqrt(3) * C_COH
    vm = VonMises(E, NU, sigma_y=sy)
    dp = DruckerPrager(E, NU, c=C_COH, phi=25.0, match="compression")
    alpha, k_dp = dp.alpha_k(25.0)
    for _ in range(5):
        T = rng.normal(size=(3, 3))
        T = T + T.T
        if dim == 2:
            T[0, 2] = T[2, 0] = T[1, 2] = T[2, 1] = 0.0
        s = T - np.trace(T) / 3 * np.eye(3)
        q = math.sqrt(0.5 * np.sum(s * s))  # √J2 from the tensor
        # von Mises: deviator scaled to √J2 = σ_y/√3, any pressure.
        Tvm = s * (sy / math.sqrt(3) / q) + 1e5 * rng.normal() * np.eye(3)
        # Drucker-Prager: deviator with √J2 = q_dp, I1 from √J2 + α I1 = k.
        q_dp = 0.5 * k_dp
        Tdp = s * (q_dp / q) + (k_dp - q_dp) / (3 * alpha) * np.eye(3)
        for mat, TT in ((vm, Tvm), (dp, Tdp)):
            v = np.array([TT[0, 0], TT[1, 1], TT[2, 2], TT[0, 1], TT[1, 2], TT[2, 0]])
            v = v[: 4 if dim == 2 else 6]
            assert abs(cone_residual(mat, dim, comps, v)) < 1e-12


@pytest.mark.parametrize("cls", [MohrCoulomb, DruckerPrager])
def test_frozen_friction_strength(cls):
    phi, psi = 30.0, 5.0
    mat = cls(E, NU, c=C_COH, phi=phi, psi=psi)
    assoc = cls(E, NU, c=C_COH, phi=phi)
    comps = (0, 1, 3) if cls is MohrCoulomb else (0, 1, 2, 3)
    rng = np.random.default_rng(8)
    sig_n = np.zeros((6, 4))
    sig_n[:, :3] = -1e5 * rng.uniform(0.2, 2.0, (6, 3))
    sig_n[:, 3] = 2e4 * rng.normal(size=6)
    sig_n[-1, :3] = 3e5  # strong tension: the strength clamps at zero
    rows = mat.cone(2, comps, sig_n)
    ref = assoc.cone(2, comps, sig_n)
    a_phi, a_psi = ref.a[0], rows.a[0]
    k0 = float(ref.k[0])
    s = sig_n[:, list(comps)]
    # k_i = max(k - (a_φ - a_ψ)^T σ_n, 0) (1e-12 relative).
    k_exp = np.maximum(k0 - s @ (a_phi - a_psi), 0.0)
    assert np.allclose(rows.k, k_exp, rtol=1e-12, atol=0)
    assert rows.k[-1] == 0.0
    # At σ = σ_n the lagged cone has the true (φ) criterion: k_i - a_ψ^T σ_n
    # equals k - a_φ^T σ_n wherever no clamp is active (1e-12 relative).
    lhs = rows.k[:-1] - s[:-1] @ a_psi
    rhs = k0 - s[:-1] @ a_phi
    assert np.allclose(lhs, rhs, rtol=1e-12, atol=0)
    # a_ψ is the dilation-angle vector: sinψ (1,1,0) for MC (exact to 1e-15).
    if cls is MohrCoulomb:
        assert np.allclose(a_psi, math.sin(math.radians(psi)) * np.array([1, 1, 0]))


# -------------------------- (e) uniform-strain returns and simple shear ----
def uniform_strain_step(mesh, mat, comps, grad, sigma_n_row, options=None, step=None):
    """All boundary nodes follow u = grad·x; interior nodes are free."""
    d, n = mesh.dim(), mesh.p.shape[1]
    fixed = np.zeros((n, d), bool)
    fixed[mesh.boundary_nodes()] = True
    du = mesh.p.T @ np.asarray(grad).T
    sigma_n = np.tile(np.asarray(sigma_n_row, float), (n, 1))
    data = step_data(mesh, mat, comps, fixed=fixed, du=du, sigma_n=sigma_n)
    sol = solve_step(data, options, step=step)
    assert_finite(sol)
    return sol


def cell_volumes(mesh):
    return nodal_integration(mesh).volumes


PATCH_2D = jittered_block(2, n=5, size=(1.0, 1.0), seed=11)
SHEAR_MATERIALS = [
    ("tresca", lambda: Tresca(E, NU, c=C_COH), (0, 1, 3)),
    ("von-mises", lambda: VonMises(E, NU, sigma_y=math.sqrt(3) * C_COH), (0, 1, 2, 3)),
]


@pytest.mark.parametrize(("name", "make", "comps"), SHEAR_MATERIALS)
def test_simple_shear_elastic_then_exact_yield(name, make, comps):
    mat = make()
    gamma_y = C_COH / SHEAR_MOD
    grad = np.array([[0.0, 1.0], [0.0, 0.0]])  # u_x = γ y
    # Below yield: τ = G γ at every node (1e-6 relative).
    sol = uniform_strain_step(PATCH_2D, mat, comps, 0.5 * gamma_y * grad, np.zeros(4))
    assert np.allclose(sol.sigma[:, 3], 0.5 * C_COH, rtol=1e-6, atol=0)
    assert np.max(np.abs(sol.deps_p)) < 1e-6 * gamma_y
    # Past yield, in one step of 10 γ_y or in 8 steps: τ = c exactly (1e-6
    # relative).  The patch mean of the plastic shear is fixed by the boundary
    # values (Σ V_i Bbar_i u = ∫ ε(u)), so it equals 9 γ_y to 1e-6.  Normal
    # stresses and nodal plastic strains are accurate only to O(sqrt(tol)) along
    # the yield surface: measured 8.5e-5 c and 7.9e-5 relative at tol = 1e-8,
    # gates 3e-4.
    for n_steps in (1, 8):
        sig = np.zeros(4)
        gp = 0.0
        for k in range(n_steps):
            sol = uniform_strain_step(
                PATCH_2D, mat, comps, 10 * gamma_y / n_steps * grad, sig, step=k
            )
            sig = sol.sigma[0]
            gp += sol.deps_p[:, 3]
        assert np.allclose(sol.sigma[:, 3], C_COH, rtol=1e-6, atol=0)
        assert np.max(np.abs(sol.sigma[:, :3])) < 3e-4 * C_COH
        V = cell_volumes(PATCH_2D)
        assert abs(V @ gp / V.sum() - 9 * gamma_y) < 1e-6 * 9 * gamma_y
        assert np.allclose(gp, 9 * gamma_y, rtol=3e-4, atol=0)


def radial_return(sig_n_voigt, grad, k, alpha=0.0):
    """Closed-form associated return for von Mises (α=0) / Drucker-Prager cones.

    Trial σ_tr = σ_n + λ tr(ε) I + 2μ ε; if f = √J2 + α I1 - k > 0 then
    Δλ = f/(μ + 9Kα²), s = s_tr (1 - μΔλ/√J2_tr), I1 = I1_tr - 9KαΔλ (smooth
    part of the cone; the tests keep away from the apex).
    """
    d = grad.shape[0]
    eps = np.zeros((3, 3))
    eps[:d, :d] = 0.5 * (grad + grad.T)
    s_n = np.asarray(sig_n_voigt, float)
    Tn = np.diag(s_n[:3])
    Tn[0, 1] = Tn[1, 0] = s_n[3]
    if s_n.size == 6:
        Tn[1, 2] = Tn[2, 1] = s_n[4]
        Tn[2, 0] = Tn[0, 2] = s_n[5]
    Ttr = Tn + LAME * np.trace(eps) * np.eye(3) + 2 * SHEAR_MOD * eps
    I1 = np.trace(Ttr)
    s = Ttr - I1 / 3 * np.eye(3)
    q = math.sqrt(0.5 * np.sum(s * s))
    f = q + alpha * I1 - k
    if f > 0:
        dlam = f / (SHEAR_MOD + 9 * BULK * alpha**2)
        assert q - SHEAR_MOD * dlam > 0  # not at the apex
        s = s * (1 - SHEAR_MOD * dlam / q)
        I1 = I1 - 9 * BULK * alpha * dlam
    T = s + I1 / 3 * np.eye(3)
    return np.array([T[0, 0], T[1, 1], T[2, 2], T[0, 1], T[1, 2], T[2, 0]])


def _j2(v):
    """J2 of a full-Voigt stress (4 or 6 components)."""
    v = np.concatenate([v, np.zeros(6 - len(v))])
    T = np.diag(v[:3])
    T[0, 1] = T[1, 0] = v[3]
    T[1, 2] = T[2, 1] = v[4]
    T[2, 0] = T[0, 2] = v[5]
    s = T - np.trace(T) / 3 * np.eye(3)
    return 0.5 * np.sum(s * s)


# Accuracy of plastic stresses: the interior-point solution is accurate to
# O(sqrt(tol)) along the yield surface (measured 1.8e-4 c at tol = 1e-8 for a
# trial exactly on the surface, 1.7e-5 c at tol = 1e-10), so the return tests
# run at tol = 1e-10 and gate at 5e-5 c.
RETURN_OPTIONS = SolverOptions(tol=1e-10)
RETURN_TOL = 5e-5 * C_COH


@pytest.mark.parametrize("factor", [0.5, 1.0, 10.0])
def test_single_step_matches_radial_return_von_mises_plane_strain(factor):
    # Single-point return: elastic, just at yield and 10x past yield from a
    # prestressed state.
    sy = math.sqrt(3) * C_COH
    mat = VonMises(E, NU, sigma_y=sy)
    k = sy / math.sqrt(3)
    sig_n = np.array([-2e4, -3e4, -2.5e4, 1e3])
    direction = np.array([[1.0, 0.6], [-0.2, -0.7]]) * 1e-2
    assert math.sqrt(_j2(sig_n)) < k

    def trial_q(scale):
        return math.sqrt(_j2(radial_return(sig_n, scale * direction, np.inf)))

    # Elastic path sig_n -> trial: find the scale that just reaches yield.
    lo, hi = 0.0, 1.0
    assert trial_q(hi) > k
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if trial_q(mid) < k else (lo, mid)
    grad = factor * lo * direction
    ref = radial_return(sig_n, grad, k)[:4]
    sol = uniform_strain_step(PATCH_2D, mat, (0, 1, 2, 3), grad, sig_n, RETURN_OPTIONS)
    # Every node equals the closed-form return (5e-5 c, see RETURN_TOL).
    assert np.max(np.abs(sol.sigma - ref[None, :])) < RETURN_TOL
    # The yield condition itself is met much more tightly (1e-7 relative).
    q_end = np.array([math.sqrt(_j2(v)) for v in sol.sigma])
    assert np.all(q_end <= k * (1 + 1e-7))
    if factor > 1:
        assert np.allclose(q_end, k, rtol=1e-7, atol=0)


def test_single_step_matches_radial_return_drucker_prager_3d():
    # Single-point return in 3D: DP (compression match) on a jittered tet
    # patch, a random deviatoric strain increment well past yield; every node
    # (interior ones free) equals the closed-form return.
    mesh = jittered_block(3, n=3, size=(1.0, 1.0, 1.0), seed=12)
    mat = DruckerPrager(E, NU, c=C_COH, phi=30.0, match="compression")
    alpha, k = mat.alpha_k(30.0)
    sig_n = np.array([-5e4, -6e4, -4e4, 2e3, -1e3, 3e3])
    assert math.sqrt(_j2(sig_n)) + alpha * sig_n[:3].sum() < k
    rng = np.random.default_rng(13)
    grad = 5 * rng.normal(size=(3, 3)) * (C_COH / E)
    grad -= np.trace(grad) / 3 * np.eye(3)
    trial = radial_return(sig_n, grad, np.inf)
    assert math.sqrt(_j2(trial)) + alpha * trial[:3].sum() > 3 * k  # far past
    ref = radial_return(sig_n, grad, k, alpha)
    sol = uniform_strain_step(mesh, mat, tuple(range(6)), grad, sig_n, RETURN_OPTIONS)
    assert np.max(np.abs(sol.sigma - ref[None, :])) < RETURN_TOL
    # and the result is on the cone: √J2 + α I1 = k (1e-7 relative).
    f_end = [math.sqrt(_j2(v)) + alpha * v[:3].sum() for v in sol.sigma]
    assert np.allclose(f_end, k, rtol=1e-7, atol=0)


# --------------------------------------------------- (f) flow direction ----
@pytest.mark.parametrize("psi", [30.0, 0.0])
def test_mohr_coulomb_plastic_dilation(psi):
    # Plane-strain MC cone f = ||Mσ|| + a_ψ^T σ - k with M rows (1,-1,0),(0,0,2):
    # Δε^p = Δλ (M^T n + sinψ (1,1,0)), n = Mσ/||Mσ||, so
    # Δε^p_v = Δε^p_xx + Δε^p_yy = 2Δλ sinψ and the plastic shear magnitude
    # γ^p = sqrt((Δε^p_xx - Δε^p_yy)² + (Δγ^p_xy)²) = 2Δλ; hence
    # Δε^p_v = sinψ · γ^p (dilation ≥ 0; isochoric for ψ = 0).
    phi = 30.0
    mat = MohrCoulomb(E, NU, c=C_COH, phi=phi, psi=psi)
    p = 1.0e5
    grad = np.array([[0.0, 1.0], [0.0, 0.0]]) * 20 * p / SHEAR_MOD
    sol = uniform_strain_step(PATCH_2D, mat, (0, 1, 3), grad, [-p, -p, -p, 0.0])
    dp = sol.deps_p
    vol = dp[:, 0] + dp[:, 1]
    gp = np.hypot(dp[:, 0] - dp[:, 1], dp[:, 3])
    assert np.all(gp > 0.5 * grad[0, 1])  # real plastic flow at every node
    s = math.sin(math.radians(psi))
    # Flow rule relation (1e-6 relative to γ^p).
    assert np.max(np.abs(vol - s * gp)) < 1e-6 * gp.max()
    assert np.all(vol >= -1e-9 * gp.max())
    # End stress lies on the lagged cone: R = (k_i - sinψ (σxx+σyy))/2 (1e-6).
    sig = sol.sigma
    R = np.hypot((sig[:, 0] - sig[:, 1]) / 2, sig[:, 3])
    f = math.radians(phi)
    k_i = 2 * C_COH * math.cos(f) + (math.sin(f) - s) * 2 * p
    assert np.allclose(2 * R, k_i - s * (sig[:, 0] + sig[:, 1]), rtol=1e-6, atol=0)


def test_isochoric_cone_dilates_only_at_tension_cutoff():
    # ψ = 0 with a tension cut-off σxx + σyy ≤ 2c cotφ: equibiaxial extension
    # drives the stress to the cut-off apex, where the flow is volumetric.
    phi = 30.0
    mat = MohrCoulomb(E, NU, c=C_COH, phi=phi, psi=0.0, tension_cutoff=True)
    e = 20 * C_COH / E
    grad = np.diag([e, e])
    sol = uniform_strain_step(PATCH_2D, mat, (0, 1, 3), grad, np.zeros(4))
    cut = 2 * C_COH / math.tan(math.radians(phi))
    # On the cut-off (1e-6 relative), isotropic in-plane (< 1e-6 c).
    assert np.allclose(sol.sigma[:, 0] + sol.sigma[:, 1], cut, rtol=1e-6, atol=0)
    assert np.max(np.abs(sol.sigma[:, 0] - sol.sigma[:, 1])) < 1e-6 * C_COH
    vol = sol.deps_p[:, 0] + sol.deps_p[:, 1]
    # Plastic volume = total 2e minus the elastic part of reaching the cut-off.
    elastic = compliance_matrix(E, NU, 2, (0, 1, 3)) @ np.array([cut / 2, cut / 2, 0])
    assert np.allclose(vol, 2 * e - elastic[:2].sum(), rtol=1e-6, atol=0)


# ------------------------------------------------------ (g) solver errors ----
def overloaded_block():
    mesh = jittered_block(2, n=4, size=(1.0, 1.0), seed=3)
    n = mesh.p.shape[1]
    x = mesh.p.T
    fixed = np.zeros((n, 2), bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    top = np.flatnonzero(np.isclose(x[:, 1], 1.0))
    force = np.zeros((n, 2))
    # Unconfined compression collapses near q = 2c; load it with 20 c.
    force[top, 1] = -20 * C_COH / top.size
    return step_data(mesh, Tresca(E, NU, c=C_COH), (0, 1, 3), fixed=fixed, force=force)


def test_static_overload_is_infeasible_with_a_useful_message():
    data = overloaded_block()
    with pytest.raises(SolverError) as info:
        solve_step(data, step=7)
    err = info.value
    assert err.status in ("PrimalInfeasible", "AlmostPrimalInfeasible")
    assert err.step == 7
    msg = str(err)
    assert "step 7" in msg
    assert "displacement control" in msg
    # The same block at 1/20 of the load (q = c < 2c) is solved and finite.
    data.force *= 0.05
    sol = solve_step(data)
    assert_finite(sol)
    assert sol.status in ("Solved", "AlmostSolved")


def test_static_overload_through_simulation_keeps_the_advice():
    # Through the public loop: a Tresca column (c = 2 kPa) under its own weight,
    # ρgH = 19.6 kPa ≈ 9.8 c, cannot stand unconfined (needs ρgH ≲ 2c).
    from skfem_npfem import FixedMesh, Simulation

    mesh = MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 1, 5))
    x = mesh.p.T.copy()
    fixed = np.zeros_like(x, bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    mat = Tresca(E, NU, RHO, c=2e3)
    vol = nodal_integration(mesh).volumes
    p = Particles.create(x, RHO * vol, fixed=fixed)
    model = Model(dim=2, materials=[mat], mode="static")
    sim = Simulation(p, model, FixedMesh(mesh.t), 1.0)
    with pytest.raises(SolverError) as info:
        sim.run(steps=1)
    assert info.value.status in ("PrimalInfeasible", "AlmostPrimalInfeasible")
    assert "step 1" in str(info.value)
    assert "displacement control" in str(info.value)


def test_max_iterations_raises():
    mat = Tresca(E, NU, c=C_COH)
    grad = np.array([[0.0, 10 * C_COH / SHEAR_MOD], [0.0, 0.0]])
    with pytest.raises(SolverError) as info:
        uniform_strain_step(
            PATCH_2D, mat, (0, 1, 3), grad, np.zeros(4), SolverOptions(max_iter=1)
        )
    assert info.value.status == "MaxIterations"
    assert info.value.iterations == 1


# ------------------------------------------------------- (h) bad inputs ----
@pytest.mark.parametrize(
    ("name", "make"),
    [
        ("linear_solver", lambda: SolverOptions(linear_solver="cholmod")),
        ("tol", lambda: SolverOptions(tol=0.0)),
        ("max_iter", lambda: SolverOptions(max_iter=0)),
        ("nu", lambda: LinearElastic(E, 0.5)),
        ("nu", lambda: LinearElastic(E, -1.0)),
        ("E", lambda: LinearElastic(0.0, NU)),
        ("E", lambda: LinearElastic(float("nan"), NU)),
        ("rho", lambda: LinearElastic(E, NU, -1.0)),
        ("c", lambda: MohrCoulomb(E, NU, c=-1.0, phi=30.0)),
        ("phi", lambda: MohrCoulomb(E, NU, c=C_COH, phi=90.0)),
        ("psi", lambda: MohrCoulomb(E, NU, c=C_COH, phi=20.0, psi=25.0)),
        ("psi", lambda: DruckerPrager(E, NU, c=C_COH, phi=20.0, psi=25.0)),
        ("c", lambda: Tresca(E, NU, c=0.0)),
        ("sigma_y", lambda: VonMises(E, NU, sigma_y=0.0)),
        ("match", lambda: DruckerPrager(E, NU, c=C_COH, match="outer")),
        ("dim", lambda: Model(dim=3, materials=[MohrCoulomb(E, NU, c=1.0, phi=30)])),
        ("dim", lambda: Model(dim=3, materials=[Tresca(E, NU, c=1.0)])),
        ("theta1", lambda: Model(dim=2, materials=[LinearElastic(E, NU)], theta1=0.4)),
        ("mode", lambda: Model(dim=2, materials=[LinearElastic(E, NU)], mode="foo")),
        ("x", lambda: Particles.create(np.array([[0.0, float("nan")]]), np.ones(1))),
        ("mass", lambda: Particles.create(np.zeros((2, 2)), np.array([1.0, 0.0]))),
    ],
)
def test_bad_inputs_raise_parameter_error(name, make):
    with pytest.raises(ParameterError) as info:
        make()
    assert isinstance(info.value, ValueError)
    assert info.value.name == name
    assert name in str(info.value)


# ------------------------------------------ a static body nothing holds ----
def _square(**particles_kw):
    from skfem_npfem import LinearElastic, Model, Particles

    mesh = MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 1, 5))
    soil = LinearElastic(E=1e7, nu=0.3, rho=2000.0)
    p = Particles.from_mesh(mesh, soil, **particles_kw)
    return p, Model(dim=2, materials=[soil], mode="static"), mesh, soil


def test_a_static_body_nothing_holds_is_refused_as_unsupported():
    # Reproducer: an elastic square under gravity, static, nothing fixed, no
    # wall: Clarabel's PrimalInfeasible came back as "the load exceeds the
    # collapse load", which an elastic body does not have.
    from skfem_npfem import ParameterError, advance

    p, model, mesh, soil = _square()
    with pytest.raises(ParameterError, match="moves it as a rigid body") as err:
        advance(p, model, dt=1.0, mesh_source=mesh)
    msg = str(err.value)
    assert "collapse load" not in msg and "mode='dynamic'" in msg
    # The resultant it names is the weight, rho g times the area of 1 m^2.
    assert f"resultant {-soil.rho * model.gravity:.4g} N along axis 1" in msg


def test_a_static_body_on_a_fixed_base_is_still_solved():
    from skfem_npfem import advance

    mesh = MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 1, 5))
    p, model, mesh, _ = _square(fixed=np.repeat(mesh.p[1][:, None] == 0, 2, 1))
    _, step = advance(p, model, dt=1.0, mesh_source=mesh)
    assert step.record.status == "Solved"
