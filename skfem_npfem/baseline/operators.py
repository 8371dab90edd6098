"""Stress-point operators: Gauss points of scikit-fem P1/P2 elements.

The cone step of N-PFEM needs, for a set of *stress points* ``g``, the weights
``w_g`` and the internal-force operator ``G = [w_1 B_1^T, ..., w_n B_n^T]`` so
that ``f_int = G @ sigma``.  With nodal integration the stress points are the
mesh nodes (``w_i = V_i``, :mod:`skfem_npfem.mesh.smoothing`); for the classical FEM
baseline they are the Gauss points of the elements (``w_g = W_q |det J_e|``).
:class:`StressPoints` is that Gauss-point operator; it implements the
:class:`~skfem_npfem.step.program.StrainOperator` protocol, so the library's one
cone program (:func:`skfem_npfem.step.conic.solve_step`) serves both.

The Gauss-point operator is built from a scikit-fem ``Basis`` of
``ElementVector(ElementTriP1|ElementTriP2|ElementTetP1|ElementTetP2)`` with an
explicit quadrature rule: ``basis.basis[j][0].grad`` (shape ``(d, d, ne, nq)``)
gives the displacement gradient of local dof ``j`` at every Gauss point and
``basis.dx`` the weights, so ``G`` is one COO assembly over
``(local dof, Voigt row, element, point)`` - no element loop.

Displacement nodes are the mesh vertices (the particles) followed, for P2, by
one node per mesh edge (straight-sided, at the edge midpoint).  scikit-fem's
global dof numbering of a vector element is already node-major over exactly
this node list (``u_0x, u_0y, u_1x, ...``); :func:`gauss_mesh` checks that.

Quadrature rules (barycentric points, weights on the reference simplex):

==========  ======  =================================================
element     points  rule
==========  ======  =================================================
P1 tri/tet  1       centroid (exact for the constant strain)
P2 tri      3       (1/6, 1/6, 2/3) permutations, degree 2
P2 tet      4       (a, b, b, b) permutations, a = 0.5854..., degree 2
==========  ======  =================================================
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import (
    Basis,
    ElementTetP1,
    ElementTetP2,
    ElementTriP1,
    ElementTriP2,
    ElementVector,
    LinearForm,
    Mesh,
    asm,
)

from ..errors import ParameterError
from ..mesh.delaunay import p1_mesh

__all__ = [
    "ELEMENTS",
    "GaussMesh",
    "StressPoints",
    "gauss_mesh",
    "quadrature",
]

#: Element orders of the FEM baseline.
ELEMENTS = ("p1", "p2")

# Voigt rows from the displacement gradient g[k, l] = du_k/dx_l (engineering
# shear): list of (k, l) pairs summed into each full-Voigt row.
_VOIGT_GRAD = {
    2: (((0, 0),), ((1, 1),), (), ((0, 1), (1, 0))),
    3: (
        ((0, 0),),
        ((1, 1),),
        ((2, 2),),
        ((0, 1), (1, 0)),
        ((1, 2), (2, 1)),
        ((2, 0), (0, 2)),
    ),
}


def quadrature(dim: int, element: str) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric Gauss points and reference weights of the baseline rules.

    Parameters
    ----------
    dim : int
        2 or 3.
    element : {"p1", "p2"}

    Returns
    -------
    bary : ndarray (nq, d+1)
        Barycentric coordinates of the points (first column: vertex 0).
    weights : ndarray (nq,)
        Weights on the reference simplex (sum 1/2 in 2D, 1/6 in 3D).

    Examples
    --------
    >>> bary, w = quadrature(2, "p2")
    >>> bary.shape, float(w.sum())
    ((3, 3), 0.5)
    """
    ref = 0.5 if dim == 2 else 1.0 / 6.0
    if element == "p1":
        return np.full((1, dim + 1), 1.0 / (dim + 1)), np.array([ref])
    if dim == 2:
        a, b = 2.0 / 3.0, 1.0 / 6.0
    else:
        a = (5.0 + 3.0 * np.sqrt(5.0)) / 20.0
        b = (5.0 - np.sqrt(5.0)) / 20.0
    bary = np.full((dim + 1, dim + 1), b)
    np.fill_diagonal(bary, a)
    return bary, np.full(dim + 1, ref / (dim + 1))


