"""Gauss-point operators of the FEM baseline and its cone program.

References: the patch test (docs/verification.md: a linear displacement gives the
exact constant strain at every Gauss point), scikit-fem's own assembly of
``int sigma : eps(v)`` (the operator must equal it), the element area, the
HRZ lumping fractions of the P2 triangle/tet (1/19, 16/57; 1/36, 4/27, from
the consistent mass matrix diagonals 1/30 : 8/45 and 1/70 : 8/105).  The
library's cone step with stress points other than the nodes is tested in
``tests/step/test_stress_points.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from skfem import (
    Basis,
    ElementTetP2,
    ElementTriP2,
    ElementVector,
    LinearForm,
    MeshTet,
    MeshTri,
    asm,
)

from skfem_npfem.baseline import gauss_mesh
from skfem_npfem.baseline.operators import body_force, lumped_masses, quadrature

FULL = {2: (0, 1, 2, 3), 3: (0, 1, 2, 3, 4, 5)}


def jittered(dim: int, n: int = 4, seed: int = 0):
    rng = np.random.default_rng(seed)
    axes = [np.linspace(0.0, 1.0 + k, n) for k in range(dim)]
    m = MeshTri.init_tensor(*axes) if dim == 2 else MeshTet.init_tensor(*axes)
    x = m.p.T.copy()
    inner = np.setdiff1d(np.arange(x.shape[0]), m.boundary_nodes())
    x[inner] += 0.2 / n * rng.uniform(-1, 1, (inner.size, dim))
    return x, m.t


def voigt(grad: np.ndarray) -> np.ndarray:
    if grad.shape[0] == 2:
        return np.array([grad[0, 0], grad[1, 1], 0.0, grad[0, 1] + grad[1, 0]])
    return np.array(
        [
            grad[0, 0],
            grad[1, 1],
            grad[2, 2],
            grad[0, 1] + grad[1, 0],
            grad[1, 2] + grad[2, 1],
            grad[2, 0] + grad[0, 2],
        ]
    )


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("element", ["p1", "p2"])
def test_patch_test_and_weights(dim, element):
    # Patch test: u = a + A x gives eps = sym(A) at every Gauss point (1e-12) and the
    # displacement gradient A; the weights sum to the domain measure.
    x, t = jittered(dim, seed=1)
    gm = gauss_mesh(x, t, element, FULL[dim])
    nq = {("p1", 2): 1, ("p1", 3): 1, ("p2", 2): 3, ("p2", 3): 4}[(element, dim)]
    assert gm.nq == nq and gm.points.n_points == nq * t.shape[1]
    A = np.random.default_rng(2).normal(size=(dim, dim))
    u = gm.node_x @ A.T + 0.3
    assert np.max(np.abs(gm.points.strain(u) - voigt(A))) < 1e-12
    assert np.max(np.abs(gm.points.gradient(u) - A)) < 1e-12
    area = 2.0 if dim == 2 else 6.0  # [0,1] x [0,2] (x [0,3])
    assert abs(gm.points.volumes.sum() - area) < 1e-12


@pytest.mark.parametrize("dim", [2, 3])
def test_G_equals_scikit_fem_linear_form(dim):
    # u^T G s = int s(x) : eps(u) dx with the same quadrature, assembled by
    # scikit-fem's asm of a LinearForm (independent of our COO assembly).
    x, t = jittered(dim, seed=3)
    gm = gauss_mesh(x, t, "p2", FULL[dim])

    def field(p):  # a smooth stress field, full Voigt
        cols = [
            np.sin(p[0] + k) * np.cos(0.7 * p[-1] - k) for k in range(len(FULL[dim]))
        ]
        return np.stack(cols)

    sig = field(gm.gp_x.T).T  # (n_points, n_s)
    f_ours = gm.points.G @ sig.reshape(-1)
    bary, w = quadrature(dim, "p2")
    el = ElementVector(ElementTriP2() if dim == 2 else ElementTetP2())
    basis = Basis(gm.mesh, el, quadrature=(bary[:, 1:].T.copy(), w))

    @LinearForm
    def work(v, wp):
        s = field(wp.x)
        g = v.grad
        eps = [g[0, 0], g[1, 1]]
        if dim == 2:
            eps += [0 * g[0, 0], g[0, 1] + g[1, 0]]
        else:
            eps += [g[2, 2], g[0, 1] + g[1, 0], g[1, 2] + g[2, 1], g[2, 0] + g[0, 2]]
        return sum(s[k] * eps[k] for k in range(len(eps)))

    f_skfem = asm(work, basis)
    assert np.max(np.abs(f_ours - f_skfem)) < 1e-12 * np.max(np.abs(f_skfem))


@pytest.mark.parametrize(
    ("dim", "vertex", "edge"), [(2, 1 / 19, 16 / 57), (3, 1 / 36, 4 / 27)]
)
def test_hrz_masses_and_consistent_load(dim, vertex, edge):
    # One element: HRZ fractions of its mass (1e-12); a mesh: masses positive
    # and summing to rho |Omega|; consistent load summing to rho g |Omega|.
    m = (MeshTri if dim == 2 else MeshTet)()
    one = (m.p.T, m.t[:, :1])
    x, t = one[0][np.unique(one[1])], one[1]
    gm = gauss_mesh(x, t, "p2", FULL[dim])
    mass = lumped_masses(gm, np.array([1.0]))
    vol = gm.points.volumes.sum()
    assert np.allclose(mass[: dim + 1] / vol, vertex, rtol=1e-12)
    assert np.allclose(mass[dim + 1 :] / vol, edge, rtol=1e-12)
    x, t = jittered(dim, seed=4)
    gm = gauss_mesh(x, t, "p2", FULL[dim])
    rho = np.full(t.shape[1], 1800.0)
    mass = lumped_masses(gm, rho)
    assert mass.min() > 0
    assert abs(mass.sum() / (1800.0 * gm.points.volumes.sum()) - 1) < 1e-12
    g = np.zeros(dim)
    g[-1] = -9.81
    f = body_force(gm, rho, g)
    assert abs(f[:, -1].sum() / (-9.81 * mass.sum()) - 1) < 1e-12
