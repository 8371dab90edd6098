"""Consistent stabilisation of the nodal stresses: an element-residual penalty.

Why
---
With nodal integration the stresses live at the particles and the internal
force is ``G sigma``.  ``G`` sees only the *element means* of the nodal
stresses (its transpose is the form ``(tau_h, eps(v))`` of the P1 interpolant
``tau_h``, and ``eps(v)`` is constant per element), so stress fields that are
in nodal equilibrium but not in equilibrium inside the elements cost nothing.
In isochoric plastic flow the pairing of nodal stresses with P1 displacements
behaves like the equal-order P1/P1 mixed element, which is not inf-sup stable:
such fields appear as a checkerboard of the mean stress.  And every remesh
changes ``G``, hence which fields it cannot see (docs/validation.md measures
both).

What
----
The P1 interpolant of the nodal stresses has a constant divergence in every
element, and the exact stress satisfies the momentum balance pointwise,

    R = div sigma + rho g - rho a = 0.

The step therefore adds to its complementary energy the Galerkin least-squares
(GLS) penalty of the element residual of the end-of-step stress

    1/2 sum_e  beta h_e^2 |e| / G_e  |div tau_h(sigma_n+1) + f_e - m a_e|^2,

where ``f_e`` and ``m a_e`` are the element means of the nodal load and
inertia densities ``f_i / V_i`` and ``m_i a_i / V_i``, ``h_e = (d! |e|)^(1/d)``
is the lattice spacing of an element of that size, ``G_e`` the smallest shear
modulus at its vertices and ``beta`` the dimensionless factor
:attr:`~skfem_npfem.step.model.Model.stabilisation`.  The acceleration is the one
at the start of the step (``a_n``, lagged by one step): the inertial forces
stay uncoupled in the program, which keeps the factorisation sparser (with the
implicit ``a_n+1`` the step cost about 1.3x more in our trials), and the lag
is ``O(dt)`` in a transient and nothing at rest.  Quasi-static steps have no
inertia: their residual is exact.

Properties (tests/test_stabilisation.py):

* **Consistent.**  ``R`` is the residual of the equation being solved, so the
  penalty is zero for the exact solution; a linear stress field in
  equilibrium with a uniform load (the geostatic state, any patch test) is not
  changed on a given mesh.  (Remeshing a body at rest redraws the elements:
  their residuals near boundaries and lattice flips are then not exactly
  zero, and the body creeps slowly, ~1e-3 m/s at beta = 30 in the remeshed
  column of docs/validation/stabilisation.md.)  For smooth
  fields the penalty is ``O(h^2)`` relative to the elastic energy and vanishes
  as the spacing goes to zero.
* **One cone program.**  The penalty is a convex quadratic in the stress
  increments added to ``P`` and ``q``; rows and cones are unchanged and every
  stress stays a particle variable (no element history, nothing mapped between
  meshes).  The stresses the step returns are in nodal equilibrium to the
  solver's tolerance.
* **On the total stress.**  The residual uses ``sigma_n+1 = sigma_n + ds``, so
  a field that the previous mesh left out of element equilibrium is driven back
  towards it on the new mesh instead of being carried along.

The optimality condition of the step gains a stabilising strain: the smoothed
strain ``Bbar du`` equals ``C ds + d eps_p + (B^T W R) / V`` at every node, i.e.
nodes whose elements are out of balance deform a little more.  It is the
pressure-stabilisation idea of equal-order Stokes elements (Hughes, Franca &
Balestra 1986; Douglas & Wang 1989) applied to the whole stress of a mixed
Hellinger-Reissner step.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError
from .program import Program, Term

__all__ = [
    "divergence_matrix",
    "element_mean",
    "element_residual",
    "hoop_matrix",
    "residual_penalty",
]

#: Full-Voigt index of the tensor component (k, j), per dimension.
_VOIGT = {
    2: {(0, 0): 0, (1, 1): 1, (0, 1): 3, (1, 0): 3},
    3: {
        (0, 0): 0,
        (1, 1): 1,
        (2, 2): 2,
        (0, 1): 3,
        (1, 0): 3,
        (1, 2): 4,
        (2, 1): 4,
        (0, 2): 5,
        (2, 0): 5,
    },
}


def divergence_matrix(
    t: np.ndarray, grads: np.ndarray, components: tuple[int, ...]
) -> sp.csr_matrix:
    """Element divergence of the P1 interpolant of nodal stresses.

    Parameters
    ----------
    t : ndarray (d+1, ne)
        Connectivity.
    grads : ndarray (ne, d+1, d)
        P1 gradients.
    components : tuple of int
        Full-Voigt components of the nodal stress vectors (node-major).

    Returns
    -------
    scipy.sparse.csr_matrix (d*ne, N*n_s)
        ``(B @ sigma)[d*e + k] = sum_a sum_j dN_a/dx_j sigma_a[k, j]``.

    Examples
    --------
    >>> from skfem import MeshTri
    >>> from skfem_npfem.mesh.smoothing import p1_gradients
    >>> m = MeshTri().refined(1)
    >>> g, _ = p1_gradients(m)
    >>> x, y = m.p
    >>> s = np.stack([2 * x, 3 * y, 0 * x], axis=1).ravel()  # div = (2, 3)
    >>> B = divergence_matrix(m.t, g, (0, 1, 3))
    >>> bool(np.allclose(B @ s, np.tile([2.0, 3.0], m.t.shape[1])))
    True
    """
    nv, ne = t.shape
    d = grads.shape[2]
    pos = {c: k for k, c in enumerate(components)}
    ns = len(components)
    rows, cols, vals = [], [], []
    for (k, j), v in _VOIGT[d].items():  # <= 9 entries, not a loop over elements
        if v not in pos:
            continue
        for a in range(nv):
            rows.append(d * np.arange(ne) + k)
            cols.append(ns * t[a] + pos[v])
            vals.append(grads[:, a, j])
    n = int(t.max()) + 1
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(d * ne, n * ns),
    )


def element_mean(t: np.ndarray, dim: int) -> sp.csr_matrix:
    """``(d*ne, d*N)``: the element mean of a nodal vector field (node-major).

    Examples
    --------
    >>> t = np.array([[0], [1], [2]])
    >>> (element_mean(t, 2) @ np.array([0.0, 0, 3, 0, 0, 6])).tolist()
    [1.0, 2.0]
    """
    nv, ne = t.shape
    rows = np.broadcast_to(
        dim * np.arange(ne)[None, :, None] + np.arange(dim), (nv, ne, dim)
    )
    cols = dim * t[:, :, None] + np.arange(dim)
    n = int(t.max()) + 1
    return sp.csr_matrix(
        (np.full(rows.size, 1.0 / nv), (rows.ravel(), cols.ravel())),
        shape=(dim * ne, dim * n),
    )


def hoop_matrix(
    t: np.ndarray, radius: np.ndarray, components: tuple[int, ...]
) -> sp.csr_matrix:
    """The hoop terms of the axisymmetric element divergence.

    In a body of revolution (mesh coordinates ``(r, z)``, stress slots
    ``(rr, zz, tt, rz)``) the divergence gains ``(sigma_rr - sigma_tt) / r``
    in the radial and ``sigma_rz / r`` in the axial row.  Their ``2 pi r``-
    weighted element means are exact for the P1 interpolant of the nodal
    stresses: ``int_e (s / r) r dA / int_e r dA = mean_e(s) / r_c`` with
    ``mean_e(s)`` the vertex mean and ``r_c`` the centroid radius.

    Parameters
    ----------
    t : ndarray (3, ne)
        Connectivity of the half-section.
    radius : ndarray (ne,)
        Centroid radii ``r_c``.
    components : tuple of int
        Full-Voigt components of the nodal stress vectors (must hold 0, 2, 3).

    Returns
    -------
    scipy.sparse.csr_matrix (2*ne, N*n_s)
        To be added to :func:`divergence_matrix` of the same mesh.

    Examples
    --------
    >>> t = np.array([[0], [1], [2]])
    >>> s = np.array([[4.0, 0, 1, 3]] * 3)  # rr, zz, tt, rz at the 3 nodes
    >>> (hoop_matrix(t, np.array([2.0]), (0, 1, 2, 3)) @ s.ravel()).round(12).tolist()
    [1.5, 1.5]
    """
    nv, ne = t.shape
    pos = {c: k for k, c in enumerate(components)}
    ns = len(components)
    inv = 1.0 / (nv * np.asarray(radius, float))
    rows, cols, vals = [], [], []
    for k, slot, sign in ((0, 0, 1.0), (0, 2, -1.0), (1, 3, 1.0)):
        for a in range(nv):  # 3 vertices x 3 terms, not a loop over elements
            rows.append(2 * np.arange(ne) + k)
            cols.append(ns * t[a] + pos[slot])
            vals.append(sign * inv)
    n = int(t.max()) + 1
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(2 * ne, n * ns),
    )


def element_residual(prog: Program) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """The element residual ``R = B ds + c`` of one step and its weights.

    Returns
    -------
    B : csr_matrix (d*ne, n_p*n_s)
        Element divergence on the stress increments.
    c : ndarray (d*ne,)
        ``div tau_h(sigma_n)`` plus the element means of the load and inertia
        densities.
    w : ndarray (d*ne,)
        Penalty weight ``beta h_e^2 |e| / G_e`` of every row.

    Notes
    -----
    Axisymmetric operators (``element_areas`` present): ``B`` gains the hoop
    terms of :func:`hoop_matrix`, ``|e|`` is the ``2 pi r``-weighted ring
    volume of the element (the measure of the weighted least-squares norm) and
    ``h_e`` comes from its planar area.
    """
    data, op = prog.data, prog.data.operator
    t, grads, vol = _elements(op)
    d = prog.dim
    B = divergence_matrix(t, grads, prog.comp)
    area = vol  # the element measure that sets h_e
    if hasattr(op, "element_areas"):  # axisymmetric: vol is the 2 pi r ring
        area = np.asarray(op.element_areas, float)
        B = B + hoop_matrix(t, vol / (2.0 * math.pi * area), prog.comp)
    f = np.asarray(data.force, float).reshape(-1)
    if data.dynamic and data.a_n is not None:
        m = np.repeat(np.asarray(data.mass, float), d)
        f = f - m * np.asarray(data.a_n, float).reshape(-1)
    density = f / np.repeat(np.asarray(op.volumes, float), d)
    c = B @ prog.sig_n.reshape(-1) + element_mean(t, d) @ density
    shear = np.array([m.E / (2.0 * (1.0 + m.nu)) for m in data.materials])
    g_e = shear[np.asarray(data.material)][t].min(axis=0)
    h2 = (math.factorial(d) * area) ** (2.0 / d)
    w_e = data.stabilisation * h2 * vol / g_e
    w = np.repeat(w_e, d)
    return B, c, w


def residual_penalty(prog: Program) -> Term:
    """Objective term ``1/2 (B ds + c)^T W (B ds + c)`` (see the module notes).

    No term when the step's ``stabilisation`` factor is 0.
    """
    if not prog.data.stabilisation:
        return Term()
    B, c, w = element_residual(prog)
    K = sp.triu(B.T @ sp.diags(w) @ B, format="coo")
    off = prog.slice("sigma").start
    q = np.zeros(prog.nx)
    q[prog.slice("sigma")] = B.T @ (w * c)
    P = sp.coo_matrix((K.data, (K.row + off, K.col + off)), shape=(prog.nx, prog.nx))
    return Term(P=P, q=q)


def _elements(op) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Connectivity, P1 gradients and volumes of the operator's elements.

    Raises
    ------
    ParameterError
        For an operator without nodal stresses on a P1 mesh (e.g. Gauss points).
    """
    need = ("t", "grads", "element_volumes")
    if not all(hasattr(op, a) for a in need) or op.n_points != op.n_nodes:
        raise ParameterError(
            "stabilisation",
            f"> 0 with a {type(op).__name__} operator",
            "0: the element-residual stabilisation is defined for nodal "
            "integration (stresses at the nodes of a P1 mesh)",
        )
    return np.asarray(op.t), np.asarray(op.grads), np.asarray(op.element_volumes)