@dataclass(frozen=True)
class StressPoints:
    """Gauss points of one mesh as a strain operator of the cone program.

    Implements :class:`~skfem_npfem.step.program.StrainOperator` with its own number
    of stress points (``n_points = nq * n_elements``), separate from the
    displacement nodes, so :func:`skfem_npfem.step.conic.solve_step` solves the
    FEM step unchanged.

    Attributes
    ----------
    dim : int
        Spatial dimension.
    components : tuple of int
        Full-Voigt components carried as stress variables.
    volumes : ndarray (n_points,)
        Integration weight ``w_q |det J_e|`` of each point.
    G : scipy.sparse.csc_matrix (d * n_nodes, n_points * n_s)
        ``f_int = G @ sigma`` (node-major dofs, point-major stresses).
    nodes : int
        Number of displacement nodes.
    grad : scipy.sparse.csr_matrix (n_points * d * d, d * n_nodes)
        Displacement gradient at the points: ``(grad @ u).reshape(-1, d, d)``.
    """

    dim: int
    components: tuple[int, ...]
    volumes: np.ndarray
    G: sp.csc_matrix
    nodes: int
    grad: sp.csr_matrix

    @property
    def n_nodes(self) -> int:
        """Number of displacement nodes."""
        return int(self.nodes)

    @property
    def n_points(self) -> int:
        """Number of stress points."""
        return int(self.volumes.shape[0])

    def check(self) -> None:
        """Refuse a mesh with degenerate elements (zero or non-finite weights)."""
        bad = ~(np.isfinite(self.volumes) & (self.volumes > 0))
        if np.any(bad):
            raise ParameterError(
                "mesh",
                f"{int(bad.sum())} Gauss point(s) of zero or non-finite weight "
                f"(first {int(np.flatnonzero(bad)[0])})",
                "elements of nonzero size",
            )

    def strain(self, u: np.ndarray) -> np.ndarray:
        """Strains (engineering shear) at the points, shape (n_points, n_s)."""
        u = np.asarray(u, dtype=float).reshape(-1)
        return (self.G.T @ u).reshape(self.n_points, -1) / self.volumes[:, None]

    def gradient(self, u: np.ndarray) -> np.ndarray:
        """Displacement gradients ``du_k/dx_l`` at the points, (n_points, d, d)."""
        u = np.asarray(u, dtype=float).reshape(-1)
        return (self.grad @ u).reshape(-1, self.dim, self.dim)


@dataclass(frozen=True)
class GaussMesh:
    """A P1 particle mesh seen as P1 or P2 finite elements.

    Attributes
    ----------
    mesh : skfem.MeshTri or skfem.MeshTet
        The P1 mesh on the active particles (vertex ``i`` = active particle ``i``).
    element : {"p1", "p2"}
    basis : skfem.Basis
        The vector basis the operators came from.
    points : StressPoints
        Gauss points (point ``e * nq + q`` is point ``q`` of element ``e``).
    node_x : ndarray (n_nodes, d)
        Displacement-node positions: vertices, then (P2) edge midpoints.
    edges : ndarray (n_edges, 2)
        Vertex pairs of the mid-edge nodes (empty for P1); mid-edge node ``j``
        is displacement node ``n_vertices + j``.
    gp_x : ndarray (n_points, d)
        Gauss-point coordinates.
    nq : int
        Gauss points per element.
    """

    mesh: Mesh
    element: str
    basis: Basis
    points: StressPoints
    node_x: np.ndarray
    edges: np.ndarray
    gp_x: np.ndarray
    nq: int

    @property
    def n_vertices(self) -> int:
        """Number of mesh vertices (active particles)."""
        return int(self.mesh.p.shape[1])

    @property
    def n_elements(self) -> int:
        """Number of elements."""
        return int(self.mesh.t.shape[1])

    def scalar_basis(self, intorder: int) -> Basis:
        """Scalar basis of the same element with a quadrature of ``intorder``."""
        return Basis(
            self.mesh, _scalar_element(self.mesh.dim(), self.element), intorder=intorder
        )


