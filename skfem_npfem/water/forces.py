"""What the pore water does in a step: forces, coupling and stabilisation.

Notation of docs/theory.md ("Water: effective stress"): ``G`` is the step's
internal-force operator, ``m`` the Voigt identity on the stress variables,
``Q = G (I (x) m)`` the volumetric coupling, so that ``(Q^T du)_j = V_j
eps_vol,j`` is the volume change of cell ``j`` and ``Q p = integral p_h div
(du_h)`` for the P1 interpolant ``p_h`` of nodal pressures (plane strain and
3D; the nodal operator's smoothed strains make it the consistent P1
coupling).  The equilibrium of a step in total stress,
``G sigma' - Q p = f + f_s`` with ``f_s = -integral_dOmega p phi n`` the
pressure of the water on the boundary, becomes an effective-stress
equilibrium with the *water force* ``Q p + f_s``: for a static pore pressure
it is ``-integral grad p phi``, the buoyancy and seepage forces.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

__all__ = [
    "coupling_matrix",
    "darcy_matrix",
    "drained_nodes",
    "projection_matrix",
    "surface_force",
    "water_force",
]


def _identity(components: tuple[int, ...]) -> np.ndarray:
    """The Voigt identity ``m`` on the carried components (normal ones 1)."""
    return np.array([1.0 if c in (0, 1, 2) else 0.0 for c in components])


def coupling_matrix(op) -> sp.csc_matrix:
    """``Q = G (I (x) m)`` (d N x n_p): the volumetric coupling of a step.

    ``Q @ p`` is the internal force of the isotropic stress ``p I`` at the
    stress points; ``Q.T @ du`` the volume change of every cell.
    """
    m = _identity(tuple(op.components))
    n_p = op.n_points
    E = sp.kron(sp.identity(n_p, format="csc"), sp.csc_matrix(m[:, None]))
    return (op.G @ E).tocsc()


def _boundary_facets(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Facets of a simplex mesh that belong to one element only.

    Returns the facets' nodes (nb, d), their element and the element's local
    vertex opposite each.
    """
    nv, ne = t.shape
    local = np.array([[j for j in range(nv) if j != k] for k in range(nv)])
    faces = t[local].transpose(2, 0, 1).reshape(ne * nv, nv - 1)  # (e, k) order
    key = np.sort(faces, axis=1)
    n = int(t.max()) + 1 if t.size else 1
    if float(n) ** (nv - 1) < 2.0**62:  # one int64 per facet: a fast 1D unique
        key = key.astype(np.int64) @ (np.int64(n) ** np.arange(nv - 2, -1, -1))
        _, inv, count = np.unique(key, return_inverse=True, return_counts=True)
    else:
        _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    once = np.flatnonzero(count[inv.reshape(-1)] == 1)
    return faces[once], once // nv, once % nv


