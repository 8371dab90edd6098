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

    1/2 sum_e  beta tau_e |e|  |div tau_h(sigma_n+1) + f_e - m a_e|^2,
    tau_e = min(h_e^2 / G_e, dt^2 / rho_e),

where ``f_e`` and ``m a_e`` are the element means of the nodal body-force and
inertia densities ``f_i / V_i`` and ``m_i a_i / V_i`` (the weight, ``k_h`` and
the water's force: a traction or point load of ``Model.loads`` acts on the
boundary, not in the elements, and is left out; read as a body force it made
the exact stress of a loaded surface a residual), ``h_e = (d! |e|)^(1/d)``
is the lattice spacing of an element of that size, ``G_e`` the smallest shear
modulus at its vertices, ``rho_e`` the largest density there and ``beta`` the
dimensionless factor :attr:`~skfem_npfem.step.model.Model.stabilisation`.
Quasi-static steps take ``h_e^2 / G_e``.  In a dynamic step an element that the
shear wave does not cross within the step (``h_e > c_s dt``, ``c_s =
sqrt(G_e / rho_e)``) is weighted on its inertial scale ``dt^2 / rho_e``: the
step's own operator per element is ``G_e / h_e^2 + rho_e / dt^2``, and the
weight of a least-squares stabilisation is the inverse of its larger part
(the time-step term of GLS and PSPG parameters of transient problems).
Without it the lagged inertia (below) was fed back with a gain ``beta rho_e
h_e^2 / (G_e dt^2)``, about 7e3 for a column of E = 1 kPa at dt = 5 ms, and
the step created energy (docs/extremes.md, "What broke on the way").

The acceleration is the one at the start of the step (``a_n``, lagged by one
step): the inertial forces stay uncoupled in the program, which keeps the
factorisation sparser (with the implicit ``a_n+1`` the step cost about 1.3x
more in our trials), and the lag is ``O(dt)`` in a transient and nothing at
rest.  Quasi-static steps have no inertia: their residual is exact.

Properties (tests/step/test_stabilisation.py):

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

Modes: which stress increments the residual couples
----------------------------------------------------
The penalty couples the stress variables of neighbouring particles, and that
coupling fills the factor of the step's KKT system: in 3D, with all six
components coupled, the factor of the seed column holds 2.6x the non-zeros
and takes 4x the flops of the unstabilised one
(``benchmarks/stabilisation_fill.py``).  ``stabilisation_mode``
(:data:`STABILISATION_MODES`) chooses what the residual takes at the end of
the step; the rest of the stress enters it at the start of the step (lagged,
like the inertia), so the residual is the same, and what changes is which
increments it can correct within the step:

* ``"full"``: every component (the residual above, exactly);
* ``"vertical"``: only the vertical row of the residual (the vertical momentum
  balance), exactly: the components it contains (``sigma_xz, sigma_yz,
  sigma_zz`` in 3D; ``sigma_rz, sigma_zz`` in axisymmetry) are coupled, the
  horizontal rows are not penalised.  Consistent like ``"full"``;
* ``"sigma_v"``: the vertical row with only the vertical normal stress
  ``sigma_v`` taken at the end of the step (the component whose checkerboard
  the stress roughness measures): one coupled variable per particle;
* ``"mean"``: only the mean stress ``p = tr(sigma) / n_v`` of the ``n_v``
  normal components: ``R = grad p(ds) + div sigma_n + f - m a``.  The step
  gets one auxiliary variable per particle, ``p_i``, tied to its stress
  increments by a zero-cone row, and the penalty couples only the ``p_i``:
  the sparsity of a pressure-projection stabilisation (Dohrmann & Bochev
  2004), the cheapest coupling of neighbouring stresses there is.
  (``div (p I) = grad p`` in axisymmetry too: the hoop terms of an isotropic
  stress vanish.)

