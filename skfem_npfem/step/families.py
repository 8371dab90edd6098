"""The physical pieces of one step's cone program, one small function each.

Objective terms (docs/theory.md, "The mixed step"; in the stress increments ``ds``):

* :func:`elastic_energy` ``1/2 sum_p V_p ds_p^T C ds_p``;
* :func:`inertia` ``1/2 sum_j dt^2/m~_j r_j^2`` (dynamic steps);
* :func:`prescribed_work` ``-ds^T G_P^T ubar`` (prescribed displacements);
* :func:`contact_gap` ``sum_c g_c lambda_c``;
* :func:`contact_slip` ``sum_c o_c lambda_t,c`` (slip against a moving body);
* :func:`~skfem_npfem.step.stabilisation.residual_penalty` the element-residual
  stabilisation of the stresses (when ``stabilisation > 0``);
* :func:`~skfem_npfem.step.volume.eigenstrain_work` ``sum_p V_p e_p . ds_p``, a
  prescribed eigenstrain (the volume correction, when ``volume_correction > 0``);
* :func:`pore_projection` ``1/2 dp_w^T (tau/2G L + S + dt H) dp_w + dp_w^T dt H
  p_w,n``: the pressure-projection stabilisation of the excess pore pressure,
  the fluid's storage and Darcy's dissipation (undrained and coupled water),
  and its prescribed work ``+dp_w^T Q_P^T ubar``.

Row families, each a finished :class:`~skfem_npfem.step.program.Block`:

* :func:`equilibrium` ``(G ds + r - N lambda_n - T lambda_t - Q dp_w)_F = f~_F -
  (G s_n - Q p_w,n)_F`` (zero cone; its duals are ``-du_F``; the ``Q`` terms only
  with water, ``dp_w`` only undrained);
* :func:`contact` ``lambda_n >= 0``;
* :func:`friction` ``|lambda_t| <= mu lambda_bar_n`` (two rows in 2D, an SOC(3)
  in 3D);
* :func:`cutoff` tension cut-offs ``a_c^T s <= k_c``;
* :func:`yield_cones` ``k_p - a_p^T s_p >= ||M s_p||`` per plastic stress point;
* :func:`drained_pores` ``dp_w = -p_w,n`` at the drained points of a coupled step.

:data:`OBJECTIVE_TERMS` and :data:`ROW_FAMILIES` list them in the order the
program is stacked; a new ingredient (a stabilisation term, more cones) is one
more function ``f(prog) -> Term`` or ``f(prog) -> Block`` added to these lists.
"""

from __future__ import annotations

import clarabel
import numpy as np
import scipy.sparse as sp

from ..mesh.geometry import tangents
from .program import Block, Program, Term
from .stabilisation import mean_stress_link, residual_penalty
from .volume import eigenstrain_work

__all__ = [
    "OBJECTIVE_TERMS",
    "ROW_FAMILIES",
    "contact",
    "contact_gap",
    "contact_slip",
    "cutoff",
    "drained_pores",
    "elastic_energy",
    "equilibrium",
    "friction",
    "inertia",
    "pore_projection",
    "prescribed_work",
    "yield_cones",
]


# -- objective ----------------------------------------------------------------
def elastic_energy(prog: Program) -> Term:
    """``1/2 ds^T (V C) ds``: one upper-triangular block per stress point.

    The stress variables are the increments ``ds = s - s_n``, so the energy has
    no linear term.
    """
    blocks = prog.data.operator.volumes[:, None, None] * prog.compliance
    n, b, _ = blocks.shape
    iu, ju = np.triu_indices(b)
    base = (np.arange(n) * b)[:, None] + prog.slice("sigma").start
    return Term(
        P=sp.coo_matrix(
            (blocks[:, iu, ju].ravel(), ((base + iu).ravel(), (base + ju).ravel())),
            shape=(prog.nx, prog.nx),
        )
    )


