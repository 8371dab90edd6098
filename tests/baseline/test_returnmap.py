"""Closed-form return mapping against the library's cone step (single-point return).

Reference: one N-PFEM step (``conic.solve_step``, an independent SOCP) of a
patch whose boundary follows a uniform strain increment: every node's stress
is the closest point of the cone to the elastic trial in the energy norm.  The
interior-point answer is accurate to O(sqrt(tol)) along the surface (measured
in tests/step/test_conic.py), so the comparison runs at tol = 1e-10 and gates at
5e-5 c.  Also exact checks: the returned stress lies on the cone, the plastic
strain follows the flow rule, elastic trials are untouched.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from skfem import MeshTet, MeshTri

from skfem_npfem import ConeInput, Contacts, SolverOptions, solve_step
from skfem_npfem.baseline.returnmap import elastic_trial, project_invariants, return_map
from skfem_npfem.materials import DruckerPrager, MohrCoulomb, Tresca, VonMises
from skfem_npfem.mesh.smoothing import nodal_integration

E, NU, C = 1.0e7, 0.3, 1.0e4
TOL = 5e-5 * C
OPTIONS = SolverOptions(tol=1e-10)


def patch(dim: int):
    rng = np.random.default_rng(7)
    ax = [np.linspace(0, 1, 4)] * dim
    m = MeshTri.init_tensor(*ax) if dim == 2 else MeshTet.init_tensor(*ax)
    p = m.p.copy()
    inner = np.setdiff1d(np.arange(p.shape[1]), m.boundary_nodes())
    p[:, inner] += 0.05 * rng.uniform(-1, 1, (dim, inner.size))
    return (MeshTri if dim == 2 else MeshTet)(p, m.t)


def voigt(grad):
    d = grad.shape[0]
    if d == 2:
        return np.array([grad[0, 0], grad[1, 1], 0.0, grad[0, 1] + grad[1, 0]])
    g = grad + grad.T
    return np.array([grad[0, 0], grad[1, 1], grad[2, 2], g[0, 1], g[1, 2], g[2, 0]])


def socp_step(mat, comps, grad, sig_n):
    mesh = patch(grad.shape[0])
    d, n = mesh.dim(), mesh.p.shape[1]
    fixed = np.zeros((n, d), bool)
    fixed[mesh.boundary_nodes()] = True
    data = ConeInput(
        operator=nodal_integration(mesh, comps),
        materials=[mat],
        material=np.zeros(n, int),
        sigma_n=np.tile(sig_n, (n, 1)),
        force=np.zeros((n, d)),
        fixed=fixed,
        du_prescribed=mesh.p.T @ grad.T,
        contacts=Contacts.empty(d),
    )
    return solve_step(data, OPTIONS)


CASES = [
    # name, material, comps, grad (units of c/E), sigma_n (units of c)
    (
        "mc-frozen-shear",
        MohrCoulomb(E, NU, c=C, phi=30.0, psi=5.0, tension_cutoff=True),
        (0, 1, 3),
        [[0.5, 8.0], [0.0, -1.0]],
        [-3.0, -5.0, -4.0, 0.5],
    ),
    (
        "mc-tension-cutoff",
        MohrCoulomb(E, NU, c=C, phi=30.0, psi=0.0, tension_cutoff=True),
        (0, 1, 3),
        [[9.0, 0.5], [0.5, 8.0]],
        [-1.0, -1.2, -1.0, 0.0],
    ),
    (
        "tresca-shear",
        Tresca(E, NU, c=C),
        (0, 1, 3),
        [[1.0, 10.0], [0.0, -2.0]],
        [-2, -2, -2, 0],
    ),
    (
        "dp-plane-strain",
        DruckerPrager(E, NU, c=C, phi=20.0, psi=0.0, tension_cutoff=True),
        (0, 1, 2, 3),
        [[2.0, 7.0], [-1.0, -3.0]],
        [-4.0, -6.0, -5.0, 1.0],
    ),
    (
        "von-mises-2d",
        VonMises(E, NU, sigma_y=math.sqrt(3) * C),
        (0, 1, 2, 3),
        [[3, 4], [1, -2]],
        [0, 0, 0, 0],
    ),
    (
        "dp-3d",
        DruckerPrager(E, NU, c=C, phi=30.0, match="compression"),
        tuple(range(6)),
        [[4.0, 15.0, -3.0], [0.0, -8.0, 9.0], [3.0, 6.0, 2.0]],
        [-5.0, -6.0, -4.0, 0.2, -0.1, 0.3],
    ),
    (
        "von-mises-3d",
        VonMises(E, NU, sigma_y=math.sqrt(3) * C),
        tuple(range(6)),
        [[2.0, 5.0, -1.0], [0.0, -4.0, 3.0], [1.0, 2.0, 1.0]],
        [0.0] * 6,
    ),
]


@pytest.mark.parametrize(
    ("name", "mat", "comps", "grad", "sig_n"), CASES, ids=[c[0] for c in CASES]
)
def test_closed_form_equals_cone_step(name, mat, comps, grad, sig_n):
    grad = np.asarray(grad, float) * C / E
    dim = grad.shape[0]
    sig_n = np.asarray(sig_n, float) * C
    ref = socp_step(mat, comps, grad, sig_n)
    mats = [mat]
    ids = np.zeros(1, int)
    trial = elastic_trial(mats, ids, dim, sig_n[None], voigt(grad)[None])
    out = return_map(mats, ids, dim, trial, sig_n[None])
    assert out.plastic[0], "the case must be plastic to test the return"
    assert np.max(np.abs(ref.sigma - out.sigma[0])) < TOL
    # Plastic strains agree with the SOCP's (B du - C ds) to its accuracy.
    dp_ref = ref.deps_p.mean(axis=0)
    assert np.max(np.abs(dp_ref - out.deps_p[0])) < 1e-3 * np.max(np.abs(voigt(grad)))


def test_elastic_trials_are_untouched_and_returns_lie_on_the_cone():
    mat = MohrCoulomb(E, NU, c=C, phi=30.0, psi=10.0)
    rng = np.random.default_rng(3)
    sig_n = np.tile([-5 * C, -5 * C, -5 * C, 0.0], (400, 1))
    deps = rng.normal(size=(400, 4)) * 6 * C / E
    deps[:, 2] = 0.0
    ids = np.zeros(400, int)
    trial = elastic_trial([mat], ids, 2, sig_n, deps)
    out = return_map([mat], ids, 2, trial, sig_n)
    assert 50 < out.plastic.sum() < 350  # both kinds present
    el = ~out.plastic
    assert np.array_equal(out.sigma[el], trial[el])
    assert np.all(out.deps_p[el] == 0)
    # Plastic points on the frozen-friction cone: 2R = k - 2 sin(psi) p (1e-12).
    s = out.sigma[out.plastic]
    R = np.hypot(0.5 * (s[:, 0] - s[:, 1]), s[:, 3])
    p = 0.5 * (s[:, 0] + s[:, 1])
    f, fp = math.radians(30.0), math.radians(10.0)
    k = 2 * C * math.cos(f) + 2 * (math.sin(f) - math.sin(fp)) * 5 * C
    assert np.max(np.abs(2 * R - (k - 2 * math.sin(fp) * p))) < 1e-9 * C
    # Flow rule of the psi cone: volumetric plastic strain = sin(psi) * shear.
    dp = out.deps_p[out.plastic]
    vol = dp[:, 0] + dp[:, 1]
    gam = np.hypot(dp[:, 0] - dp[:, 1], dp[:, 3])
    assert np.max(np.abs(vol - math.sin(fp) * gam)) < 1e-9 * gam.max()


def test_projection_polygon_cases():
    # Hand-computed projections in the (p, r) plane with K = G = 1:
    # cone r <= 1 - p (B = 1), cut-off p <= 0.5.
    cases = [
        ((0.0, 0.5), (0.0, 0.5)),  # inside
        ((0.0, 2.0), (-0.5, 1.5)),  # normal to the cone line
        ((2.0, 0.2), (0.5, 0.2)),  # straight onto the cut-off
        ((1.0, 1.0), (0.5, 0.5)),  # the corner
    ]
    for (p, r), (pe, re) in cases:
        pp, rr = project_invariants(p, r, 1.0, 1.0, 1.0, 1.0, 0.5)
        assert abs(pp - pe) < 1e-14 and abs(rr - re) < 1e-14
    # Without cut-off, far in tension: the apex (1, 0).
    pp, rr = project_invariants(5.0, 0.1, 1.0, 1.0, 1.0, 1.0, np.inf)
    assert abs(pp - 1.0) < 1e-14 and rr == 0.0
