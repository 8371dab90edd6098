"""Axisymmetric N-PFEM operators: exactness, consistency and closed-form problems.

References (docs/verification.md, "The reference cases"): smoothing cells (the
cells partition the body of revolution, sum V_i = pi (b^2 - a^2) h), the patch
test (with the hoop strain), divergence consistency, zero-energy modes, the
single-point return, the elastic column (oedometric) and the thick-walled
cylinder (Lamé, and the von Mises limit pressure (2/sqrt 3) sigma_y ln(b/a));
docs/theory.md "Axisymmetric N-PFEM".
All references are closed forms or independent scikit-fem assemblies.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import jittered_section
from skfem import (
    Basis,
    BilinearForm,
    ElementTriP1,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshTri,
)

from skfem_npfem import (
    ConeInput,
    Contacts,
    FixedMesh,
    Model,
    SolverOptions,
    advance,
    solve_step,
)
from skfem_npfem.errors import ParameterError, SolverError
from skfem_npfem.materials import (
    DruckerPrager,
    LinearElastic,
    MohrCoulomb,
    VonMises,
    compliance_matrix,
)
from skfem_npfem.mesh.axisymmetric import (
    AxisymmetricMohrCoulomb,
    axisymmetric_integration,
    mohr_coulomb_cones,
)
from skfem_npfem.particles import Particles

TWO_PI = 2.0 * math.pi


# ----------------------------------------------------------------- meshes ----
ANNULUS = dict(r0=0.5, r1=2.0, h=1.0)  # a, b, h of the annular rectangle


def annulus(nr=7, nz=5, seed=0):
    a, b, h = ANNULUS["r0"], ANNULUS["r1"], ANNULUS["h"]
    return jittered_section(a, b, h, nr, nz, seed=seed)


def solid(nr=6, nz=5, seed=1):
    """Solid cylinder R = 1, H = 1.5 (nodes on the axis r = 0)."""
    return jittered_section(0.0, 1.0, 1.5, nr, nz, seed=seed)


def node_major(basis, ncomp):
    """Permutation from scikit-fem dofs to node-major order (nodal_dofs[c, i])."""
    n = basis.nodal_dofs.shape[1]
    perm = np.empty(ncomp * n, int)
    for c in range(ncomp):
        perm[np.arange(n) * ncomp + c] = basis.nodal_dofs[c]
    return perm


# -------------------------------------------------- smoothing cells: volumes ----
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_cell_volumes_sum_to_the_body_of_revolution(seed):
    a, b, h = ANNULUS["r0"], ANNULUS["r1"], ANNULUS["h"]
    ni = axisymmetric_integration(annulus(seed=seed))
    # Annulus: sum V_i = pi (b^2 - a^2) h to round-off (1e-13 relative).
    assert abs(ni.volumes.sum() / (math.pi * (b * b - a * a) * h) - 1) < 1e-13
    ns = axisymmetric_integration(solid(seed=seed))
    # Solid cylinder R = 1, H = 1.5: pi R^2 H (1e-13 relative), axis cells > 0.
    assert abs(ns.volumes.sum() / (math.pi * 1.5) - 1) < 1e-13
    assert np.all(ns.volumes > 0)
    # Planar areas still partition the section (1e-13).
    assert abs(ni.areas.sum() / ((b - a) * h) - 1) < 1e-13


def test_cell_volume_is_the_weighted_integral_not_area_times_radius():
    # V_i = int phi_i 2 pi r dA (independent scikit-fem assembly, degree-4
    # quadrature, 1e-13).  The lumped guess 2 pi A_i r_i has the same *sum* (r is
    # linear, so sum_i A_i r_i = int r dA) but wrong cells: zero on the axis
    # (a massless axis particle) and up to 18 % off elsewhere (median 5 %).
    mesh = solid()
    ni = axisymmetric_integration(mesh)
    basis = Basis(mesh, ElementTriP1(), intorder=4)
    ref = LinearForm(lambda v, w: TWO_PI * w.x[0] * v).assemble(basis)
    assert np.max(np.abs(ni.volumes - ref)) < 1e-13 * ref.max()
    naive = TWO_PI * ni.areas * mesh.p[0]
    assert abs(naive.sum() / ref.sum() - 1) < 1e-13
    axis = np.isclose(mesh.p[0], 0.0)
    assert np.all(naive[axis] == 0.0) and np.all(ni.volumes[axis] > 0.0)
    assert np.max(np.abs(naive[~axis] / ni.volumes[~axis] - 1)) > 0.02


# ----------------------------------------------------------- patch test ----
def hoop_reference(mesh, ur):
    """(2 pi / V_i) int phi_i u_r dA by an independent scikit-fem assembly."""
    basis = Basis(mesh, ElementTriP1(), intorder=4)
    num = LinearForm(lambda v, w: TWO_PI * ur(w.x) * v).assemble(basis)
    vol = LinearForm(lambda v, w: TWO_PI * w.x[0] * v).assemble(basis)
    return num / vol


def test_patch_test_linear_fields_on_an_annulus():
    mesh = annulus()
    r, z = mesh.p
    c = dict(a=0.3, b=0.7, e=0.25, u0=0.1, d=-0.4, f=0.6)

    def ur(x):
        return c["a"] + c["b"] * x[0] + c["e"] * x[1]

    u = np.column_stack([ur(mesh.p), c["u0"] + c["d"] * z + c["f"] * r])
    ni = axisymmetric_integration(mesh)
    eps = ni.strain(u)
    # In-plane rows exact at every node, boundary nodes included (1e-13).
    assert np.max(np.abs(eps[:, 0] - c["b"])) < 1e-13
    assert np.max(np.abs(eps[:, 1] - c["d"])) < 1e-13
    assert np.max(np.abs(eps[:, 3] - (c["e"] + c["f"]))) < 1e-13
    # Hoop row: the 2 pi r-weighted cell mean of the exact u_r / r (1e-13).
    assert np.max(np.abs(eps[:, 2] - hoop_reference(mesh, ur))) < 1e-13
    # Smoothed in-plane gradient of a linear field is its constant gradient.
    grad = np.array([[c["b"], c["e"]], [c["f"], c["d"]]])
    assert np.max(np.abs(ni.gradient(u) - grad[None])) < 1e-13


def test_patch_test_uniform_expansion_is_exact_on_the_axis():
    # u_r = c r, u_z = d z: eps_rr = eps_tt = c, eps_zz = d at every node,
    # the axis nodes (r = 0) included, to round-off (1e-13).
    mesh = solid()
    c, d = 0.37, -0.21
    u = np.column_stack([c * mesh.p[0], d * mesh.p[1]])
    eps = axisymmetric_integration(mesh).strain(u)
    axis = np.isclose(mesh.p[0], 0.0)
    assert axis.sum() >= 6
    assert np.max(np.abs(eps - np.array([c, d, c, 0.0])[None])) < 1e-13
    assert np.max(np.abs(eps[axis, 2] - c)) < 1e-13


# --------------------------------------- G is the weighted bilinear form ----
def test_G_equals_the_scikit_fem_axisymmetric_bilinear_form():
    mesh = annulus(5, 4)
    btau = Basis(mesh, ElementVector(ElementTriP1(), dim=4), intorder=4)
    bv = Basis(mesh, ElementVector(ElementTriP1()), intorder=4)

    @BilinearForm
    def work(tau, v, w):
        r = w.x[0]
        gv = v.grad  # gv[k, j] = d v_k / d x_j, (x_0, x_1) = (r, z)
        in_plane = tau[0] * gv[0, 0] + tau[1] * gv[1, 1]
        in_plane = in_plane + tau[3] * (gv[0, 1] + gv[1, 0])
        return TWO_PI * (in_plane * r + tau[2] * v[0])  # hoop: (v_r / r) r

    ref = work.assemble(btau, bv).toarray()
    ref = ref[np.ix_(node_major(bv, 2), node_major(btau, 4))]
    G = axisymmetric_integration(mesh).G.toarray()
    # sigma^T G^T v = int tau_h : eps(v_h) 2 pi r dA (1e-13 relative).
    assert np.linalg.norm(G - ref) < 1e-13 * np.linalg.norm(ref)


# ------------------------------------------------- divergence consistency ----
def test_uniform_stress_gives_the_consistent_boundary_and_hoop_loads():
    # For uniform sigma: G sigma = int_dOmega phi sigma n 2 pi r ds
    #                              - int phi div_axi(sigma) 2 pi r dA,
    # div_axi(sigma) = ((s_rr - s_tt) / r, s_rz / r) (independent assembly, 1e-12).
    mesh = annulus()
    s = dict(rr=-3.0, zz=-5.0, tt=-1.5, rz=0.8)
    ni = axisymmetric_integration(mesh)
    sig = np.tile([s["rr"], s["zz"], s["tt"], s["rz"]], mesh.p.shape[1])
    vb = ElementVector(ElementTriP1())
    fb = FacetBasis(mesh, vb, intorder=3)

    @LinearForm
    def traction(v, w):
        n = w.n
        t_r = s["rr"] * n[0] + s["rz"] * n[1]
        t_z = s["rz"] * n[0] + s["zz"] * n[1]
        return TWO_PI * w.x[0] * (t_r * v[0] + t_z * v[1])

    @LinearForm
    def body(v, w):
        return TWO_PI * ((s["rr"] - s["tt"]) * v[0] + s["rz"] * v[1])

    cb = Basis(mesh, vb, intorder=3)
    ref = traction.assemble(fb) - body.assemble(cb)
    ref = ref[node_major(cb, 2)]
    f = ni.G @ sig
    assert np.max(np.abs(f - ref)) < 1e-12 * np.max(np.abs(ref))
    # Hydrostatic stress: interior nodes carry no force (1e-12).
    f_hyd = ni.G @ np.tile([-2.0, -2.0, -2.0, 0.0], mesh.p.shape[1])
    inner = np.setdiff1d(np.arange(mesh.p.shape[1]), mesh.boundary_nodes())
    assert np.max(np.abs(f_hyd.reshape(-1, 2)[inner])) < 1e-12 * np.abs(f_hyd).max()


# ---------------------------------------------------- zero-energy modes ----
@pytest.mark.parametrize("make", [annulus, solid])
def test_only_the_axial_translation_has_zero_energy(make):
    # K = G diag(D / V_i) G^T: in axisymmetry the only rigid motion is u_z =
    # const, so exactly one zero eigenvalue (none spurious).  On the solid
    # cylinder u_r is fixed on the axis first (its symmetry condition).
    mesh = make()
    ni = axisymmetric_integration(mesh)
    D = np.linalg.inv(compliance_matrix(1.0, 0.3, 2, (0, 1, 2, 3)))
    n = mesh.p.shape[1]
    Dbig = np.kron(np.diag(1.0 / ni.volumes), D)
    K = ni.G.toarray() @ Dbig @ ni.G.toarray().T
    free = np.ones(2 * n, bool)
    free[2 * np.flatnonzero(np.isclose(mesh.p[0], 0.0))] = False
    lam = np.linalg.eigvalsh(K[np.ix_(free, free)])
    scale = lam.max()
    assert np.sum(np.abs(lam) < 1e-12 * scale) == 1
    assert lam[1] > 1e-6 * scale


# ----------------------------------------------- model-level validation ----
def test_model_refuses_what_axisymmetry_cannot_use():
    mc = MohrCoulomb(1e7, 0.3, c=1e3, phi=30.0)
    with pytest.raises(ParameterError, match="hoop"):
        Model(dim=2, materials=[mc], axisymmetric=True)
    with pytest.raises(ParameterError, match="dim=2"):
        Model(dim=3, materials=[LinearElastic(1e7, 0.3)], axisymmetric=True)
    with pytest.raises(ParameterError, match="True or False"):
        Model(dim=2, materials=[LinearElastic(1e7, 0.3)], axisymmetric="yes")
    m = Model(dim=2, materials=[DruckerPrager(1e7, 0.3, phi=30.0)], axisymmetric=True)
    assert m.components == (0, 1, 2, 3)
    with pytest.raises(ValueError, match="r < 0"):
        axisymmetric_integration(MeshTri.init_tensor([-1.0, 0.0, 1.0], [0.0, 1.0]))
    with pytest.raises(ValueError, match="hoop"):
        axisymmetric_integration(annulus(), components=(0, 1, 3))


# ------------------------------------ elastic column: the oedometric column ----
def test_oedometric_column_under_self_weight():
    # Solid cylinder R = 1, H = 4, fixed base, smooth lateral wall (u_r = 0 at
    # r = R) and the axis (u_r = 0): s_zz = -rho g (H - z), s_rr = s_tt =
    # nu/(1-nu) s_zz, settlement rho g H^2 / (2 M).  Same mesh density and
    # tolerances as the plane-strain column (spacing 0.125: 9 x 33 nodes, 0.5 %;
    # measured 0.47 % / 0.31 % / 0.32 % / 0.02 % / 0.13 %).
    R, H, rho, g, E, nu = 1.0, 4.0, 2000.0, 9.81, 1e7, 0.3
    mesh = MeshTri.init_tensor(np.linspace(0, R, 9), np.linspace(0, H, 33))
    ni = axisymmetric_integration(mesh)
    x = mesh.p.T.copy()
    fixed = np.zeros_like(x, bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    fixed[np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], R), 0] = True
    p = Particles.create(x, rho * ni.volumes, fixed=fixed)
    # Masses of the full ring: rho pi R^2 H exactly (1e-13).
    assert abs(p.mass.sum() / (rho * math.pi * R * R * H) - 1) < 1e-13
    mat = LinearElastic(E, nu, rho)
    model = Model(dim=2, materials=[mat], gravity=g, mode="static", axisymmetric=True)
    new, res = advance(p, model, 1.0, FixedMesh(mesh.t))
    rec = res.record
    z = x[:, 1]
    sv_ex = -rho * g * (H - z)
    sh_ex = nu / (1 - nu) * sv_ex

    def rel(a, b):
        return np.linalg.norm(a - b) / np.linalg.norm(b)

    assert rec.iterations == 0
    assert rel(new.stress[:, 1], sv_ex) <= 5e-3
    assert rel(new.stress[:, 0], sh_ex) <= 5e-3
    assert rel(new.stress[:, 2], sh_ex) <= 5e-3  # hoop = radial (K0 state)
    top = np.isclose(z, H)
    settle = rho * g * H**2 / (2 * mat.p_wave_modulus)
    assert abs(-new.u[top, 1].mean() / settle - 1) <= 5e-3
    assert abs(new.stress[np.isclose(z, 0), 1].mean() / (-rho * g * H) - 1) <= 5e-3


# ------------------------------------------ thick-walled cylinder: Lamé ----
def lame_setup(nr, nz, a=1.0, b=2.0):
    """Annulus [a, b] x [0, hz] with rollers on top and bottom (eps_zz = 0)."""
    hz = (b - a) / nr * nz
    mesh = MeshTri.init_tensor(np.linspace(a, b, nr + 1), np.linspace(0, hz, nz + 1))
    r, z = mesh.p
    fixed = np.zeros((r.size, 2), bool)
    fixed[:, 1] = np.isclose(z, 0) | np.isclose(z, hz)
    return mesh, fixed


def pressure_load(mesh, a, p):
    """Consistent ring load of an internal pressure p on r = a (2 pi a p per m)."""
    r, z = mesh.p
    inner = np.flatnonzero(np.isclose(r, a))
    order = inner[np.argsort(z[inner])]
    half = 0.5 * TWO_PI * a * p * np.diff(z[order])
    force = np.zeros((r.size, 2))
    np.add.at(force[:, 0], order[:-1], half)
    np.add.at(force[:, 0], order[1:], half)
    return force


def static_step(mesh, mat, fixed, force, du=None, sigma_n=None, options=None):
    n = mesh.p.shape[1]
    data = ConeInput(
        operator=axisymmetric_integration(mesh),
        materials=[mat],
        material=np.zeros(n, int),
        sigma_n=np.zeros((n, 4)) if sigma_n is None else sigma_n,
        force=force,
        fixed=fixed,
        du_prescribed=np.zeros((n, 2)) if du is None else du,
        contacts=Contacts.empty(2),
    )
    return solve_step(data, options)


def lame_errors(nu, n=16, a=1.0, b=2.0, p=1.0, E=1.0):
    mesh, fixed = lame_setup(n, n, a, b)
    sol = static_step(mesh, LinearElastic(E, nu), fixed, pressure_load(mesh, a, p))
    r = mesh.p[0]
    A = p * a * a / (b * b - a * a)
    B = p * a * a * b * b / (b * b - a * a)
    ur = (1 + nu) / E * ((1 - 2 * nu) * A * r + B / r)
    s = sol.sigma
    exact = np.column_stack([A - B / r**2, 2 * nu * A + 0 * r, A + B / r**2])

    def rel(x, y):
        return float(np.linalg.norm(x - y) / np.linalg.norm(y))

    mean = s[:, :3].mean(axis=1)
    mean_ex = exact.mean(axis=1)
    elem = mesh.t  # element means: average of the three vertex values
    return {
        "ur": rel(sol.du[:, 0], ur),
        "rr": rel(s[:, 0], exact[:, 0]),
        "tt": rel(s[:, 2], exact[:, 2]),
        "zz": rel(s[:, 1], exact[:, 1]),
        "dev": rel(s[:, 2] - s[:, 0], exact[:, 2] - exact[:, 0]),
        "rz": float(np.abs(s[:, 3]).max() / p),
        "mean_nodal": rel(mean, mean_ex),
        "mean_elem": rel(mean[elem].mean(0), mean_ex[elem].mean(0)),
        "iterations": sol.iterations,
    }


def test_lame_thick_cylinder_plane_strain_without_locking():
    e3, e5 = lame_errors(0.3), lame_errors(0.4999)
    assert e3["iterations"] == e5["iterations"] == 0
    # nu = 0.3: u_r 0.12 %, s_rr / s_tt / s_zz 0.9 / 1.7 / 2.6 % (relative L2
    # over the nodes; the boundary cells carry O(h) errors); gates 2x.
    assert e3["ur"] < 2.5e-3
    assert e3["rr"] < 2e-2 and e3["tt"] < 3.5e-2 and e3["zz"] < 5e-2
    assert e3["rz"] < 2e-2
    # nu = 0.4999: no volumetric locking -- the displacement, the deviatoric
    # stress s_tt - s_rr and the element-mean pressure are as accurate as at
    # nu = 0.3 (measured ratios 1.25, 1.31, 2.2; gates 1.5, 1.5, 3).
    assert e5["ur"] < 1.5 * e3["ur"]
    assert e5["dev"] < 1.5 * e3["dev"]
    assert e5["mean_elem"] < 3.0 * e3["mean_elem"]
    # The nodal mean stress carries the checkerboard of equal-order P1 stress /
    # P1 displacement (28 % here, zero element mean): docs/theory.md.
    assert e5["mean_nodal"] > 5 * e5["mean_elem"]


# -------------------- thick-walled cylinder: von Mises limit pressure ----
#: Published limit pressure of the internally pressurised thick cylinder of
#: de Souza Neto, Peric & Owen (2008), plane strain: a = 100, b = 200,
#: E = 210, nu = 0.3, sigma_y = 0.24 (Hill's (2/sqrt 3) sigma_y ln(b/a)).
P_LIM_PUBLISHED = 0.19209


def _admits(mesh, fixed, mat, a, p):
    """True if a static step at internal pressure p admits a solution."""
    try:
        return static_step(mesh, mat, fixed, pressure_load(mesh, a, p)).status == (
            "Solved"
        )
    except SolverError:
        return False


def test_von_mises_thick_cylinder_limit_pressure_is_the_published_one():
    # The largest pressure a static step admits (bisection on feasibility, to
    # 1e-4 relative) is the published limit pressure: 1.0005 of it on this
    # 16 x 4 mesh; within 0.2 %.
    a, b, sy = 100.0, 200.0, 0.24
    mesh, fixed = lame_setup(16, 4, a, b)
    mat = VonMises(210.0, 0.3, sigma_y=sy)
    lo, hi = 0.9 * P_LIM_PUBLISHED, 1.1 * P_LIM_PUBLISHED
    assert _admits(mesh, fixed, mat, a, lo) and not _admits(mesh, fixed, mat, a, hi)
    while hi - lo > 1e-4 * P_LIM_PUBLISHED:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _admits(mesh, fixed, mat, a, mid) else (lo, mid)
    assert lo / P_LIM_PUBLISHED == pytest.approx(1.0, abs=2e-3)


@pytest.mark.parametrize(("factor", "feasible"), [(0.99, True), (1.01, False)])
def test_von_mises_thick_cylinder_limit_pressure(factor, feasible):
    # A static step admits an equilibrated stress inside the cone below the
    # published limit pressure and none above it.
    a, b, sy = 100.0, 200.0, 0.24
    p_lim = P_LIM_PUBLISHED
    mesh, fixed = lame_setup(16, 4, a, b)
    mat = VonMises(210.0, 0.3, sigma_y=sy)
    force = pressure_load(mesh, a, factor * p_lim)
    if feasible:
        sol = static_step(mesh, mat, fixed, force)
        assert sol.status == "Solved"
        q = np.sqrt(_j2(sol.sigma))
        assert q.max() <= sy / math.sqrt(3) * (1 + 1e-7)
    else:
        with pytest.raises(SolverError, match="Infeasible"):
            static_step(mesh, mat, fixed, force)


def _j2(s: np.ndarray) -> np.ndarray:
    """J2 of (rr, zz, tt, rz) stresses (rows)."""
    s = np.atleast_2d(s)
    m = s[:, :3].mean(axis=1, keepdims=True)
    dev = s[:, :3] - m
    return 0.5 * np.sum(dev**2, axis=1) + s[:, 3] ** 2


# ------------------ single-point return: Drucker-Prager with the hoop stress ----
def dp_return(sig_n, eps, E, nu, alpha, k):
    """Closed-form associated Drucker-Prager return (smooth part of the cone)."""
    G, K = E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))
    T = np.array([[sig_n[0], sig_n[3], 0], [sig_n[3], sig_n[1], 0], [0, 0, sig_n[2]]])
    e = np.array([[eps[0], eps[3] / 2, 0], [eps[3] / 2, eps[1], 0], [0, 0, eps[2]]])
    T = T + 2 * G * e + (K - 2 * G / 3) * np.trace(e) * np.eye(3)
    I1 = np.trace(T)
    s = T - I1 / 3 * np.eye(3)
    q = math.sqrt(0.5 * np.sum(s * s))
    f = q + alpha * I1 - k
    if f > 0:
        dlam = f / (G + 9 * K * alpha**2)
        assert q - G * dlam > 0  # not at the apex
        s = s * (1 - G * dlam / q)
        I1 = I1 - 9 * K * alpha * dlam
    T = s + I1 / 3 * np.eye(3)
    return np.array([T[0, 0], T[1, 1], T[2, 2], T[0, 1]])


@pytest.mark.parametrize("factor", [0.5, 10.0])
def test_drucker_prager_uniform_step_is_the_closed_form_return(factor):
    # All nodes follow u_r = e_r r, u_z = e_z z + g r (uniform strain
    # (e_r, e_z, e_r, g), hoop = radial), from a uniform stress inside the
    # cone: every node, axis nodes included, is the closed-form return of the
    # associated cone; past yield it lies on the cone (1e-7 relative).
    E, nu, c = 1e7, 0.3, 1e4
    mat = DruckerPrager(E, nu, c=c, phi=30.0, match="compression")
    alpha, k = mat.alpha_k(30.0)
    sig_n = np.array([-5e4, -8e4, -5e4, 1e3])
    assert math.sqrt(_j2(sig_n)[0]) + alpha * sig_n[:3].sum() < k
    mesh = solid(4, 4)
    r, z = mesh.p
    e_r, e_z, g = 0.4e-3 * factor, -1.2e-3 * factor, 0.3e-3 * factor
    du = np.column_stack([e_r * r, e_z * z + g * r])
    n = r.size
    opts = SolverOptions(tol=1e-10)
    sol = static_step(
        mesh,
        mat,
        np.ones((n, 2), bool),
        np.zeros((n, 2)),
        du=du,
        sigma_n=np.tile(sig_n, (n, 1)),
        options=opts,
    )
    ref = dp_return(sig_n, (e_r, e_z, e_r, g), E, nu, alpha, k)
    # Same gate as the plane-strain/3D return tests: 5e-5 c.
    assert np.max(np.abs(sol.sigma - ref[None])) < 5e-5 * c
    f = np.sqrt(_j2(sol.sigma)) + alpha * sol.sigma[:, :3].sum(axis=1)
    if factor > 1:
        assert np.allclose(f, k, rtol=1e-7, atol=0)
    else:
        assert np.all(f < k)


# ------------------------------------------ Mohr-Coulomb as three cones ----
@pytest.mark.parametrize(("phi", "c"), [(30.0, 0.0), (20.0, 1e4), (0.0, 1e4)])
def test_axisymmetric_mohr_coulomb_is_three_second_order_cones(phi, c):
    # Random axisymmetric stresses scaled onto the Mohr-Coulomb surface (from
    # the principal stresses): the largest of the three cone residuals is 0
    # there (1e-9 relative), negative inside (scale 0.9), positive outside (1.1).
    rng = np.random.default_rng(7)
    s, cos = math.sin(math.radians(phi)), math.cos(math.radians(phi))
    cones = mohr_coulomb_cones(phi, c)

    def mc(sig):  # max over ordered pairs of principal stresses
        T = np.array([[sig[0], sig[3], 0], [sig[3], sig[1], 0], [0, 0, sig[2]]])
        e = np.linalg.eigvalsh(T)
        return (
            max(
                e[i] * (1 + s) - e[j] * (1 - s)
                for i in range(3)
                for j in range(3)
                if i != j
            )
            - 2 * c * cos
        )

    def worst(sig):
        return max(a @ sig + np.linalg.norm(M @ sig) - k for a, k, M in cones)

    apex = np.array([1.0, 1.0, 1.0, 0.0]) * (
        c / math.tan(math.radians(phi)) if phi else 0
    )
    for _ in range(40):
        dev = rng.normal(size=4) * 1e4
        dev[:3] -= dev[:3].mean()  # deviatoric: the ray leaves the cone
        base = apex - np.array([1.0, 1.0, 1.0, 0.0]) * rng.uniform(0, 5e4)
        lo, hi = 0.0, 1.0  # find t with mc(base + t dev) = 0 (mc(base) <= 0)
        while mc(base + hi * dev) < 0:
            hi *= 2
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if mc(base + mid * dev) < 0 else (lo, mid)
        on = base + lo * dev
        scale = 1e4 + abs(on).max()
        assert abs(worst(on)) < 1e-9 * scale
        assert worst(base + 0.9 * lo * dev) < 0 < worst(base + 1.1 * lo * dev)


@pytest.mark.parametrize("phi", [0.0, 10.0, 30.0])
@pytest.mark.parametrize(("factor", "feasible"), [(0.99, True), (1.01, False)])
def test_mohr_coulomb_thick_cylinder_limit_pressure(phi, factor, feasible):
    # Thick-walled cylinder, Mohr-Coulomb in plane strain (hoop stress
    # major, radial minor, axial intermediate): p_lim = c cot(phi) [(b/a)^((N-1)
    # /N) - 1] = 1.2911 c (10 deg), 1.0174 c (30 deg); Tresca 2 c ln(b/a) =
    # 1.3863 c.  The hoop-major cone is the active one.  Bisection on this
    # 16 x 4 mesh: 1.0006, 1.00006, 1.0053 p_lim; gate +-1 % (the case's
    # tolerance, docs/verification.md).
    a, b, c = 1.0, 2.0, 1.0
    s = math.sin(math.radians(phi))
    if phi == 0.0:
        p_lim = 2 * c * math.log(b / a)
    else:
        n = (1 + s) / (1 - s)
        p_lim = c / math.tan(math.radians(phi)) * ((b / a) ** ((n - 1) / n) - 1)
    ref = {0.0: 1.3863, 10.0: 1.2911, 30.0: 1.0174}[phi]
    assert abs(p_lim - ref) < 1e-4
    mesh, fixed = lame_setup(16, 4, a, b)
    mat = AxisymmetricMohrCoulomb(1e3, 0.3, c=c, phi=phi)
    force = pressure_load(mesh, a, factor * p_lim)
    if feasible:
        sol = static_step(mesh, mat, fixed, force)
        worst = max(
            np.max(sol.sigma @ a_ + np.linalg.norm(sol.sigma @ M.T, axis=1) - k)
            for a_, k, M in mohr_coulomb_cones(phi, c)
        )
        assert worst <= 1e-7 * c
    else:
        with pytest.raises(SolverError, match="Infeasible"):
            static_step(mesh, mat, fixed, force)


def test_axisymmetric_mohr_coulomb_frozen_friction_and_model():
    # psi < phi: each cone has friction psi and a strength lagged on sigma_n
    # such that, at sigma = sigma_n, it is exactly the phi cone (1e-9).
    mat = AxisymmetricMohrCoulomb(1e7, 0.3, c=2e3, phi=30.0, psi=0.0)
    sig_n = np.array([[-3e4, -6e4, -2.5e4, 4e3]])
    rows = mat.cone(2, (0, 1, 2, 3), sig_n)
    assert len(rows) == 3
    for r, (a_phi, k_phi, M) in zip(rows, mohr_coulomb_cones(30.0, 2e3), strict=True):
        assert np.allclose(r.M, M)
        frozen = r.k[0] - r.a[0] @ sig_n[0]
        assert abs(frozen - (k_phi - a_phi @ sig_n[0])) < 1e-9 * 6e4
    # psi = 0: the cones' a have no friction left (isochoric flow).
    assert np.allclose(rows[0].a, 0.0)
    assert np.allclose(rows[1].a[0], [0.5, 0.5, -1.0, 0.0])
    m = Model(dim=2, materials=[mat], axisymmetric=True)
    assert m.components == (0, 1, 2, 3)