def inertia(prog: Program) -> Term:
    """``1/2 sum dt^2 / m~ r^2`` on the inertial forces of free dofs."""
    nr = prog.size("r")
    if not nr:
        return Term()
    idx = prog.slice("r").start + np.arange(nr)
    vals = prog.data.dt**2 / prog.mt[prog.free]
    return Term(P=sp.coo_matrix((vals, (idx, idx)), shape=(prog.nx, prog.nx)))


def prescribed_work(prog: Program) -> Term:
    """``-ds^T G_P^T ubar``: the work of prescribed displacement increments."""
    if not prog.pres.size:
        return Term()
    q = np.zeros(prog.nx)
    q[prog.slice("sigma")] -= prog.data.operator.G[prog.pres].T @ prog.ubar
    return Term(q=q)


def pore_projection(prog: Program) -> Term:
    """The excess pore pressure's own terms (undrained and coupled water).

    ``1/2 dp_w^T (tau/2G L + S + dt H) dp_w + dp_w^T (dt H p_w,n + Q_P^T ubar)``:
    the pressure projection (:func:`~skfem_npfem.water.projection_matrix`),
    the fluid's storage, and the Darcy dissipation of a coupled step on the
    pressure at the end of the step, ``1/2 dt p^T H p`` with ``p = p_w,n +
    dp_w``; the last term is the excess pore pressure's share of the work of
    prescribed displacements (its columns in equilibrium are ``-Q``).
    """
    n = prog.size("pore")
    if not n:
        return Term()
    off = prog.slice("pore").start
    pore = prog.data.pore
    parts = []
    if pore.projection is not None:
        parts.append(sp.triu(pore.projection))
    if pore.darcy is not None:
        parts.append(sp.triu(pore.darcy))
    if pore.storage is not None:
        parts.append(sp.diags(np.asarray(pore.storage, float)))
    P = None
    if parts:
        L = sum(parts[1:], parts[0]).tocoo()
        nx = prog.nx
        P = sp.coo_matrix((L.data, (L.row + off, L.col + off)), shape=(nx, nx))
    q = np.zeros(prog.nx)
    if pore.darcy is not None:
        q[prog.slice("pore")] += pore.darcy @ np.asarray(pore.excess, float)
    if prog.pres.size:
        q[prog.slice("pore")] += prog.Q[prog.pres].T @ prog.ubar
    return Term(P=P, q=q)


def drained_pores(prog: Program) -> Block:
    """Rows ``dp_w = -p_w,n`` at drained points: no excess pore pressure there.

    Zero-cone rows of a coupled step (the free surface lets the water out);
    their multipliers are the water the points expel over the step.
    """
    pore = prog.data.pore
    if pore is None or pore.drained is None or not prog.size("pore"):
        return _rows(prog, [], [], [], [], [], "stress")
    j = np.asarray(pore.drained, int)
    cols = prog.slice("pore").start + j
    b = -np.asarray(pore.excess, float)[j]
    rows = np.arange(j.size)
    cone = [clarabel.ZeroConeT(j.size)] if j.size else []
    return _rows(prog, [rows], [cols], [np.ones(j.size)], [b], cone, "stress")


def contact_gap(prog: Program) -> Term:
    """``g^T lambda_n``: the gaps enter the objective linearly."""
    q = np.zeros(prog.nx)
    q[prog.slice("lambda_n")] = prog.data.contacts.gap
    return Term(q=q)


def contact_slip(prog: Program) -> Term:
    """``o^T lambda_t``: slip measured against a moving surface (rigid bodies).

    The tangential counterpart of :func:`contact_gap`: with the offsets ``o =
    t . (du_prescribed - du_surface)`` (:attr:`Contacts.slip_offset`) the
    friction bound acts on the relative slip ``t . du + o``.  No term for fixed
    walls (``slip_offset`` None).
    """
    off = prog.data.contacts.slip_offset
    if off is None or not prog.fric.size:
        return Term()
    q = np.zeros(prog.nx)
    q[prog.slice("lambda_t")] = off[prog.fric].reshape(-1)
    return Term(q=q)


