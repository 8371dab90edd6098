"""Nodal (smoothing-cell) integration: patch tests and the scikit-fem identity.

References (docs/verification.md, "The reference cases"): smoothing cells
(they partition the domain), the patch test (smoothed strain exact for linear
fields), divergence consistency, zero-energy modes; docs/theory.md, "Nodal
integration" (G is the scikit-fem bilinear form (tau, v) -> ∫ tau·eps(v)).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay
from skfem import (
    Basis,
    BilinearForm,
    ElementTetP1,
    ElementTriP1,
    ElementVector,
    MeshTet,
    MeshTri,
)

from skfem_npfem.materials import compliance_matrix
from skfem_npfem.mesh.smoothing import nodal_integration, p1_gradients

# Voigt rows of the full vector: (row, displacement component k, direction j),
# engineering shear, written out independently of the library's table.
VOIGT_2D = {0: [(0, 0)], 1: [(1, 1)], 2: [], 3: [(0, 1), (1, 0)]}
VOIGT_3D = {
    0: [(0, 0)],
    1: [(1, 1)],
    2: [(2, 2)],
    3: [(0, 1), (1, 0)],
    4: [(1, 2), (2, 1)],
    5: [(2, 0), (0, 2)],
}


def jittered_square(nx: int = 9, ny: int = 7, amount: float = 0.3, seed: int = 0):
    """Structured mesh of [0,2]x[0,1] with interior nodes moved up to amount*h."""
    rng = np.random.default_rng(seed)
    m = MeshTri.init_tensor(np.linspace(0, 2, nx), np.linspace(0, 1, ny))
    p = m.p.copy()
    h = min(2 / (nx - 1), 1 / (ny - 1))
    interior = np.setdiff1d(np.arange(p.shape[1]), m.boundary_nodes())
    p[:, interior] += amount * h * rng.uniform(-1, 1, (2, interior.size))
    return MeshTri(p, m.t), 2.0


def random_delaunay(n: int = 60, seed: int = 1):
    """Delaunay mesh of random points in the unit square plus its corners."""
    rng = np.random.default_rng(seed)
    pts = np.vstack([[0, 0], [1, 0], [1, 1], [0, 1], rng.uniform(0, 1, (n, 2))])
    tri = Delaunay(pts)
    return MeshTri(pts.T.copy(), tri.simplices.T.copy()), 1.0


def jittered_cube(seed: int = 2, refine: int = 2):
    """MeshTet().refined(refine) with interior nodes jittered by up to 0.2 h."""
    rng = np.random.default_rng(seed)
    m = MeshTet().refined(refine)
    p = m.p.copy()
    h = 0.5**refine
    interior = np.setdiff1d(np.arange(p.shape[1]), m.boundary_nodes())
    p[:, interior] += 0.2 * h * rng.uniform(-1, 1, (3, interior.size))
    return MeshTet(p, m.t), 1.0


MESHES_2D = [jittered_square, random_delaunay]


def exact_voigt_strain(grad: np.ndarray) -> np.ndarray:
    """Full-Voigt engineering strain of a constant gradient du_k/dx_j."""
    table = VOIGT_2D if grad.shape[0] == 2 else VOIGT_3D
    return np.array([sum(grad[k, j] for k, j in table[s]) for s in sorted(table)])


@pytest.mark.parametrize("make_mesh", [*MESHES_2D, jittered_cube])
def test_patch_test_linear_field_exact(make_mesh):
    mesh, _ = make_mesh()
    d = mesh.dim()
    rng = np.random.default_rng(3)
    grad = rng.normal(size=(d, d))
    a = rng.normal(size=d)
    u = a[None, :] + mesh.p.T @ grad.T  # u_k = a_k + grad[k, j] x_j
    ni = nodal_integration(mesh)
    eps = ni.strain(u)
    exact = exact_voigt_strain(grad)
    # Patch test: exact to round-off at every node, boundary nodes included (1e-12).
    assert np.max(np.abs(eps - exact[None, :])) < 1e-12
    bnd = mesh.boundary_nodes()
    assert np.max(np.abs(eps[bnd] - exact[None, :])) < 1e-12
    # Smoothed gradient of a linear field equals its constant gradient (1e-12).
    assert np.max(np.abs(ni.gradient(u) - grad[None])) < 1e-12


@pytest.mark.parametrize("make_mesh", MESHES_2D)
def test_patch_test_component_subset(make_mesh):
    mesh, _ = make_mesh()
    rng = np.random.default_rng(4)
    grad = rng.normal(size=(2, 2))
    u = mesh.p.T @ grad.T
    ni = nodal_integration(mesh, components=(0, 1, 3))
    assert ni.G.shape == (2 * mesh.p.shape[1], 3 * mesh.p.shape[1])
    exact = exact_voigt_strain(grad)[[0, 1, 3]]
    # (xx, yy, xy) subset is exact too (1e-12).
    assert np.max(np.abs(ni.strain(u) - exact[None, :])) < 1e-12


@pytest.mark.parametrize("make_mesh", [*MESHES_2D, jittered_cube])
def test_cell_volumes_partition_domain(make_mesh):
    mesh, measure = make_mesh()
    ni = nodal_integration(mesh)
    # Sum of smoothing cells = domain measure (1e-12 relative).
    assert abs(ni.volumes.sum() - measure) < 1e-12 * measure
    # Independent per-node value: |e|/(d+1) of every simplex from the determinant
    # of its edge vectors (1e-12 relative).
    p, t, d = mesh.p.T, mesh.t, mesh.dim()
    edges = np.stack([p[t[k]] - p[t[0]] for k in range(1, d + 1)], axis=-1)
    vol = np.abs(np.linalg.det(edges)) / (2.0 if d == 2 else 6.0)
    ref = np.zeros(p.shape[0])
    for k in range(d + 1):
        np.add.at(ref, t[k], vol / (d + 1))
    assert np.max(np.abs(ni.volumes - ref)) < 1e-12 * ref.max()
    _, vol_lib = p1_gradients(mesh)
    assert np.max(np.abs(vol_lib - vol)) < 1e-12 * vol.max()


@pytest.mark.parametrize("make_mesh", [*MESHES_2D, jittered_cube])
def test_rows_annihilate_constants(make_mesh):
    mesh, _ = make_mesh()
    d, n = mesh.dim(), mesh.p.shape[1]
    ni = nodal_integration(mesh)
    scale = abs(ni.G).max()
    for k in range(d):
        u = np.zeros((n, d))
        u[:, k] = 1.0
        # Rigid translation: zero smoothed strain and gradient (1e-12 relative).
        assert np.max(np.abs(ni.G.T @ u.ravel())) < 1e-12 * scale
        assert np.max(np.abs(ni.gradient(u))) < 1e-12


def test_divergence_consistency_boundary_traction():
    # Divergence consistency: G @ (constant stress) is the consistent nodal
    # force of the boundary traction sigma·n (interior nodes: zero).  Reference
    # computed edge by edge.
    mesh, _ = jittered_square()
    n = mesh.p.shape[1]
    sig = np.array([1.3, -0.7, 0.4, 0.25])  # xx, yy, zz, xy
    ni = nodal_integration(mesh)
    f = (ni.G @ np.tile(sig, n)).reshape(n, 2)
    S = np.array([[sig[0], sig[3]], [sig[3], sig[1]]])
    ref = np.zeros((n, 2))
    centre = mesh.p.mean(axis=1)
    for facet in mesh.boundary_facets():
        i, j = mesh.facets[:, facet]
        e = mesh.p[:, j] - mesh.p[:, i]
        normal = np.array([e[1], -e[0]])  # length = edge length
        mid = 0.5 * (mesh.p[:, i] + mesh.p[:, j])
        if normal @ (mid - centre) < 0:
            normal = -normal
        ref[i] += 0.5 * S @ normal
        ref[j] += 0.5 * S @ normal
    # Agreement to round-off (1e-12 relative to the largest force).
    assert np.max(np.abs(f - ref)) < 1e-12 * np.abs(ref).max()


def _skfem_G(mesh, components):
    """G from scikit-fem: (tau, v) -> ∫ tau · eps(v), permuted to node-major."""
    d = mesh.dim()
    elem = ElementTriP1() if d == 2 else ElementTetP1()
    ns = len(components)
    btau = Basis(mesh, ElementVector(elem, ns), intorder=2)
    bv = Basis(mesh, ElementVector(elem, d), intorder=2)
    table = VOIGT_2D if d == 2 else VOIGT_3D

    @BilinearForm
    def work(tau, v, w):
        out = 0.0
        for pos, s in enumerate(components):
            for k, j in table[s]:  # engineering shear: tau_xy (du_x/dy + du_y/dx)
                out = out + tau[pos] * v.grad[k, j]
        return out

    A = work.assemble(btau, bv).toarray()  # (v dofs, tau dofs)
    n = mesh.p.shape[1]
    # Map scikit-fem dofs to node-major order explicitly (nodal_dofs[c, i]).
    row_perm = np.empty(d * n, int)
    col_perm = np.empty(ns * n, int)
    for c in range(d):
        row_perm[np.arange(n) * d + c] = bv.nodal_dofs[c]
    for c in range(ns):
        col_perm[np.arange(n) * ns + c] = btau.nodal_dofs[c]
    return A[np.ix_(row_perm, col_perm)]


@pytest.mark.parametrize(
    ("make_mesh", "components"),
    [
        (jittered_square, (0, 1, 2, 3)),
        (jittered_square, (0, 1, 3)),
        (random_delaunay, (0, 1, 2, 3)),
        (lambda: jittered_cube(refine=1), (0, 1, 2, 3, 4, 5)),
    ],
)
def test_G_equals_scikit_fem_bilinear_form(make_mesh, components):
    mesh, _ = make_mesh()
    ni = nodal_integration(mesh, components)
    ref = _skfem_G(mesh, components)
    G = ni.G.toarray()
    # Assembly identity of docs/theory.md, "Nodal integration" (1e-12 relative,
    # Frobenius).
    assert np.linalg.norm(G - ref) < 1e-12 * np.linalg.norm(ref)


def _nodal_stiffness(mesh, E=1.0, nu=0.3):
    d = mesh.dim()
    comps = (0, 1, 2, 3) if d == 2 else (0, 1, 2, 3, 4, 5)
    ni = nodal_integration(mesh, comps)
    D = np.linalg.inv(compliance_matrix(E, nu, d, comps))
    n = mesh.p.shape[1]
    G = ni.G.toarray()
    Dblk = np.zeros((n * len(comps), n * len(comps)))
    for i in range(n):
        sl = slice(i * len(comps), (i + 1) * len(comps))
        Dblk[sl, sl] = D / ni.volumes[i]
    return G @ Dblk @ G.T


@pytest.mark.parametrize(
    ("make_mesh", "n_rigid"),
    [
        (lambda: jittered_square(7, 5), 3),
        (lambda: random_delaunay(25), 3),
        (lambda: jittered_cube(refine=1), 6),
    ],
)
def test_zero_energy_modes_are_rigid_only(make_mesh, n_rigid):
    # Zero-energy modes: a free patch has exactly the rigid-body zero eigenvalues
    # (|lambda| < 1e-10 max lambda); more zeros would be spurious modes.
    mesh, _ = make_mesh()
    K = _nodal_stiffness(mesh)
    lam = np.linalg.eigvalsh(K)
    zero = np.abs(lam) < 1e-10 * lam.max()
    assert int(zero.sum()) == n_rigid
    # The first deformation mode is clearly separated from round-off (> 1e-6).
    assert lam[n_rigid] > 1e-6 * lam.max()


def test_unused_node_raises():
    m = MeshTri().refined(1)
    # An extra node after all used ones...
    p_extra = np.hstack([m.p, [[0.5], [2.0]]])
    with pytest.raises(ValueError, match="every mesh node"):
        nodal_integration(MeshTri(p_extra, m.t))
    # ...and an unused node in the middle of the numbering.
    t = m.t.copy()
    t[t >= 3] += 1
    p_mid = np.hstack([m.p[:, :3], [[0.5], [2.0]], m.p[:, 3:]])
    with pytest.raises(ValueError, match="every mesh node"):
        nodal_integration(MeshTri(p_mid, t))
