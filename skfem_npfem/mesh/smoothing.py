"""Nodal (smoothing-cell) integration on scikit-fem P1 meshes.

Each node ``i`` owns a smoothing cell made of ``1/(d+1)`` of every simplex around
it.  Strains are averaged over that cell, so the smoothed strain of node ``i`` is
``eps_i = Bbar_i @ u`` with

    V_i    = sum_{e ∋ i} |e| / (d+1)
    Bbar_i = (1 / V_i) sum_{e ∋ i} (|e| / (d+1)) B_e

and the internal-force operator is ``G = [V_1 Bbar_1^T, ..., V_N Bbar_N^T]`` so that
``f_int = G @ sigma``.  Everything is assembled in one vectorised COO call from the
gradients of a scikit-fem P1 basis (:func:`p1_gradients`).

:class:`NodalIntegration` is the N-PFEM strain operator of the cone program (one
stress point per node; the interface is described in
:mod:`skfem_npfem.step.program`).

Stress/strain vectors use the *full Voigt* order of this library

* 2D (plane strain): ``(xx, yy, zz, xy)``
* 3D: ``(xx, yy, zz, xy, yz, zx)``

with engineering shear strains, so that ``sigma · eps`` is the work density.  A
subset of these components (for instance ``(xx, yy, xy)`` for plane-strain
Mohr-Coulomb) can be selected with ``components``.

Displacement degrees of freedom are node-major: ``(u_0x, u_0y, u_1x, u_1y, ...)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import CellBasis, ElementTetP1, ElementTriP1, Mesh

from ..errors import ParameterError

__all__ = [
    "FULL_VOIGT",
    "NodalIntegration",
    "check_p1_mesh",
    "nodal_integration",
    "p1_gradients",
]

#: Names of the full Voigt components, by spatial dimension.
FULL_VOIGT: dict[int, tuple[str, ...]] = {
    2: ("xx", "yy", "zz", "xy"),
    3: ("xx", "yy", "zz", "xy", "yz", "zx"),
}

# P1 elements and their one-point rule (centroid, weight = reference volume).
_P1 = {
    2: (ElementTriP1(), (np.full((2, 1), 1.0 / 3.0), np.array([1.0 / 2.0]))),
    3: (ElementTetP1(), (np.full((3, 1), 1.0 / 4.0), np.array([1.0 / 6.0]))),
}

# Strain-displacement pattern: (voigt row, displacement component k, gradient
# direction j) meaning B[row, (node, k)] = dN_node/dx_j.
_B_PATTERN: dict[int, tuple[tuple[int, int, int], ...]] = {
    2: ((0, 0, 0), (1, 1, 1), (3, 0, 1), (3, 1, 0)),
    3: (
        (0, 0, 0),
        (1, 1, 1),
        (2, 2, 2),
        (3, 0, 1),
        (3, 1, 0),
        (4, 1, 2),
        (4, 2, 1),
        (5, 2, 0),
        (5, 0, 2),
    ),
}


def check_p1_mesh(mesh: Mesh, name: str = "mesh") -> Mesh:
    """Return ``mesh`` if it is a scikit-fem P1 simplex mesh, else raise.

    The particles of N-PFEM are the vertices of linear triangles (2D) or
    tetrahedra (3D): ``MeshTri1`` (``MeshTri``) or ``MeshTet1`` (``MeshTet``).

    Raises
    ------
    ParameterError
        For any other mesh type (quadrilaterals, hexahedra, quadratic or
        discontinuous meshes, lines), naming the conversion where scikit-fem
        has one.

    Examples
    --------
    >>> from skfem import MeshQuad, MeshTri
    >>> type(check_p1_mesh(MeshTri())).__name__
    'MeshTri1'
    >>> try:
    ...     check_p1_mesh(MeshQuad())
    ... except ParameterError as err:
    ...     print(err.value, "->", err.allowed.split("; ")[1])
    MeshQuad1 -> split it with mesh.to_meshtri()
    """
    elem = getattr(type(mesh), "elem", None)
    if elem in (ElementTriP1, ElementTetP1):
        return mesh
    hint = {
        "MeshQuad1": "; split it with mesh.to_meshtri()",
        "MeshHex1": "; split it with mesh.to_meshtet()",
    }.get(type(mesh).__name__, "")
    raise ParameterError(
        name,
        type(mesh).__name__,
        f"a scikit-fem P1 simplex mesh, MeshTri (MeshTri1) or MeshTet (MeshTet1){hint}",
    )


def p1_gradients(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Return P1 shape-function gradients and simplex volumes of a mesh.

    Both come from a scikit-fem :class:`~skfem.CellBasis` of ``ElementTriP1`` or
    ``ElementTetP1`` with a one-point (centroid) quadrature, which is exact for
    P1 simplices and independent of the vertex orientation.

    Parameters
    ----------
    mesh : skfem.Mesh
        A ``MeshTri1`` or ``MeshTet1``.

    Returns
    -------
    grads : ndarray, shape (ne, d+1, d)
        ``grads[e, a, j]`` is dN_a/dx_j on element ``e`` (local vertex ``a`` is
        ``mesh.t[a, e]``).
    volumes : ndarray, shape (ne,)
        Element areas (2D) or volumes (3D), positive.

    Examples
    --------
    >>> from skfem import MeshTri
    >>> g, v = p1_gradients(MeshTri())
    >>> float(v.sum()), g[0].sum(axis=0).tolist()
    (1.0, [0.0, 0.0])
    """
    dim = mesh.dim()
    element, quadrature = _P1[dim]
    basis = CellBasis(mesh, element, quadrature=quadrature, disable_doflocs=True)
    grads = np.stack([phi[0].grad[:, :, 0] for phi in basis.basis], axis=1)
    return grads.transpose(2, 1, 0), basis.dx[:, 0]