The lagged part makes ``"sigma_v"`` and ``"mean"`` consistent at rest, not
within a step: for the exact solution the penalty is that of the lagged
increments, ``O(dt)`` in a transient and zero at rest.  In a single elastic
step from a state out of balance they drive the lagged residual into the
implicit quantity (the pressure gradient has to absorb the deviatoric
imbalance), and the full residual can grow (tests/step/test_stabilisation.py).
"""

from __future__ import annotations

import math

import clarabel
import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError
from ..mesh.delaunay import SLIVER_QUALITY
from .program import Block, Program, Term

__all__ = [
    "STABILISATION_MODES",
    "divergence_matrix",
    "element_mean",
    "element_residual",
    "hoop_matrix",
    "mean_stress_link",
    "residual_penalty",
]

#: Values of ``stabilisation_mode`` (see the module notes).
STABILISATION_MODES = ("full", "vertical", "sigma_v", "mean")

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
        Penalty weight ``beta min(h_e^2 / G_e, dt^2 / rho_e) |e|`` of every
        row (``h_e^2 / G_e`` in quasi-static steps).

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
    body = data.force if data.body_force is None else data.body_force
    f = np.asarray(body, float).reshape(-1)
    if data.dynamic and data.a_n is not None:
        m = np.repeat(np.asarray(data.mass, float), d)
        f = f - m * np.asarray(data.a_n, float).reshape(-1)
    density = f / np.repeat(np.asarray(op.volumes, float), d)
    sig_n = prog.sig_n
    pore = getattr(data, "pore", None)
    if pore is not None and np.any(pore.excess):
        # The residual is one of total stress: sigma' - p_ex m (the static
        # pore pressure is in the load as its water force); the excess is
        # taken at the start of the step, like the inertia.
        m = np.array([1.0 if c in (0, 1, 2) else 0.0 for c in prog.comp])
        sig_n = sig_n - np.asarray(pore.excess, float)[:, None] * m[None, :]
    c = B @ sig_n.reshape(-1) + element_mean(t, d) @ density
    shear = np.array([m.E / (2.0 * (1.0 + m.nu)) for m in data.materials])
    g_e = shear[np.asarray(data.material)][t].min(axis=0)
    h2 = (math.factorial(d) * area) ** (2.0 / d)
    if data.dynamic:
        # An element the shear wave does not cross within the step (h_e >
        # c_s dt) is weighted on its inertial scale dt^2 / rho instead of
        # h_e^2 / G_e: the lagged inertia then cannot feed energy back.
        rho = np.array([m.rho for m in data.materials])
        rho_e = rho[np.asarray(data.material)][t].max(axis=0)
        wave = data.dt**2 * g_e  # rho_e h_e^2 above it: the wave is slower
        cap = rho_e * h2 > wave
        h2 = np.where(cap, wave / np.where(cap, rho_e, 1.0), h2)
    w_e = data.stabilisation * h2 * vol / g_e
    w = np.repeat(w_e, d)
    rows = np.ones(d * t.shape[1], dtype=bool)
    if d == 3:
        # Slivers meshed to close the body (alpha_shape's keep_buried_slivers)
        # carry no volume, and their divergence is a normal derivative taken
        # over four nearly coplanar points: their rows are left out.
        rows = np.repeat(element_quality(grads, vol) >= SLIVER_QUALITY, d)
    mode = getattr(data, "stabilisation_mode", "full")
    if mode in ("vertical", "sigma_v"):
        rows &= np.arange(d * t.shape[1]) % d == d - 1
    if not rows.all():
        keep = np.flatnonzero(rows)
        B, c, w = B.tocsr()[keep], c[keep], w[keep]
    if mode == "sigma_v":  # the other columns of the row are lagged
        cols = np.zeros(prog.ns)
        cols[prog.comp.index(d - 1)] = 1.0
        B = (B @ sp.diags(np.tile(cols, prog.n_points))).tocsr()
        B.eliminate_zeros()
    elif mode == "mean":
        # The residual of the isotropic increment p I: the sum of the normal
        # stresses' columns (div(p I) = grad p; the hoop terms cancel).
        base = prog.ns * np.arange(prog.n_points)
        B = B.tocsc()
        B = sum(B[:, base + k] for k in _normal_slots(prog.comp)).tocsr()
    return B, c, w


def element_quality(grads: np.ndarray, volumes: np.ndarray) -> np.ndarray:
    """Tetrahedra's volume over that of the regular one with their circumradius.

    The measure of :func:`~skfem_npfem.mesh.delaunay.alpha_shape`'s
    ``min_quality`` (1 for a regular tetrahedron, 0 for a flat sliver),
    from the P1 gradients: the edges from vertex 0 are the columns of the
    inverse of the gradients of vertices 1-3, and the circumcentre relative
    to vertex 0 is ``G^T |e|^2 / 2``.

    Examples
    --------
    >>> from skfem import MeshTet
    >>> from skfem_npfem.mesh.smoothing import p1_gradients
    >>> g, v = p1_gradients(MeshTet())  # a cube in five: four corners, one regular
    >>> element_quality(g, v).round(6).tolist()
    [0.5, 0.5, 0.5, 1.0, 0.5]
    """
    G = np.asarray(grads, float)[:, 1:, :]  # (ne, 3, 3): rows grad N_1..N_3
    edges = np.linalg.inv(G)  # columns: x_a - x_0
    sq = np.einsum("ija,ija->ia", edges, edges)
    centre = 0.5 * np.einsum("iaj,ia->ij", G, sq)
    radius = np.linalg.norm(centre, axis=1)
    return np.asarray(volumes, float) / (8.0 * math.sqrt(3.0) / 27.0 * radius**3)


def residual_penalty(prog: Program) -> Term:
    """Objective term ``1/2 (B ds + c)^T W (B ds + c)`` (see the module notes).

    No term when the step's ``stabilisation`` factor is 0.  In ``mean`` mode
    ``B`` acts on the auxiliary mean-stress variables (:func:`mean_stress_link`).
    """
    if not prog.data.stabilisation:
        return Term()
    B, c, w = element_residual(prog)
    K = sp.triu(B.T @ sp.diags(w) @ B, format="coo")
    block = "mean_stress" if prog.size("mean_stress") else "sigma"
    off = prog.slice(block).start
    q = np.zeros(prog.nx)
    q[prog.slice(block)] = B.T @ (w * c)
    P = sp.coo_matrix((K.data, (K.row + off, K.col + off)), shape=(prog.nx, prog.nx))
    return Term(P=P, q=q)


def mean_stress_link(prog: Program) -> Block:
    """Zero-cone rows ``p_i - mean_k ds_i[kk] = 0`` of the ``mean`` mode.

    An empty block in the other modes (and without stabilisation).
    """
    n = prog.size("mean_stress")
    if not n:
        return Block(sp.csc_matrix((0, prog.nx)), np.zeros(0), [], "stress")
    normal = _normal_slots(prog.comp)
    sig = prog.slice("sigma").start
    rows = np.repeat(np.arange(n), len(normal) + 1)
    cols = np.concatenate(
        [
            sig + prog.ns * np.arange(n)[:, None] + np.asarray(normal)[None, :],
            prog.slice("mean_stress").start + np.arange(n)[:, None],
        ],
        axis=1,
    ).ravel()
    vals = np.tile(np.r_[np.full(len(normal), -1.0 / len(normal)), 1.0], n)
    A = sp.csc_matrix((vals, (rows, cols)), shape=(n, prog.nx))
    return Block(A, np.zeros(n), [clarabel.ZeroConeT(n)], "stress")


def _normal_slots(comp: tuple[int, ...]) -> list[int]:
    """Positions of the normal components (full Voigt 0, 1, 2) among ``comp``."""
    return [k for k, v in enumerate(comp) if v < 3]


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