# -- rows ---------------------------------------------------------------------
def contact_maps(prog: Program) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """Place contact forces on dofs: ``N`` (dN x n_c) and ``T`` (dN x n_t)."""
    d, c = prog.dim, prog.data.contacts
    ndof, nc, nt = d * prog.n_nodes, prog.size("lambda_n"), prog.size("lambda_t")
    # A candidate is a node, or a point of a boundary edge (a rigid body's
    # corner): its force goes to the edge's two nodes by their weights.
    nodes, w, used = c.weights()
    rows = d * nodes[:, :, None] + np.arange(d)  # (nc, 2, d)
    vals = w[:, :, None] * c.normal[:, None, :]
    cols = np.broadcast_to(np.arange(nc)[:, None, None], rows.shape)
    keep = np.broadcast_to(used[:, :, None], rows.shape)
    Nmat = sp.csc_matrix((vals[keep], (rows[keep], cols[keep])), shape=(ndof, nc))
    if not nt:
        return Nmat, sp.csc_matrix((ndof, 0))
    tang = tangents(c.normal[prog.fric])  # (nf, d-1, d)
    nodes = c.node[prog.fric]
    r = (d * nodes[:, None, None] + np.arange(d)[None, None, :]) * np.ones(
        (1, d - 1, 1), int
    )
    col = np.arange(nt).reshape(-1, d - 1)[:, :, None] * np.ones((1, 1, d), int)
    Tmat = sp.csc_matrix((tang.ravel(), (r.ravel(), col.ravel())), shape=(ndof, nt))
    return Nmat, Tmat


def equilibrium(prog: Program) -> Block:
    """Rows ``(G ds + r - N lambda_n - T lambda_t)_F = f~_F - (G s_n)_F``.

    In the increments ``ds`` the right-hand side is the out-of-balance force.
    """
    G, free = prog.data.operator.G, prog.free
    Nmat, Tmat = contact_maps(prog)
    blocks = [G[free]]
    if prog.size("r"):
        blocks.append(sp.identity(prog.size("r"), format="csc"))
    blocks += [-Nmat[free], -Tmat[free]]
    if prog.size("mean_stress"):  # not in the equilibrium rows
        blocks.append(sp.csc_matrix((free.size, prog.size("mean_stress"))))
    if prog.size("pore"):  # total stress: sigma' - p m
        blocks.append(-prog.Q[free])
    rhs = prog.ftilde[free] - G[free] @ prog.sig_n.reshape(-1)
    if prog.Q is not None and np.any(prog.data.pore.excess):
        rhs = rhs + prog.Q[free] @ np.asarray(prog.data.pore.excess, float)
    A = sp.hstack(blocks, format="csc")
    if prog.tie is not None:  # a tied group balances its resultant only
        A, rhs = (prog.tie @ A).tocsc(), prog.tie @ rhs
    return Block(A, rhs, [clarabel.ZeroConeT(rhs.size)], "force")


def _rows(prog: Program, rows, cols, vals, b, cones, unit: str) -> Block:
    """A block from COO pieces (lists of arrays)."""
    nrow = sum(r.size for r in b)
    if not rows:
        return Block(sp.csc_matrix((nrow, prog.nx)), np.zeros(0), cones, unit)
    A = sp.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(nrow, prog.nx),
    )
    return Block(A, np.concatenate(b), cones, unit)


def contact(prog: Program) -> Block:
    """Nonnegative rows ``lambda_n >= 0``."""
    nc = prog.size("lambda_n")
    if not nc:
        return _rows(prog, [], [], [], [], [], "force")
    cols = prog.slice("lambda_n").start + np.arange(nc)
    return _rows(
        prog,
        [np.arange(nc)],
        [cols],
        [-np.ones(nc)],
        [np.zeros(nc)],
        [clarabel.NonnegativeConeT(nc)],
        "force",
    )