@dataclass(frozen=True)
class NodalIntegration:
    """Smoothing-cell quantities of one mesh (built by :func:`nodal_integration`).

    Attributes
    ----------
    dim : int
        Spatial dimension.
    components : tuple of int
        Indices into the full Voigt vector of the stress/strain components used.
    volumes : ndarray, shape (N,)
        Smoothing-cell areas/volumes ``V_i`` (the lumped P1 mass of a unit density).
    G : scipy.sparse.csc_matrix, shape (d*N, N*n_s)
        Internal-force operator: ``f_int = G @ sigma`` with node-major dofs and
        node-major stresses.
    averaging : scipy.sparse.csr_matrix, shape (N, ne)
        ``averaging[i, e] = |e| / ((d+1) V_i)`` for elements around node ``i``:
        smoothed nodal value of any element-constant field.
    grads : ndarray, shape (ne, d+1, d)
        Element P1 gradients.
    t : ndarray, shape (d+1, ne)
        Element connectivity (``mesh.t``).
    element_volumes : ndarray, shape (ne,)
        Element areas (2D) or volumes (3D).
    """

    dim: int
    components: tuple[int, ...]
    volumes: np.ndarray
    G: sp.csc_matrix
    averaging: sp.csr_matrix
    grads: np.ndarray
    t: np.ndarray
    element_volumes: np.ndarray

    @property
    def n_nodes(self) -> int:
        """Number of nodes ``N``."""
        return self.volumes.shape[0]

    @property
    def n_points(self) -> int:
        """Number of stress points (one per node)."""
        return self.volumes.shape[0]

    def check(self) -> None:
        """Refuse a mesh with degenerate elements (infinite P1 gradients).

        Raises
        ------
        ParameterError
            Naming the first element of zero area/volume and its nodes.
        """
        _refuse_degenerate(~np.all(np.isfinite(self.grads), axis=(1, 2)), self.t)

    def strain(self, u: np.ndarray) -> np.ndarray:
        """Smoothed nodal strains ``Bbar_i u`` (engineering shear).

        Parameters
        ----------
        u : ndarray, shape (N, d) or (d*N,)
            Nodal displacements (or increments).

        Returns
        -------
        ndarray, shape (N, n_s)
        """
        u = np.asarray(u, dtype=float).reshape(-1)
        return (self.G.T @ u).reshape(self.n_nodes, -1) / self.volumes[:, None]

    def gradient(self, u: np.ndarray) -> np.ndarray:
        """Smoothed nodal displacement gradients ``(grad u)_i[k, j] = du_k/dx_j``.

        Parameters
        ----------
        u : ndarray, shape (N, d)

        Returns
        -------
        ndarray, shape (N, d, d)
        """
        u = np.asarray(u, dtype=float).reshape(self.n_nodes, self.dim)
        ue = u[self.t.T]  # (ne, d+1, d)
        grad_e = np.einsum("eak,eaj->ekj", ue, self.grads)
        d = self.dim
        return (self.averaging @ grad_e.reshape(-1, d * d)).reshape(-1, d, d)


def _refuse_degenerate(degenerate: np.ndarray, t: np.ndarray) -> None:
    """Raise ParameterError naming the first degenerate element, if any."""
    if not np.any(degenerate):
        return
    e = int(np.flatnonzero(degenerate)[0])
    raise ParameterError(
        "mesh",
        f"{int(degenerate.sum())} degenerate element(s) of zero "
        f"{'area' if t.shape[0] == 3 else 'volume'}, first {e} with nodes "
        f"{t[:, e].tolist()}",
        "elements of nonzero size; drop them (remesh.alpha_shape does) or "
        "separate coincident/collinear nodes (near-degenerate elements "
        "are fine)",
    )