def _scalar_element(dim: int, element: str):
    table = {
        (2, "p1"): ElementTriP1,
        (2, "p2"): ElementTriP2,
        (3, "p1"): ElementTetP1,
        (3, "p2"): ElementTetP2,
    }
    return table[(dim, element)]()


def _mid_edges(basis: Basis, dim: int, n_vert: int) -> np.ndarray:
    """Vertex pairs of the P2 mid-edge nodes in scikit-fem's dof order."""
    mesh = basis.mesh
    # Edges are facets in 2D and edges in 3D.
    pairs = mesh.facets if dim == 2 else mesh.edges
    dofs = basis.facet_dofs if dim == 2 else basis.edge_dofs
    expect = (
        dim * (n_vert + np.arange(pairs.shape[1]))[None, :] + np.arange(dim)[:, None]
    )
    if not np.array_equal(dofs, expect):
        raise RuntimeError("unexpected scikit-fem dof order of the P2 edge nodes")
    return np.ascontiguousarray(pairs.T)


def gauss_mesh(
    x: np.ndarray, t: np.ndarray, element: str, components: tuple[int, ...]
) -> GaussMesh:
    """Build the Gauss-point operators of P1 or P2 elements on a particle mesh.

    Parameters
    ----------
    x : ndarray (N, d)
        Vertex (particle) positions.
    t : ndarray (d+1, ne)
        Connectivity on the vertices (every vertex used).
    element : {"p1", "p2"}
        Linear (1 Gauss point) or quadratic (3 in 2D / 4 in 3D) elements.
    components : tuple of int
        Full-Voigt stress components kept as variables.

    Returns
    -------
    GaussMesh

    Examples
    --------
    >>> from skfem import MeshTri
    >>> m = MeshTri().refined(1)
    >>> gm = gauss_mesh(m.p.T, m.t, "p2", (0, 1, 3))
    >>> gm.points.n_points, gm.node_x.shape[0]
    (24, 25)
    >>> round(float(gm.points.volumes.sum()), 12)
    1.0
    """
    if element not in ELEMENTS:
        raise ParameterError("element", element, f"one of {ELEMENTS}")
    dim = x.shape[1]
    mesh = p1_mesh(x, t)
    bary, wref = quadrature(dim, element)
    X = np.ascontiguousarray(bary[:, 1:].T)  # reference coordinates (d, nq)
    basis = Basis(
        mesh, ElementVector(_scalar_element(dim, element)), quadrature=(X, wref)
    )
    n_vert = mesh.p.shape[1]
    nodal = basis.nodal_dofs
    if not np.array_equal(
        nodal, dim * np.arange(n_vert)[None, :] + np.arange(dim)[:, None]
    ):
        raise RuntimeError("unexpected scikit-fem dof order of the vertex nodes")
    edges = _mid_edges(basis, dim, n_vert) if element == "p2" else np.zeros((0, 2), int)
    n_nodes = n_vert + edges.shape[0]
    G, grad, weights = _assemble(basis, dim, components, n_nodes)
    ne, nq = basis.dx.shape
    # Straight-sided (affine) elements: Gauss points from the barycentric rule.
    gp_x = np.einsum("qa,aed->eqd", bary, x[t]).reshape(ne * nq, dim)
    node_x = np.concatenate([x, 0.5 * (x[edges[:, 0]] + x[edges[:, 1]])])
    pts = StressPoints(dim, tuple(components), weights, G, n_nodes, grad)
    return GaussMesh(mesh, element, basis, pts, node_x, edges, gp_x, nq)


