"""The N-PFEM cone program on arbitrary stress points (Gauss points).

DUPLICATE OF :mod:`skfem_npfem.conic` (to be unified): ``conic.solve_step``
assumes that the stress points are the displacement nodes
(``StepData.ni.n_nodes`` sizes both).  The FEM baseline keeps its stresses at
Gauss points, so this module builds the *same* program (formulation.md §3-§5,
in stress increments, with the same non-dimensionalisation and the same
Clarabel settings) from a :class:`~skfem_npfem.baseline.operators.StressPoints`
operator that has its own number of points, weights ``w_g`` (in place of the
cell volumes ``V_i``) and ``G = sum_g w_g B_g^T``.  Once the step builder of
:mod:`skfem_npfem.conic` takes such an operator, this module should shrink to
the adapter.  ``tests/test_baseline_program.py`` checks that, with the nodal
operator, it reproduces ``conic.solve_step`` to round-off.

Pieces reused from :mod:`skfem_npfem.conic`: :class:`Contacts`,
:class:`SolverOptions` (``clarabel_settings``, backend choice),
:class:`StepSolution`, ``_block_diag_upper``, ``_tangents``, ``_hint`` and the
accepted statuses.  Duplicated: the row families, the scales, the solve with
the refined retry and the read-back (marked "dup conic" below).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import clarabel
import numpy as np
import scipy.sparse as sp

from ..backends import pardiso_threads
from ..conic import (
    ACCEPTED,
    Contacts,
    SolverOptions,
    StepSolution,
    _block_diag_upper,
    _hint,
    _tangents,
)
from ..errors import ParameterError, SolverError
from ..materials import Material
from .operators import StressPoints

__all__ = ["GaussStepData", "solve_gauss_step"]


@dataclass
class GaussStepData:
    """One step's data with stresses at stress points (see conic.StepData).

    Attributes
    ----------
    points : StressPoints
        Weights and ``G`` (``points.components`` selects the stress variables).
    materials : list of Material
    material : ndarray (n_points,) int
        Material index per stress point.
    sigma_n : ndarray (n_points, n_full)
        Stress at the start of the step, Pa.
    force : ndarray (n_nodes, d)
        External nodal force, N.
    fixed : ndarray (n_nodes, d) bool
    du_prescribed : ndarray (n_nodes, d)
    contacts : Contacts
        Candidates among the displacement nodes.
    dt, mass, v_n, theta1, theta2, dynamic, stress_scale
        As :class:`skfem_npfem.conic.StepData` (mass, v_n per node).
    """

    points: StressPoints
    materials: list[Material]
    material: np.ndarray
    sigma_n: np.ndarray
    force: np.ndarray
    fixed: np.ndarray
    du_prescribed: np.ndarray
    contacts: Contacts
    dt: float = 1.0
    mass: np.ndarray | None = None
    v_n: np.ndarray | None = None
    theta1: float = 1.0
    theta2: float = 1.0
    dynamic: bool = False
    stress_scale: float | None = None


class _Layout:
    """Variable layout and physical blocks of one program (dup conic._Program)."""

    def __init__(self, data: GaussStepData) -> None:
        op = data.points
        self.data, self.dim, d = data, op.dim, op.dim
        self.n_nodes, self.n_pts = op.n_nodes, op.n_points
        self.comp = list(op.components)
        self.ns = ns = len(self.comp)
        fixed = np.asarray(data.fixed, bool).reshape(-1)
        self.free, self.pres = np.flatnonzero(~fixed), np.flatnonzero(fixed)
        self.ubar = np.asarray(data.du_prescribed, float).reshape(-1)[self.pres]
        self.sig_n = np.asarray(data.sigma_n, float)[:, self.comp]
        f = np.asarray(data.force, float).reshape(-1)
        self.mt = np.zeros(0)
        if data.dynamic:
            th1, th2 = data.theta1, data.theta2
            self.mt = np.repeat(np.asarray(data.mass, float), d) / (th1 * th2)
            f = f / th1 + self.mt * np.asarray(data.v_n, float).reshape(-1) / data.dt
            if th1 != 1.0:
                f = f - (1 - th1) / th1 * (op.G @ self.sig_n.reshape(-1))
        self.ftilde = f
        c = data.contacts
        self.nc = c.size
        self.fric = np.flatnonzero(c.mu_lambda > 0.0)
        self.nt = self.fric.size * (d - 1)
        self.nr = self.free.size if data.dynamic else 0
        self.n_sigma = self.n_pts * ns
        self.nx = self.n_sigma + self.nr + self.nc + self.nt
        self.compliance = np.empty((self.n_pts, ns, ns))
        for m_id, mat in enumerate(data.materials):
            sel = data.material == m_id
            if np.any(sel):
                self.compliance[sel] = mat.compliance(d, tuple(self.comp))


def _objective(lay: _Layout):
    """P (energy and inertia) and q (prescribed work, gaps) (dup conic)."""
    data, op = lay.data, lay.data.points
    P_sigma = _block_diag_upper(op.weights[:, None, None] * lay.compliance)
    q = np.zeros(lay.nx)
    if lay.pres.size:
        q[: lay.n_sigma] -= op.G[lay.pres].T @ lay.ubar
    diag = [np.zeros(lay.nc + lay.nt)]
    if lay.nr:
        diag.insert(0, data.dt**2 / lay.mt[lay.free])
    P = sp.block_diag([P_sigma, sp.diags(np.concatenate(diag))], format="csc")
    off = lay.n_sigma + lay.nr
    q[off : off + lay.nc] = data.contacts.gap
    return P, q


def _equilibrium(lay: _Layout):
    """(G s + r - N lambda_n - T lambda_t)_F = f~_F - (G s_n)_F (dup conic)."""
    d, c = lay.dim, lay.data.contacts
    G = lay.data.points.G
    ndof = d * lay.n_nodes
    rows = (d * c.node[:, None] + np.arange(d)).ravel()
    Nmat = sp.csc_matrix(
        (c.normal.ravel(), (rows, np.repeat(np.arange(lay.nc), d))),
        shape=(ndof, lay.nc),
    )
    if lay.nt:
        tang = _tangents(c.normal[lay.fric])  # (nf, d-1, d)
        nodes = c.node[lay.fric]
        r = d * nodes[:, None, None] + np.arange(d)[None, None, :]
        col = np.arange(lay.nt).reshape(-1, d - 1)[:, :, None]
        r, col = np.broadcast_arrays(r, col)
        r = np.broadcast_to(r, tang.shape)
        col = np.broadcast_to(col, tang.shape)
        Tmat = sp.csc_matrix(
            (tang.ravel(), (r.ravel(), col.ravel())), shape=(ndof, lay.nt)
        )
    else:
        Tmat = sp.csc_matrix((ndof, 0))
    blocks = [G[lay.free]]
    if lay.nr:
        blocks.append(sp.identity(lay.nr, format="csc"))
    blocks += [-Nmat[lay.free], -Tmat[lay.free]]
    rhs = lay.ftilde[lay.free] - G[lay.free] @ lay.sig_n.reshape(-1)
    return sp.hstack(blocks, format="csc"), rhs


def _contact_rows(lay: _Layout):
    """lambda_n >= 0 and 2D friction |lambda_t| <= mu lambda_bar (dup conic)."""
    off_n = lay.n_sigma + lay.nr
    off_t = off_n + lay.nc
    rows, cols, vals, b = [], [], [], []
    nrow = 0
    if lay.nc:
        rows.append(np.arange(lay.nc))
        cols.append(off_n + np.arange(lay.nc))
        vals.append(-np.ones(lay.nc))
        b.append(np.zeros(lay.nc))
        nrow = lay.nc
    if lay.nt and lay.dim == 2:
        bound = lay.data.contacts.mu_lambda[lay.fric]
        nf = lay.fric.size
        for sign in (1.0, -1.0):
            rows.append(nrow + np.arange(nf))
            cols.append(off_t + np.arange(nf))
            vals.append(np.full(nf, sign))
            b.append(bound)
            nrow += nf
    A = _coo(rows, cols, vals, nrow, lay.nx)
    return A, (np.concatenate(b) if b else np.zeros(0)), nrow


def _coo(rows, cols, vals, nrow, ncol) -> sp.csc_matrix:
    if not rows:
        return sp.csc_matrix((nrow, ncol))
    return sp.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(nrow, ncol),
    )


def _yield_rows(lay: _Layout):
    """Cut-off rows and one SOC per plastic stress point (dup conic).

    Returns ``(A_cut, b_cut)`` (nonnegative rows) and a list of
    ``(A_soc, b_soc, cone_dim, count)``.
    """
    data, ns = lay.data, lay.ns
    cut_A, cut_b, socs = [], [], []
    for m_id, mat in enumerate(data.materials):
        pts = np.flatnonzero(data.material == m_id)
        if pts.size == 0 or not mat.plastic:
            continue
        cone = mat.cone(lay.dim, tuple(lay.comp), data.sigma_n[pts])
        m, n = cone.M.shape[0], pts.size
        rowmat = np.concatenate(
            [cone.a[:, None, :], np.broadcast_to(-cone.M, (n, m, ns))], axis=1
        )
        sn = lay.sig_n[pts]
        bvec = np.empty((n, 1 + m))
        bvec[:, 0] = cone.k - np.einsum("ns,ns->n", cone.a, sn)
        bvec[:, 1:] = sn @ cone.M.T
        dim_cone = 1 + m
        rr = np.arange(n)[:, None, None] * dim_cone + np.arange(dim_cone)[None, :, None]
        cc = (pts[:, None] * ns + np.arange(ns))[:, None, :]
        rr, cc = np.broadcast_arrays(rr, cc)
        A = sp.csc_matrix(
            (rowmat.ravel(), (rr.ravel(), cc.ravel())), shape=(n * dim_cone, lay.nx)
        )
        socs.append((A, bvec.ravel(), dim_cone, n))
        if cone.cutoff_a is not None:
            cc = (pts[:, None] * ns + np.arange(ns)).ravel()
            rr = np.repeat(np.arange(n), ns)
            vals = np.tile(cone.cutoff_a, n)
            cut_A.append(sp.csc_matrix((vals, (rr, cc)), shape=(n, lay.nx)))
            cut_b.append(cone.cutoff_k - sn @ cone.cutoff_a)
    return cut_A, cut_b, socs


def _friction_cones_3d(lay: _Layout):
    """SOC(3) (mu lambda_bar ; lambda_t) per frictional 3D contact (dup conic)."""
    nf = lay.fric.size
    off_t = lay.n_sigma + lay.nr + lay.nc
    rows = (3 * np.arange(nf)[:, None] + np.array([1, 2])).ravel()
    A = sp.csc_matrix(
        (-np.ones(2 * nf), (rows, off_t + np.arange(2 * nf))), shape=(3 * nf, lay.nx)
    )
    b = np.zeros((nf, 3))
    b[:, 0] = lay.data.contacts.mu_lambda[lay.fric]
    return A, b.ravel(), nf


def _scales(data: GaussStepData, lay: _Layout):
    """Stress, force and displacement scales (dup conic._stress_scale)."""
    op, d = data.points, lay.dim
    h = float(np.sum(op.weights) / lay.n_nodes) ** (1.0 / d)
    if data.stress_scale is not None:
        s = float(data.stress_scale)
    else:
        cands = [float(np.max(np.abs(data.sigma_n), initial=0.0))]
        section = float(op.weights.sum()) ** ((d - 1) / d)
        cands.append(float(np.abs(np.asarray(data.force)).sum()) / section)
        for m_id, mat in enumerate(data.materials):
            sel = data.material == m_id
            if mat.plastic and np.any(sel):
                rows = mat.cone(d, tuple(lay.comp), data.sigma_n[sel])
                cands.append(float(np.max(rows.k)))
        s = max(cands)
        if not s > 0.0:
            s = min(m.E for m in data.materials) * 1e-6
    F = s * h ** (d - 1)
    k_el = min(m.E for m in data.materials) * h ** (d - 2)
    k_in = float(np.mean(lay.mt)) / data.dt**2 if data.dynamic and lay.mt.size else 0.0
    return s, F, F / (k_el + k_in)


def _assemble(lay: _Layout):
    """Stack all blocks: (P, q, A, b, cones, row kinds) (dup conic)."""
    P, q = _objective(lay)
    A_eq, b_eq = _equilibrium(lay)
    A_c, b_c, n_c = _contact_rows(lay)
    cut_A, cut_b, socs = _yield_rows(lay)
    A_parts, b_parts, kinds = [A_eq, A_c], [b_eq, b_c], []
    kinds += [("F", b_eq.size), ("F", n_c)]
    cones = [clarabel.ZeroConeT(b_eq.size)]
    n_nonneg = n_c + sum(a.shape[0] for a in cut_A)
    A_parts += cut_A
    b_parts += cut_b
    kinds += [("S", a.shape[0]) for a in cut_A]
    if n_nonneg:
        cones.append(clarabel.NonnegativeConeT(n_nonneg))
    for A, b, dim_cone, n in socs:
        A_parts.append(A)
        b_parts.append(b)
        kinds.append(("S", b.size))
        cones.extend([clarabel.SecondOrderConeT(dim_cone)] * n)
    if lay.nt and lay.dim == 3:
        A_f, b_f, nf = _friction_cones_3d(lay)
        A_parts.append(A_f)
        b_parts.append(b_f)
        kinds.append(("F", b_f.size))
        cones.extend([clarabel.SecondOrderConeT(3)] * nf)
    A = sp.vstack(A_parts, format="csc")
    return P, q, A, np.concatenate(b_parts), cones, kinds


def _solve(P, q, A, b, cones, options: SolverOptions, n_var: int, dim: int):
    """Clarabel solve with one refined retry (dup conic.solve_step)."""
    backend = options.resolved_linear_solver(n_var, dim)
    with pardiso_threads(options.max_threads if backend == "mkl" else 0):
        settings = options.clarabel_settings(backend)
        t0 = time.perf_counter()
        solver = clarabel.DefaultSolver(P, q, A, b, cones, settings)
        t1 = time.perf_counter()
        sol = solver.solve()
        status, iters = str(sol.status), int(sol.iterations)
        if status in ("InsufficientProgress", "NumericalError") and not (
            settings.iterative_refinement_enable
        ):
            settings.iterative_refinement_enable = True
            sol = clarabel.DefaultSolver(P, q, A, b, cones, settings).solve()
            status, iters = str(sol.status), iters + int(sol.iterations)
    t2 = time.perf_counter()
    return sol, status, iters, backend, (t1 - t0, t2 - t1)


def _check(data: GaussStepData) -> None:
    op = data.points
    mat = np.asarray(data.material)
    if mat.shape != (op.n_points,) or mat.dtype.kind not in "iu":
        raise ParameterError("material", mat.shape, f"ints, ({op.n_points},)")
    if np.any((mat < 0) | (mat >= len(data.materials))):
        raise ParameterError("material", int(mat.max()), "indices into materials")
    if not np.all(np.isfinite(op.weights) & (op.weights > 0)):
        raise ParameterError(
            "mesh",
            "degenerate element (zero or non-finite weight)",
            "elements of nonzero size",
        )
    if data.dynamic and (data.mass is None or np.any(np.asarray(data.mass) <= 0)):
        raise ParameterError("mass", None, "positive nodal masses for dynamic steps")


def solve_gauss_step(
    data: GaussStepData, options: SolverOptions | None = None, step: int | None = None
) -> StepSolution:
    """Assemble and solve one step with stresses at stress points.

    Returns
    -------
    StepSolution
        ``du``, ``reaction`` per displacement node; ``sigma`` and ``deps_p`` per
        stress point (full Voigt, not rotated).

    Raises
    ------
    SolverError
        Status other than Solved/AlmostSolved, or a non-finite result.
    """
    options = options or SolverOptions()
    t0 = time.perf_counter()
    _check(data)
    lay = _Layout(data)
    P, q, A, b, cones, kinds = _assemble(lay)
    if options.scaling:
        s_star, F_star, U_star = _scales(data, lay)
    else:
        s_star = F_star = U_star = 1.0
    J_star = F_star * U_star
    col = np.concatenate(
        [np.full(lay.n_sigma, s_star), np.full(lay.nx - lay.n_sigma, F_star)]
    )
    R = np.concatenate(
        [np.full(n, 1 / F_star if k == "F" else 1 / s_star) for k, n in kinds]
    )
    Dc = sp.diags(col)
    A_hat = (sp.diags(R) @ A @ Dc).tocsc()
    P_hat = sp.triu((Dc @ P @ Dc / J_star).tocsc(), format="csc")
    t1 = time.perf_counter()
    sol, status, iters, backend, (t_setup, t_solve) = _solve(
        P_hat, col * q / J_star, A_hat, R * b, cones, options, lay.nx, lay.dim
    )
    t3 = time.perf_counter()
    if status not in ACCEPTED:
        raise SolverError(status, step, iters, _hint(status, data))
    x = col * np.asarray(sol.x)
    z = J_star * R * np.asarray(sol.z)
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
        raise SolverError("NonFinite", step, iters, _hint("NonFinite", data))
    out = _read_back(lay, x, z)
    timings = {
        "assembly": (t1 - t0) + (time.perf_counter() - t3),
        "setup": t_setup,
        "solve": t_solve,
    }
    sizes = {"variables": lay.nx, "rows": int(b.size), "nnz_A": int(A.nnz)}
    sizes["linear_solver"] = backend
    return StepSolution(
        **out, status=status, iterations=iters, timings=timings, sizes=sizes
    )


def _read_back(lay: _Layout, x: np.ndarray, z: np.ndarray) -> dict:
    """Displacements, stresses, plastic strains, reactions, contact forces."""
    data, op, d = lay.data, lay.data.points, lay.dim
    du = np.zeros(d * lay.n_nodes)
    du[lay.free] = -z[: lay.free.size]
    du[lay.pres] = lay.ubar
    dsig = x[: lay.n_sigma].reshape(lay.n_pts, lay.ns)
    sig_sel = lay.sig_n + dsig
    sigma = np.array(data.sigma_n, dtype=float, copy=True)
    sigma[:, lay.comp] = sig_sel
    deps_sel = op.strain(du) - np.einsum("nij,nj->ni", lay.compliance, dsig)
    deps_p = np.zeros_like(sigma)
    deps_p[:, lay.comp] = deps_sel
    elastic = np.array([not m.plastic for m in data.materials])[data.material]
    deps_p[elastic] = 0.0
    if d == 2 and 2 not in lay.comp:
        nu = np.array([m.nu for m in data.materials])[data.material]
        sigma[:, 2] = data.sigma_n[:, 2] + nu * (dsig[:, 0] + dsig[:, 1])
    reaction = np.zeros(d * lay.n_nodes)
    if lay.pres.size:
        r_p = 0.0
        if data.dynamic:
            r_p = lay.mt[lay.pres] * lay.ubar / data.dt**2
        gs = op.G[lay.pres] @ sig_sel.reshape(-1)
        reaction[lay.pres] = gs + r_p - lay.ftilde[lay.pres]
    off = lay.n_sigma + lay.nr
    lam_t = np.zeros((lay.nc, d - 1))
    lam_t[lay.fric] = x[off + lay.nc : off + lay.nc + lay.nt].reshape(-1, d - 1)
    return {
        "du": du.reshape(lay.n_nodes, d),
        "sigma": sigma,
        "deps_p": deps_p,
        "reaction": reaction.reshape(lay.n_nodes, d),
        "lambda_n": x[off : off + lay.nc],
        "lambda_t": lam_t,
    }