def connectivity(mesh: Mesh) -> tuple[np.ndarray, int]:
    """``(t, n_nodes)`` of a mesh whose every node belongs to an element.

    Raises
    ------
    ValueError
        If a node belongs to no element (smoothing cells need them all).
    """
    t = np.asarray(mesh.t)
    n = mesh.p.shape[1]
    if t.max() + 1 != n or np.unique(t).size != n:
        raise ValueError(
            "every mesh node must belong to an element; build the mesh on the "
            "active nodes only"
        )
    return t, n


def signed_volumes(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Signed areas (2D) or volumes (3D) of simplices ``t`` (d+1, ne) at ``p`` (d, N).

    Examples
    --------
    >>> p = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    >>> signed_volumes(p, np.array([[0], [1], [2]])).tolist(), signed_volumes(
    ...     p, np.array([[0], [2], [1]])
    ... ).tolist()
    ([0.5], [-0.5])
    """
    d = p.shape[0]
    edges = p[:, t[1:]] - p[:, t[:1]]  # (d, d, ne): coordinate, edge, element
    return np.linalg.det(np.moveaxis(edges, 2, 0)) / (2.0 if d == 2 else 6.0)


def nodal_integration(
    mesh: Mesh, components: tuple[int, ...] | None = None
) -> NodalIntegration:
    """Assemble smoothing cells and the internal-force operator of a P1 mesh.

    Parameters
    ----------
    mesh : skfem.MeshTri1 or skfem.MeshTet1
        Every node must belong to at least one element (build meshes on compacted
        node sets; scikit-fem takes ``nvertices = max(t) + 1``).
    components : tuple of int, optional
        Full-Voigt components to keep (default: all, i.e. 4 in 2D, 6 in 3D).

    Returns
    -------
    NodalIntegration

    Raises
    ------
    ParameterError
        If an element has zero area (2D) or volume (3D), naming it and its
        nodes.

    Examples
    --------
    >>> from skfem import MeshTri
    >>> ni = nodal_integration(MeshTri().refined(2))
    >>> round(float(ni.volumes.sum()), 12)
    1.0
    """
    check_p1_mesh(mesh)
    dim = mesh.dim()
    nfull = len(FULL_VOIGT[dim])
    if components is None:
        components = tuple(range(nfull))
    components = tuple(int(c) for c in components)
    t, n = connectivity(mesh)
    # Refuse zero-size elements here, before their infinite gradients enter G
    # (an element shared with others would otherwise give NaN in G).
    _refuse_degenerate(signed_volumes(np.asarray(mesh.p, float), t) == 0.0, t)
    grads, vol = p1_gradients(mesh)
    _refuse_degenerate(~np.all(np.isfinite(grads), axis=(1, 2)), t)
    nv = dim + 1
    w = vol / nv
    volumes = np.bincount(t.ravel(), weights=np.tile(w, nv), minlength=n)
    if np.any(volumes <= 0.0):  # pragma: no cover - refused above
        raise ParameterError("mesh", "nodes of zero cell volume", "nonzero elements")

    # Map full-Voigt rows to positions in the selected component list.
    pos = -np.ones(nfull, dtype=int)
    pos[list(components)] = np.arange(len(components))
    pattern = [p for p in _B_PATTERN[dim] if pos[p[0]] >= 0]
    ns = len(components)
    # G[(t[c,e], k), (t[a,e], s)] += w_e * grads[e, c, j] for (s, k, j) in pattern.
    a_idx, c_idx = np.meshgrid(np.arange(nv), np.arange(nv), indexing="ij")
    a_idx, c_idx = a_idx.ravel(), c_idx.ravel()
    rows, cols, vals = [], [], []
    for s, k, j in pattern:  # at most 9 pattern entries: not a loop over elements
        rows.append(dim * t[c_idx] + k)
        cols.append(ns * t[a_idx] + pos[s])
        vals.append(w[None, :] * grads[:, c_idx, j].T)
    G = sp.csc_matrix(
        (
            np.concatenate(vals).ravel(),
            (np.concatenate(rows).ravel(), np.concatenate(cols).ravel()),
        ),
        shape=(dim * n, ns * n),
    )
    ne = t.shape[1]
    averaging = sp.csr_matrix(
        (
            (np.tile(w, nv) / volumes[t.ravel()]),
            (t.ravel(), np.tile(np.arange(ne), nv)),
        ),
        shape=(n, ne),
    )
    return NodalIntegration(
        dim=dim,
        components=components,
        volumes=volumes,
        G=G,
        averaging=averaging,
        grads=grads,
        t=t,
        element_volumes=vol,
    )