def _assemble(basis: Basis, dim: int, components, n_nodes: int):
    """COO assembly of G and of the gradient operator from the basis arrays."""
    ne, nq = basis.dx.shape
    nb = basis.Nbfun
    ns = len(components)
    # grads[j, k, l, e, q]: du_k/dx_l of local vector dof j.
    grads = np.stack([np.asarray(basis.basis[j][0].grad) for j in range(nb)])
    dofs = basis.element_dofs  # (nb, ne)
    point = np.arange(ne)[:, None] * nq + np.arange(nq)[None, :]  # (ne, nq)
    rows, cols, vals = [], [], []
    for s, comp in enumerate(components):  # at most 6 Voigt rows, not elements
        pairs = _VOIGT_GRAD[dim][comp]
        if not pairs:
            continue  # eps_zz = 0 in plane strain: no column entries
        b = sum(grads[:, k, j] for k, j in pairs)  # (nb, ne, nq)
        rows.append(np.broadcast_to(dofs[:, :, None], b.shape))
        cols.append(np.broadcast_to((point * ns + s)[None], b.shape))
        vals.append(b * basis.dx[None])
    ndof = dim * n_nodes
    G = sp.csc_matrix(
        (
            np.concatenate([v.ravel() for v in vals]),
            (
                np.concatenate([r.ravel() for r in rows]),
                np.concatenate([c.ravel() for c in cols]),
            ),
        ),
        shape=(ndof, ne * nq * ns),
    )
    # Gradient operator: row (point, k, l), column dof j.
    kl = np.arange(dim * dim)
    g_rows = point[None, :, :, None] * dim * dim + kl[None, None, None, :]
    g_vals = np.moveaxis(grads.reshape(nb, dim * dim, ne, nq), 1, -1)
    grad = sp.csr_matrix(
        (
            g_vals.ravel(),
            (
                np.broadcast_to(g_rows, g_vals.shape).ravel(),
                np.broadcast_to(dofs[:, :, None, None], g_vals.shape).ravel(),
            ),
        ),
        shape=(ne * nq * dim * dim, ndof),
    )
    return G, grad, np.asarray(basis.dx).reshape(-1).copy()


def lumped_masses(gm: GaussMesh, rho_e: np.ndarray) -> np.ndarray:
    """Diagonal (HRZ) lumped masses of the displacement nodes, kg.

    Hinton-Rock-Zienkiewicz lumping: the diagonal of each element's consistent
    mass matrix, scaled so that the element keeps its mass ``rho_e |e|``.  It is
    positive for P2 (vertex : mid-edge = 3 : 16 on triangles and tets, i.e.
    1/19 and 16/57 of a triangle's mass, 1/36 and 4/27 of a tet's), unlike
    the row sum, which gives P2 vertices zero (triangles) or negative (tets)
    mass.  For P1 it equals the row sum, ``rho_e |e| / (d+1)``.

    Parameters
    ----------
    gm : GaussMesh
    rho_e : ndarray (ne,)
        Element densities, kg/m^d.

    Returns
    -------
    ndarray (n_nodes,)
    """
    sb = gm.scalar_basis(4)  # degree-4 rule: exact for phi_j^2 with P2
    vals = np.stack([np.asarray(sb.basis[j][0]) for j in range(sb.Nbfun)])
    dx = np.asarray(sb.dx)  # (ne, nq)
    diag = np.einsum("jeq,eq->je", vals**2, dx)  # (nb, ne)
    mass_e = rho_e * dx.sum(axis=1)
    share = diag / diag.sum(axis=0, keepdims=True) * mass_e[None, :]
    n_nodes = gm.node_x.shape[0]
    return np.bincount(sb.element_dofs.ravel(), share.ravel(), minlength=n_nodes)


def body_force(gm: GaussMesh, rho_e: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Consistent nodal body force ``int rho_e g phi_j dx``, shape (n_nodes, d).

    Assembled with scikit-fem's ``asm`` of a ``LinearForm`` on the scalar basis
    (for P2 the vertex loads are zero on triangles and negative on tets: that
    is the consistent load, exact for the static problem).
    """
    sb = gm.scalar_basis(2)

    @LinearForm
    def density(v, w):
        return w["rho"] * v

    rho_q = np.broadcast_to(np.asarray(rho_e, float)[:, None], sb.dx.shape)
    nodal = asm(density, sb, rho=rho_q)
    return nodal[:, None] * np.asarray(g, float)[None, :]