def surface_force(op, x: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``-integral_dOmega p phi_i n``: the water's pressure on the boundary, N.

    Parameters
    ----------
    op : NodalIntegration or AxisymmetricIntegration
        The step's operator (its elements, gradients and volumes).
    x : ndarray (N, d)
        Node positions, m.
    p : ndarray (N,)
        Nodal pore pressure, Pa (linear along each boundary facet).

    Returns
    -------
    ndarray (N, d)
        Consistent nodal forces of the pressure on every boundary facet of
        the mesh (full rings in axisymmetry), pushing into the body.
    """
    x = np.asarray(x, float)
    p = np.asarray(p, float)
    n, d = x.shape
    out = np.zeros((n, d))
    if not np.any(p):
        return out
    t = np.asarray(op.t)
    nodes, elem, opp = _boundary_facets(t)
    keep = np.any(p[nodes] != 0.0, axis=1)
    nodes, elem, opp = nodes[keep], elem[keep], opp[keep]
    if not nodes.size:
        return out
    axisym = hasattr(op, "element_areas")
    planar = np.asarray(op.element_areas if axisym else op.element_volumes, float)
    # |f| n = -d |e| grad phi_k, k the vertex opposite the facet.
    area_n = -d * planar[elem, None] * np.asarray(op.grads)[elem, opp, :]
    pf = p[nodes]
    if not axisym:
        # integral phi_i p over a facet = |f| (p_i + sum_j p_j) / (d (d+1))
        w = (pf + pf.sum(axis=1, keepdims=True)) / (d * (d + 1))
    else:
        r = x[nodes, 0]
        pa, pb, ra, rb = pf[:, 0], pf[:, 1], r[:, 0], r[:, 1]
        # integral of phi_a p r over the segment, per unit length, times 2 pi
        wa = pa * ra / 4 + (pa * rb + pb * ra) / 12 + pb * rb / 12
        wb = pb * rb / 4 + (pb * ra + pa * rb) / 12 + pa * ra / 12
        w = 2.0 * math.pi * np.stack([wa, wb], axis=1)
    for k in range(nodes.shape[1]):
        np.add.at(out, nodes[:, k], -w[:, k, None] * area_n)
    return out


def water_force(op, x: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The force of a prescribed pore-pressure field on the skeleton, N (N, d).

    ``Q p - integral_dOmega p phi n``: added to the external force, it turns
    the step's equilibrium into one of effective stress.  For a hydrostatic
    field it is the buoyancy ``-rho_w g V_i`` at every node (plane strain
    and 3D: exactly, as ``-integral grad p_h phi_i``).
    """
    x = np.asarray(x, float)
    p = np.asarray(p, float)
    q = (coupling_matrix(op) @ p).reshape(x.shape)
    return q + surface_force(op, x, p)


def projection_matrix(op, compliance: np.ndarray, tau: float) -> sp.csc_matrix:
    """Upper triangle of ``tau / (2 G) L``: the pressure-projection term.

    ``L = M - Pi_0^T diag|e| Pi_0`` is the P1 mass matrix less that of the
    element means (positive semidefinite, zero on fields constant in every
    element; Dohrmann & Bochev 2004).  ``compliance`` is ``1 / (2 G)`` per
    node (Pa^-1); an element takes the mean of its vertices'.  Axisymmetric
    operators weight each element by its ring volume.
    """
    t = np.asarray(op.t)
    nv, ne = t.shape
    vol = np.asarray(op.element_volumes, float)
    c_e = np.asarray(compliance, float)[t].mean(axis=0)
    w = tau * c_e * vol
    local = np.full((nv, nv), -1.0 / nv**2) + (np.eye(nv) + 1.0) / (nv * (nv + 1))
    rows = np.broadcast_to(t[:, None, :], (nv, nv, ne))
    cols = np.broadcast_to(t[None, :, :], (nv, nv, ne))
    vals = local[:, :, None] * w[None, None, :]
    n = op.n_points
    L = sp.coo_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(n, n))
    return sp.triu(L.tocsc(), format="csc")


def darcy_matrix(op, kappa: np.ndarray) -> sp.csr_matrix:
    """``H = integral kappa grad phi_i . grad phi_j`` (N x N, symmetric).

    ``kappa = k / gamma_w`` per node (m^2 / (Pa s)); an element takes the mean
    of its vertices'.  The P1 gradients are constant in an element, so the
    element's volume (its ``2 pi r`` ring in axisymmetry, exact for the
    linear weight ``r``) integrates the product exactly.
    """
    t = np.asarray(op.t)
    nv, ne = t.shape
    grads = np.asarray(op.grads)  # (ne, nv, d)
    k_e = np.asarray(kappa, float)[t].mean(axis=0)
    w = k_e * np.asarray(op.element_volumes, float)
    local = np.einsum("ead,ebd->eab", grads, grads) * w[:, None, None]
    rows = np.broadcast_to(t.T[:, :, None], (ne, nv, nv))
    cols = np.broadcast_to(t.T[:, None, :], (ne, nv, nv))
    n = op.n_points
    return sp.coo_matrix(
        (local.ravel(), (rows.ravel(), cols.ravel())), shape=(n, n)
    ).tocsr()


def drained_nodes(op, fixed: np.ndarray, walled: np.ndarray) -> np.ndarray:
    """Nodes on the free (drained) part of a step's boundary.

    A boundary facet is impermeable when all its nodes are held along the
    axis closest to its normal (a support or a symmetry plane: ``fixed``,
    (N, d) bool) or all touch a wall or a body (``walled``, (N,) bool);
    every other boundary facet is drained, and its nodes are returned
    (sorted, unique).
    """
    t = np.asarray(op.t)
    nodes, elem, opp = _boundary_facets(t)
    if not nodes.size:
        return np.zeros(0, int)
    normal = np.asarray(op.grads)[elem, opp, :]
    axis = np.argmax(np.abs(normal), axis=1)
    held = np.asarray(fixed, bool)[nodes, axis[:, None]].all(axis=1)
    touching = np.asarray(walled, bool)[nodes].all(axis=1)
    return np.unique(nodes[~(held | touching)])