def friction(prog: Program) -> Block:
    """Coulomb bound ``|lambda_t| <= mu lambda_bar_n`` with the lagged normal force.

    2D: two nonnegative rows ``mu lambda_bar -+ lambda_t >= 0``; 3D: one SOC(3)
    ``(mu lambda_bar ; lambda_t)`` per frictional contact.
    """
    nf, off = prog.fric.size, prog.slice("lambda_t").start
    bound = prog.data.contacts.mu_lambda[prog.fric]
    if not nf:
        return _rows(prog, [], [], [], [], [], "force")
    if prog.dim == 2:
        rows, cols, vals, b = [], [], [], []
        for k, sign in enumerate((1.0, -1.0)):  # s = mu*lam - sign*lambda_t >= 0
            rows.append(k * nf + np.arange(nf))
            cols.append(off + np.arange(nf))
            vals.append(np.full(nf, sign))
            b.append(bound)
        cone = [clarabel.NonnegativeConeT(2 * nf)]
        return _rows(prog, rows, cols, vals, b, cone, "force")
    rows = (3 * np.arange(nf)[:, None] + np.array([1, 2])).ravel()
    cols = off + np.arange(2 * nf)
    b = np.zeros((nf, 3))
    b[:, 0] = bound
    cones = [clarabel.SecondOrderConeT(3)] * nf
    return _rows(prog, [rows], [cols], [-np.ones(2 * nf)], [b.ravel()], cones, "force")


def cutoff(prog: Program) -> Block:
    """Tension cut-off rows ``a_c^T ds <= k_c - a_c^T s_n`` (nonnegative)."""
    ns, cut = prog.ns, [(p, c) for p, c in prog.yield_cones if c.cutoff_a is not None]
    if not cut:
        return _rows(prog, [], [], [], [], [], "stress")
    points = np.concatenate([p for p, _ in cut])
    vals = np.concatenate([np.broadcast_to(c.cutoff_a, (len(p), ns)) for p, c in cut])
    b = np.concatenate([c.cutoff_k - prog.sig_n[p] @ c.cutoff_a for p, c in cut])
    rows = np.repeat(np.arange(points.size), ns)
    cols = prog.slice("sigma").start + (points[:, None] * ns + np.arange(ns)).ravel()
    cone = [clarabel.NonnegativeConeT(points.size)]
    return _rows(prog, [rows], [cols], [vals.ravel()], [b], cone, "stress")


def yield_cones(prog: Program) -> Block:
    """One SOC ``(k - a^T s ; M s)`` per plastic stress point, on ``ds``.

    Rows per point: ``[a^T ; -M] ds + s = (k - a^T s_n ; M s_n)``.
    """
    ns, start = prog.ns, prog.slice("sigma").start
    rows, cols, vals, b, cones = [], [], [], [], []
    nrow = 0
    for points, cone in prog.yield_cones:
        n, m = points.size, cone.M.shape[0]
        rowmat = np.concatenate(
            [cone.a[:, None, :], np.broadcast_to(-cone.M, (n, m, ns))], axis=1
        )  # (n, 1+m, ns)
        sn = prog.sig_n[points]
        bvec = np.empty((n, 1 + m))
        bvec[:, 0] = cone.k - np.einsum("ns,ns->n", cone.a, sn)
        bvec[:, 1:] = sn @ cone.M.T
        rr = (np.arange(n)[:, None] * (1 + m) + np.arange(1 + m))[:, :, None]
        cc = (points[:, None] * ns + np.arange(ns))[:, None, :]
        rows.append(nrow + np.broadcast_to(rr, (n, 1 + m, ns)).ravel())
        cols.append(start + np.broadcast_to(cc, (n, 1 + m, ns)).ravel())
        vals.append(rowmat.ravel())
        b.append(bvec.ravel())
        cones.extend([clarabel.SecondOrderConeT(1 + m)] * n)
        nrow += n * (1 + m)
    return _rows(prog, rows, cols, vals, b, cones, "stress")


#: Objective terms, summed.
OBJECTIVE_TERMS = (
    elastic_energy,
    inertia,
    prescribed_work,
    contact_gap,
    contact_slip,
    residual_penalty,
    eigenstrain_work,
    pore_projection,
)
#: Row families, stacked in this order within each cone kind.
ROW_FAMILIES = (
    equilibrium,
    contact,
    friction,
    cutoff,
    yield_cones,
    mean_stress_link,
    drained_pores,
)
