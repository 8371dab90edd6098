"""One N-PFEM time step as a Clarabel cone program.

The mixed (stress-based) step of ``formulation.md`` §3-§5:

    minimise   1/2 sum_i V_i (s_i - s_n,i)^T C (s_i - s_n,i)
               + 1/2 sum_j dt^2/m~_j r_j^2
               - (prescribed-displacement work) + sum_c g_c lambda_c
    subject to (G s + r - N lambda_n - T lambda_t)_F = f~_F     (equilibrium)
               lambda_n >= 0, |lambda_t| <= mu lambda_bar_n    (contact)
               k_i - a_i^T s_i >= || M s_i ||                    (yield cone per node)

The displacement increment is the multiplier of the equilibrium rows:
``du_F = -z_eq`` (Clarabel's stationarity is ``P x + q + A^T z = 0``).  The static
variant drops the inertial force ``r``.  The problem is non-dimensionalised with a
stress scale ``s*``, a length ``h`` and a displacement scale ``U*`` (``s* h / E``
for static steps, smaller when inertia dominates: :func:`_displacement_scale`)
before it is handed to Clarabel; without that the interior-point method needs
several times the iterations or fails (pitfall 5).

The stress unknowns are the *increments* ``ds_i = s_i - s_n,i``: the equilibrium
right-hand side becomes the out-of-balance force ``f~ - G s_n`` and each cone is
shifted by ``s_n``.  This is the same program (same feasible set and optimum),
but the solver's relative tolerance then bounds the error of the increment
rather than that of the total stress, which keeps a body at rest at rest and a
small step accurate (docs/extremes.md).

Pieces of the program are built by small named functions (``_objective``,
``_equilibrium``, ``_contact_rows``, ``_yield_rows``) so a reader finds each
physical ingredient by name.
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass, field

import clarabel
import numpy as np
import scipy.sparse as sp

from .backends import (
    choose_linear_solver,
    faer_threads,
    mkl_available,
    pardiso_thread_count,
    pardiso_threads,
)
from .errors import ParameterError, SolverError
from .materials import Material
from .smoothing import NodalIntegration

__all__ = [
    "Contacts",
    "SolverOptions",
    "StepData",
    "StepSolution",
    "solve_step",
]

LINEAR_SOLVERS = ("auto", "qdldl", "faer", "mkl")
ACCEPTED = ("Solved", "AlmostSolved")
ACCURACY_PRESETS = {"high": 1e-8, "fast": 1e-6}


@dataclass
class SolverOptions:
    """Settings passed to Clarabel.

    Parameters
    ----------
    linear_solver : {"auto", "qdldl", "faer", "mkl"}
        Clarabel's ``direct_solve_method``.  ``"auto"`` picks by availability,
        dimension and size (:func:`skfem_npfem.backends.choose_linear_solver`):
        MKL Pardiso when installed, else qdldl for small 2D and faer otherwise.
    max_threads : int
        Threads of the linear solver, faer or MKL Pardiso.  0 (default): MKL's
        own choice (all physical cores) for Pardiso; for faer one thread on
        machines with at most 2 cores (17-22 % faster than two there, in 2D and
        3D: docs/performance.md), else Clarabel's choice.  qdldl is
        single-threaded.
    tol : float
        Gap and feasibility tolerances (Clarabel default 1e-8).
    max_iter : int
        Interior-point iteration limit.
    time_limit : float
        Seconds per solve (``inf``: none).
    verbose : bool
        Print Clarabel's log.
    scaling : bool
        Non-dimensionalise the program (strongly recommended).
    iterative_refinement : bool or None
        Clarabel's iterative refinement of each KKT solve.  None (default): off
        for MKL Pardiso, where it cost 25-40 % of the step for changes of ~1e-8
        in the results (docs/performance.md), on for qdldl and faer.  When a
        solve without refinement ends in ``InsufficientProgress`` or
        ``NumericalError`` it is repeated once with refinement before the error
        is raised (the time of both solves is reported).
    accuracy : {"high", "fast"} or None
        Preset that overrides ``tol``: ``"high"`` = 1e-8 (Clarabel's default),
        ``"fast"`` = 1e-6 (fewer interior-point iterations; its cost in accuracy
        is measured in docs/performance.md).
    reproducible : bool
        MKL Pardiso only: run in MKL's conditional numerical reproducibility
        mode, so that identical runs and resumed runs give bit-identical
        results.  False saves 20-24 % of an MKL step, but round-off then
        varies from run to run (a full column collapse differs in the 3rd-4th
        digit of the run-out).  qdldl and faer are always reproducible.
    """

    linear_solver: str = "auto"
    max_threads: int = 0
    tol: float = 1e-8
    max_iter: int = 200
    time_limit: float = math.inf
    verbose: bool = False
    scaling: bool = True
    accuracy: str | None = None
    iterative_refinement: bool | None = None
    reproducible: bool = True

    def __post_init__(self) -> None:
        if self.accuracy is not None:
            if self.accuracy not in ACCURACY_PRESETS:
                raise ParameterError(
                    "accuracy", self.accuracy, f"one of {tuple(ACCURACY_PRESETS)}"
                )
            self.tol = ACCURACY_PRESETS[self.accuracy]
        if self.linear_solver not in LINEAR_SOLVERS:
            raise ParameterError(
                "linear_solver", self.linear_solver, f"one of {LINEAR_SOLVERS}"
            )
        if not isinstance(self.reproducible, bool):
            raise ParameterError("reproducible", self.reproducible, "True or False")
        if not (isinstance(self.max_threads, int) and self.max_threads >= 0):
            raise ParameterError("max_threads", self.max_threads, "an integer >= 0")
        if not (math.isfinite(self.tol) and 0 < self.tol < 1e-2):
            raise ParameterError("tol", self.tol, "a number in (0, 1e-2)")
        if not (isinstance(self.max_iter, int) and self.max_iter > 0):
            raise ParameterError("max_iter", self.max_iter, "an integer > 0")
        if not (isinstance(self.time_limit, numbers.Real) and self.time_limit > 0):
            raise ParameterError("time_limit", self.time_limit, "seconds > 0 (or inf)")

    def resolved_linear_solver(self, n_variables: int, dim: int) -> str:
        """The backend actually used (``auto`` resolved by problem size).

        Raises
        ------
        ParameterError
            If ``mkl`` is requested but MKL Pardiso cannot be loaded.
        """
        if self.linear_solver == "auto":
            return choose_linear_solver(n_variables, dim)
        if self.linear_solver == "mkl" and not mkl_available():
            raise ParameterError(
                "linear_solver",
                "mkl",
                "MKL Pardiso is not available; install it with "
                "pip install 'skfem-npfem[mkl]' or use auto, qdldl or faer",
            )
        return self.linear_solver

    def clarabel_settings(self, linear_solver: str | None = None):
        """Return a configured ``clarabel.DefaultSettings``."""
        s = clarabel.DefaultSettings()
        s.verbose = bool(self.verbose)
        s.direct_solve_method = linear_solver or self.linear_solver
        s.max_threads = int(self.max_threads)
        if s.direct_solve_method == "faer":
            s.max_threads = faer_threads(self.max_threads)
        if s.direct_solve_method == "mkl":
            # Pardiso's threads are set by solve_step (backends.pardiso_threads):
            # Clarabel would change them after the analysis, which crashes MKL.
            s.max_threads = 0
            if self.reproducible:
                # Conditional numerical reproducibility for this thread count:
                # identical runs and resumed runs give bit-identical results.
                iparm = list(s.pardiso_iparm)
                iparm[33] = max(1, pardiso_thread_count(self.max_threads))
                s.pardiso_iparm = iparm
        s.max_iter = int(self.max_iter)
        s.time_limit = float(self.time_limit)
        s.tol_gap_abs = s.tol_gap_rel = s.tol_feas = self.tol
        s.tol_infeas_abs = s.tol_infeas_rel = self.tol
        refine = self.iterative_refinement
        if refine is None:
            refine = s.direct_solve_method != "mkl"
        s.iterative_refinement_enable = bool(refine)
        return s


@dataclass
class Contacts:
    """Contact candidates of one step (node against a rigid plane).

    Attributes
    ----------
    node : ndarray (nc,) int
        Local node index.
    normal : ndarray (nc, d)
        Unit wall normal pointing into the body.
    gap : ndarray (nc,)
        Current gap (>= 0), m, plus ``normal . du_prescribed`` for a node with
        prescribed dofs (the program only sees the free dofs; non-penetration is
        ``gap + normal . du_free >= 0``).
    mu_lambda : ndarray (nc,)
        Friction bound ``mu * lambda_bar_n`` (N) from the previous step; values
        <= 0 mean frictionless (no tangential variable).

    Notes
    -----
    Sign conventions (``formulation.md`` §4.3): the wall pushes on the body, so
    the equilibrium rows read ``G s + r - N lambda_n - T lambda_t = f~`` with
    ``lambda_n >= 0``; the normal dual gives ``gap + n . du >= 0`` and is zero
    where ``lambda_n > 0``.  Tangential forces ``lambda_t`` act along
    :func:`_tangents` of the normal and oppose the slip ``t . du``.
    """

    node: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    mu_lambda: np.ndarray

    def __post_init__(self) -> None:
        self.node = np.asarray(self.node, dtype=np.int64).reshape(-1)
        nc = self.node.size
        self.normal = np.asarray(self.normal, dtype=float)
        self.gap = np.asarray(self.gap, dtype=float).reshape(-1)
        self.mu_lambda = np.asarray(self.mu_lambda, dtype=float).reshape(-1)
        if (
            self.normal.ndim != 2
            or self.normal.shape[0] != nc
            or self.gap.size != nc
            or self.mu_lambda.size != nc
        ):
            raise ParameterError(
                "contacts",
                (nc, self.normal.shape, self.gap.size, self.mu_lambda.size),
                "node (nc,), normal (nc, d), gap (nc,) and mu_lambda (nc,)",
            )
        if not (np.all(np.isfinite(self.gap)) and np.all(np.isfinite(self.mu_lambda))):
            raise ParameterError(
                "contacts", "non-finite values", "finite gap, mu_lambda"
            )

    @classmethod
    def empty(cls, dim: int) -> Contacts:
        """No contacts."""
        return cls(np.zeros(0, int), np.zeros((0, dim)), np.zeros(0), np.zeros(0))

    @property
    def size(self) -> int:
        """Number of candidates."""
        return int(self.node.shape[0])


@dataclass
class StepData:
    """Everything one cone step needs, on the active nodes of one mesh.

    Attributes
    ----------
    ni : NodalIntegration
        Smoothing operators (``ni.components`` selects the stress variables).
    materials : list of Material
        Materials referenced by ``material``.
    material : ndarray (N,) int
        Material index per node.
    sigma_n : ndarray (N, n_full)
        Stress at the start of the step (full Voigt), Pa.
    force : ndarray (N, d)
        External nodal force over the step (gravity ``m g`` plus tractions), N.
    fixed : ndarray (N, d) bool
        Prescribed degrees of freedom.
    du_prescribed : ndarray (N, d)
        Displacement increment on prescribed dofs (ignored elsewhere), m.
    contacts : Contacts
        Contact candidates.
    dt : float
        Time step, s (dynamic only).
    mass : ndarray (N,) or None
        Nodal masses, kg (dynamic only).
    v_n : ndarray (N, d) or None
        Velocity at the start of the step, m/s (dynamic only).
    theta1, theta2 : float
        Time-integration parameters (dynamic only).
    dynamic : bool
        Include inertia (otherwise quasi-static).
    stress_scale : float or None
        Stress scale ``s*`` for non-dimensionalisation (None: automatic).
    """

    ni: NodalIntegration
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


@dataclass
class StepSolution:
    """Result of :func:`solve_step`.

    Attributes
    ----------
    du : ndarray (N, d)
        Displacement increment (from the equilibrium duals), m.
    sigma : ndarray (N, n_full)
        End-of-step stress (full Voigt, not yet rotated), Pa.
    deps_p : ndarray (N, n_full)
        Plastic strain increment (engineering shear).
    reaction : ndarray (N, d)
        Reaction forces on prescribed dofs (zero elsewhere), N.
    lambda_n, lambda_t : ndarray
        Contact normal (nc,) and tangential (nc, d-1) forces on the body, N.
    status : str
        Clarabel status.
    iterations : int
        Interior-point iterations.
    timings : dict
        Seconds spent in ``assembly``, ``setup`` and ``solve``.
    sizes : dict
        Variables, rows and nonzeros of the program.
    """

    du: np.ndarray
    sigma: np.ndarray
    deps_p: np.ndarray
    reaction: np.ndarray
    lambda_n: np.ndarray
    lambda_t: np.ndarray
    status: str
    iterations: int
    timings: dict = field(default_factory=dict)
    sizes: dict = field(default_factory=dict)


def _block_diag_upper(blocks: np.ndarray) -> sp.csc_matrix:
    """Upper triangle of a block-diagonal matrix from (n, b, b) blocks."""
    n, b, _ = blocks.shape
    iu, ju = np.triu_indices(b)
    base = (np.arange(n) * b)[:, None]
    return sp.csc_matrix(
        (blocks[:, iu, ju].ravel(), ((base + iu).ravel(), (base + ju).ravel())),
        shape=(n * b, n * b),
    )


class _Program:
    """Assembled (unscaled) blocks of the cone program and their layout."""

    def __init__(self, data: StepData) -> None:
        ni = data.ni
        self.dim = d = ni.dim
        self.N = N = ni.n_nodes
        self.comp = list(ni.components)
        self.ns = ns = len(self.comp)
        self.data = data
        dofs_fixed = np.asarray(data.fixed, bool).reshape(-1)
        self.free = np.flatnonzero(~dofs_fixed)
        self.pres = np.flatnonzero(dofs_fixed)
        self.ubar = np.asarray(data.du_prescribed, float).reshape(-1)[self.pres]
        self.sig_n = np.asarray(data.sigma_n, float)[:, self.comp]
        # Generalised external force f~ (formulation.md §3).
        f = np.asarray(data.force, float).reshape(-1)
        if data.dynamic:
            th1, th2 = data.theta1, data.theta2
            self.mt = np.repeat(np.asarray(data.mass, float), d) / (th1 * th2)
            f = f / th1 + self.mt * np.asarray(data.v_n, float).reshape(-1) / data.dt
            if th1 != 1.0:
                f = f - (1 - th1) / th1 * (ni.G @ self.sig_n.reshape(-1))
        self.ftilde = f
        c = data.contacts
        self.nc = c.size
        self.fric = np.flatnonzero(c.mu_lambda > 0.0)  # contacts with friction
        self.nt = self.fric.size * (d - 1)
        self.nr = self.free.size if data.dynamic else 0
        self.n_sigma = N * ns
        self.nx = self.n_sigma + self.nr + self.nc + self.nt
        # Physical blocks
        self.compliance = np.empty((N, ns, ns))
        for m_id, mat in enumerate(data.materials):
            sel = data.material == m_id
            if np.any(sel):
                self.compliance[sel] = mat.compliance(d, tuple(self.comp))

    # -- objective ------------------------------------------------------------
    def objective(self) -> tuple[sp.csc_matrix, np.ndarray]:
        data, ni = self.data, self.data.ni
        V = ni.volumes
        blocks = V[:, None, None] * self.compliance
        P_sigma = _block_diag_upper(blocks)
        q = np.zeros(self.nx)
        # The stress variables are the increments ds = s - s_n, so the energy
        # 1/2 ds^T V C ds has no linear term (see ``solve_step``).
        q_sigma = np.zeros(self.n_sigma)
        if self.pres.size:
            # Work of prescribed displacements: -G_P^T ubar.
            q_sigma -= ni.G[self.pres].T @ self.ubar
        q[: self.n_sigma] = q_sigma
        diag = []
        if self.nr:
            diag.append(data.dt**2 / self.mt[self.free])
        n_rest = self.nc + self.nt
        diag.append(np.zeros(n_rest))
        P = sp.block_diag([P_sigma, sp.diags(np.concatenate(diag))], format="csc")
        # Contact gaps enter the objective linearly.
        q[self.n_sigma + self.nr : self.n_sigma + self.nr + self.nc] = (
            self.data.contacts.gap
        )
        return P, q

    # -- constraints -----------------------------------------------------------
    def contact_maps(self) -> tuple[sp.csc_matrix, sp.csc_matrix]:
        """Place contact forces on dofs: N (dN x nc) and T (dN x nt)."""
        d, c = self.dim, self.data.contacts
        ndof = d * self.N
        rows = (d * c.node[:, None] + np.arange(d)).ravel()
        Nmat = sp.csc_matrix(
            (c.normal.ravel(), (rows, np.repeat(np.arange(self.nc), d))),
            shape=(ndof, self.nc),
        )
        tang = _tangents(c.normal[self.fric])  # (nf, d-1, d)
        nodes = c.node[self.fric]
        if self.nt:
            r = (d * nodes[:, None, None] + np.arange(d)[None, None, :]) * np.ones(
                (1, d - 1, 1), int
            )
            col = np.arange(self.nt).reshape(-1, d - 1)[:, :, None] * np.ones(
                (1, 1, d), int
            )
            Tmat = sp.csc_matrix(
                (tang.ravel(), (r.ravel(), col.ravel())), shape=(ndof, self.nt)
            )
        else:
            Tmat = sp.csc_matrix((ndof, 0))
        return Nmat, Tmat

    def equilibrium(self) -> tuple[sp.csc_matrix, np.ndarray]:
        """Rows (G s + r - N lambda_n - T lambda_t)_F = f~_F."""
        G = self.data.ni.G
        Nmat, Tmat = self.contact_maps()
        blocks = [G[self.free]]
        if self.nr:
            blocks.append(sp.identity(self.nr, format="csc"))
        blocks += [-Nmat[self.free], -Tmat[self.free]]
        # In the increments ds the right-hand side is the out-of-balance force.
        rhs = self.ftilde[self.free] - G[self.free] @ self.sig_n.reshape(-1)
        return sp.hstack(blocks, format="csc"), rhs

    def contact_rows(self) -> tuple[sp.csc_matrix, np.ndarray, int]:
        """Nonnegative rows: lambda_n >= 0 and 2D friction |lambda_t| <= mu lambda."""
        off_n = self.n_sigma + self.nr
        off_t = off_n + self.nc
        rows, cols, vals, b = [], [], [], []
        nrow = 0
        if self.nc:
            rows.append(np.arange(self.nc))
            cols.append(off_n + np.arange(self.nc))
            vals.append(-np.ones(self.nc))
            b.append(np.zeros(self.nc))
            nrow = self.nc
        if self.nt and self.dim == 2:
            bound = self.data.contacts.mu_lambda[self.fric]
            nf = self.fric.size
            for sign in (1.0, -1.0):  # s = mu*lam - sign*lambda_t >= 0
                rows.append(nrow + np.arange(nf))
                cols.append(off_t + np.arange(nf))
                vals.append(np.full(nf, sign))
                b.append(bound)
                nrow += nf
        A = _coo(rows, cols, vals, nrow, self.nx)
        return A, (np.concatenate(b) if b else np.zeros(0)), nrow

    def cones(self):
        """``(nodes, ConeRows)`` of every plastic material, one per cone.

        A material may return a list of cones per node (axisymmetric
        Mohr-Coulomb: three SOC(3), ``skfem_npfem.axisymmetric``).
        """
        data = self.data
        for m_id, mat in enumerate(data.materials):
            nodes = np.flatnonzero(data.material == m_id)
            if nodes.size == 0 or not mat.plastic:
                continue
            rows = mat.cone(self.dim, tuple(self.comp), data.sigma_n[nodes])
            for cone in _cone_list(rows):
                yield nodes, cone

    def yield_rows(self):
        """Cut-off rows (nonnegative) and one SOC per plastic node (and cone)."""
        ns = self.ns
        soc_blocks = []  # (A coo parts, b, cone dims)
        cut_rows, cut_cols, cut_vals, cut_b = [], [], [], []
        for nodes, cone in self.cones():
            m = cone.M.shape[0]
            # Rows per node: [a^T ; -M] on ds_i, b = (k - a^T s_n ; M s_n).
            rowmat = np.concatenate(
                [cone.a[:, None, :], np.broadcast_to(-cone.M, (nodes.size, m, ns))],
                axis=1,
            )  # (n, 1+m, ns)
            sn = self.sig_n[nodes]
            bvec = np.empty((nodes.size, 1 + m))
            bvec[:, 0] = cone.k - np.einsum("ns,ns->n", cone.a, sn)
            bvec[:, 1:] = sn @ cone.M.T
            soc_blocks.append((nodes, rowmat, bvec, 1 + m))
            if cone.cutoff_a is not None:
                cut_rows.append(np.arange(nodes.size))
                cut_cols.append(nodes)
                cut_vals.append(cone.cutoff_a)
                cut_b.append(cone.cutoff_k - sn @ cone.cutoff_a)
        return soc_blocks, (cut_cols, cut_vals, cut_b)

    def friction_cones_3d(self):
        """SOC(3) rows (mu lambda_bar ; lambda_t) per frictional contact in 3D."""
        nf = self.fric.size
        off_t = self.n_sigma + self.nr + self.nc
        rows = (3 * np.arange(nf)[:, None] + np.array([1, 2])).ravel()
        cols = off_t + np.arange(2 * nf)
        A = sp.csc_matrix((-np.ones(2 * nf), (rows, cols)), shape=(3 * nf, self.nx))
        b = np.zeros((nf, 3))
        b[:, 0] = self.data.contacts.mu_lambda[self.fric]
        return A, b.ravel(), nf


def _cone_list(rows) -> list:
    """A material's cone rows as a list (one ConeRows, or several)."""
    return list(rows) if isinstance(rows, list | tuple) else [rows]


def _coo(rows, cols, vals, nrow, ncol) -> sp.csc_matrix:
    if not rows:
        return sp.csc_matrix((nrow, ncol))
    return sp.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(nrow, ncol),
    )


def _tangents(normals: np.ndarray) -> np.ndarray:
    """Unit tangents (n, d-1, d) orthogonal to unit normals (n, d)."""
    d = normals.shape[1]
    if d == 2:
        return np.stack([-normals[:, 1], normals[:, 0]], axis=1)[:, None, :]
    # 3D: pick the coordinate axis least aligned with n, Gram-Schmidt.
    ref = np.eye(3)[np.argmin(np.abs(normals), axis=1)]
    t1 = ref - np.sum(ref * normals, axis=1, keepdims=True) * normals
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    return np.stack([t1, t2], axis=1)


def _check_step_data(data: StepData) -> None:
    """Refuse inputs that would otherwise give NaN or silent garbage.

    Raises
    ------
    ParameterError
        For material ids outside ``materials``, a degenerate mesh element
        (zero area/volume: its P1 gradients are infinite), a non-positive or
        non-finite ``stress_scale``, or (dynamic steps) a time step, mass or
        velocity that is not finite and positive where required.
    """
    ni = data.ni
    n = ni.n_nodes
    mat = np.asarray(data.material)
    n_mat = len(data.materials)
    if mat.shape != (n,) or mat.dtype.kind not in "iu":
        raise ParameterError(
            "material", f"{mat.dtype} array of shape {mat.shape}", f"ints, ({n},)"
        )
    bad = (mat < 0) | (mat >= n_mat)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise ParameterError(
            "material",
            int(mat[i]),
            f"an index into the {n_mat} material(s), 0..{n_mat - 1} (node {i})",
        )
    degenerate = ~np.all(np.isfinite(ni.grads), axis=(1, 2))
    if np.any(degenerate):
        e = int(np.flatnonzero(degenerate)[0])
        raise ParameterError(
            "mesh",
            f"{int(degenerate.sum())} degenerate element(s) of zero "
            f"{'area' if ni.dim == 2 else 'volume'}, first {e} with nodes "
            f"{ni.t[:, e].tolist()}",
            "elements of nonzero size; drop them (remesh.alpha_shape does) or "
            "separate coincident/collinear nodes (near-degenerate elements are fine)",
        )
    if data.stress_scale is not None:
        s = data.stress_scale
        if isinstance(s, bool) or not (
            isinstance(s, numbers.Real) and math.isfinite(s) and s > 0
        ):
            raise ParameterError("stress_scale", s, "a finite stress > 0 (Pa) or None")
    if data.dynamic:
        dt = data.dt
        if not (isinstance(dt, numbers.Real) and math.isfinite(dt) and dt > 0):
            raise ParameterError("dt", dt, "a finite time step > 0 (s)")
        if data.mass is None or data.v_n is None:
            raise ParameterError(
                "mass" if data.mass is None else "v_n", None, "needed by dynamic steps"
            )
        m = np.asarray(data.mass, float)
        if m.shape != (n,) or not np.all(np.isfinite(m) & (m > 0)):
            raise ParameterError(
                "mass", f"array of shape {m.shape}", f"({n},) finite masses > 0 (kg)"
            )
        v = np.asarray(data.v_n, float)
        if v.shape != (n, ni.dim) or not np.all(np.isfinite(v)):
            raise ParameterError(
                "v_n", f"array of shape {v.shape}", f"({n}, {ni.dim}), finite (m/s)"
            )


def _stress_scale(data: StepData) -> float:
    """Characteristic stress s* for scaling (user value or an automatic one).

    The largest of: the current stress, the plastic strengths, and the total
    external load spread over the body's cross-section (``rho g H`` for a column
    under gravity, up to a factor of order one).
    """
    if data.stress_scale is not None:
        return float(data.stress_scale)
    ni = data.ni
    cands = [float(np.max(np.abs(data.sigma_n), initial=0.0))]
    section = float(ni.volumes.sum()) ** ((ni.dim - 1) / ni.dim)
    cands.append(float(np.abs(np.asarray(data.force)).sum()) / section)
    for m_id, mat in enumerate(data.materials):
        sel = data.material == m_id
        if mat.plastic and np.any(sel):
            rows = mat.cone(ni.dim, ni.components, data.sigma_n[sel])
            cands += [float(np.max(r.k)) for r in _cone_list(rows)]
    s = max(cands)
    if not s > 0.0:
        s = min(m.E for m in data.materials) * 1e-6
    return s


def _displacement_scale(data: StepData, prog: _Program, F_star: float, h: float):
    """Displacement scale ``U* = F* / (k_el + k_in)`` (formulation.md §5).

    ``k_el = E h^(d-2)`` is the stiffness of one smoothing cell and
    ``k_in = m~ / dt^2`` (mean modified nodal mass, dynamic steps only) its
    inertia.  The static choice of §5, ``U* = s* h / E``, is the ``k_in = 0``
    case; it stays right while the CFL number ``c dt / h`` is of order one or
    larger.  For small time steps the increment is governed by inertia,
    ``du ~ F* dt^2 / m~``, which is ``(c dt / h)^2`` times the static scale: the
    scaled duals (``du = -U* z_eq``) would then be tiny and ``du`` (hence the
    velocity) would lose its digits to round-off and the solver tolerance
    (a column at rest moved at ``|v| ~ g t`` for ``dt = 1e-9`` s).  With both
    terms the scaled increment stays of order one in every regime, and nothing
    changes when ``k_in << k_el``.
    """
    d = prog.dim
    k_el = min(m.E for m in data.materials) * h ** (d - 2)
    k_in = 0.0
    if data.dynamic and prog.mt.size:
        k_in = float(np.mean(prog.mt)) / data.dt**2
    return F_star / (k_el + k_in)


def solve_step(
    data: StepData, options: SolverOptions | None = None, step: int | None = None
) -> StepSolution:
    """Assemble and solve one N-PFEM step.

    Parameters
    ----------
    data : StepData
        Operators, state and loads of the step.
    options : SolverOptions, optional
        Clarabel settings.
    step : int, optional
        Step index, used in error messages.

    Returns
    -------
    StepSolution

    Raises
    ------
    SolverError
        If Clarabel's status is not Solved/AlmostSolved or the result is not finite.
    """
    options = options or SolverOptions()
    t0 = time.perf_counter()
    _check_step_data(data)
    prog = _Program(data)
    ni, d, N, ns = data.ni, prog.dim, prog.N, prog.ns
    P, q = prog.objective()
    A_eq, b_eq = prog.equilibrium()
    A_c, b_c, n_c = prog.contact_rows()
    socs, (cut_cols, cut_vals, cut_b) = prog.yield_rows()

    # Scales (formulation.md §5).
    h = float(np.mean(ni.volumes)) ** (1.0 / d)
    if options.scaling:
        s_star = _stress_scale(data)
        F_star = s_star * h ** (d - 1)
        U_star = _displacement_scale(data, prog, F_star, h)
    else:
        s_star = F_star = U_star = 1.0
    J_star = F_star * U_star
    col_scale = np.concatenate(
        [np.full(prog.n_sigma, s_star), np.full(prog.nx - prog.n_sigma, F_star)]
    )

    A_parts = [A_eq, A_c]
    b_parts = [b_eq, b_c]
    row_scale = [np.full(b_eq.size, 1 / F_star), np.full(n_c, 1 / F_star)]
    cones = [clarabel.ZeroConeT(b_eq.size)]
    n_nonneg = n_c
    if cut_cols:
        nodes = np.concatenate(cut_cols)
        vals = np.concatenate(
            [
                np.broadcast_to(v, (len(c), ns))
                for c, v in zip(cut_cols, cut_vals, strict=True)
            ]
        )
        rr = np.repeat(np.arange(nodes.size), ns)
        cc = (nodes[:, None] * ns + np.arange(ns)).ravel()
        A_parts.append(
            sp.csc_matrix((vals.ravel(), (rr, cc)), shape=(nodes.size, prog.nx))
        )
        b_parts.append(np.concatenate(cut_b))
        row_scale.append(np.full(nodes.size, 1 / s_star))
        n_nonneg += nodes.size
    if n_nonneg:
        cones.append(clarabel.NonnegativeConeT(n_nonneg))
    for nodes, rowmat, bvec, dim_cone in socs:
        n = nodes.size
        rr = np.broadcast_to(
            (np.arange(n)[:, None] * dim_cone + np.arange(dim_cone))[:, :, None],
            (n, dim_cone, ns),
        )
        cc = np.broadcast_to(
            (nodes[:, None] * ns + np.arange(ns))[:, None, :], (n, dim_cone, ns)
        )
        A_parts.append(
            sp.csc_matrix(
                (rowmat.ravel(), (rr.ravel(), cc.ravel())),
                shape=(n * dim_cone, prog.nx),
            )
        )
        b_parts.append(bvec.ravel())
        row_scale.append(np.full(n * dim_cone, 1 / s_star))
        cones.extend([clarabel.SecondOrderConeT(dim_cone)] * n)
    if prog.nt and d == 3:
        A_f, b_f, nf = prog.friction_cones_3d()
        A_parts.append(A_f)
        b_parts.append(b_f)
        row_scale.append(np.full(b_f.size, 1 / F_star))
        cones.extend([clarabel.SecondOrderConeT(3)] * nf)

    A = sp.vstack(A_parts, format="csc")
    b = np.concatenate(b_parts)
    R = np.concatenate(row_scale)
    Dc = sp.diags(col_scale)
    A_hat = (sp.diags(R) @ A @ Dc).tocsc()
    b_hat = R * b
    P_hat = (Dc @ P @ Dc / J_star).tocsc()
    P_hat = sp.triu(P_hat, format="csc")
    q_hat = col_scale * q / J_star
    t1 = time.perf_counter()
    backend = options.resolved_linear_solver(prog.nx, d)
    with pardiso_threads(options.max_threads if backend == "mkl" else 0):
        settings = options.clarabel_settings(backend)
        solver = clarabel.DefaultSolver(P_hat, q_hat, A_hat, b_hat, cones, settings)
        t2 = time.perf_counter()
        sol = solver.solve()
        status = str(sol.status)
        iters = int(sol.iterations)
        if status in ("InsufficientProgress", "NumericalError") and not (
            settings.iterative_refinement_enable
        ):
            # Without iterative refinement the KKT solves can be too inaccurate
            # near the optimum (seen in 3D at tol 1e-6): repeat once with it.
            settings.iterative_refinement_enable = True
            sol = clarabel.DefaultSolver(
                P_hat, q_hat, A_hat, b_hat, cones, settings
            ).solve()
            status = str(sol.status)
            iters += int(sol.iterations)
    t3 = time.perf_counter()
    if status not in ACCEPTED:
        raise SolverError(status, step, iters, _hint(status, data))
    x = col_scale * np.asarray(sol.x)
    z = J_star * R * np.asarray(sol.z)
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
        raise SolverError("NonFinite", step, iters, _hint("NonFinite", data))

    du = np.zeros(d * N)
    du[prog.free] = -z[: prog.free.size]
    du[prog.pres] = prog.ubar
    du = du.reshape(N, d)
    dsig = x[: prog.n_sigma].reshape(N, ns)
    sig_sel = prog.sig_n + dsig
    sigma = np.array(data.sigma_n, dtype=float, copy=True)
    sigma[:, prog.comp] = sig_sel
    deps = ni.strain(du)
    deps_p_sel = deps - np.einsum("nij,nj->ni", prog.compliance, dsig)
    deps_p = np.zeros_like(sigma)
    deps_p[:, prog.comp] = deps_p_sel
    # Elastic nodes have no plastic strain (avoid round-off noise of B du - C ds).
    elastic = np.array([not m.plastic for m in data.materials])[data.material]
    deps_p[elastic] = 0.0
    if d == 2 and 2 not in prog.comp:
        # sigma_zz is elastic with eps_zz = 0 (formulation.md §4.6).
        nu = np.array([m.nu for m in data.materials])[data.material]
        sigma[:, 2] = data.sigma_n[:, 2] + nu * (dsig[:, 0] + dsig[:, 1])
    # Reactions on prescribed dofs: R = G s + r - f~.
    reaction = np.zeros(d * N)
    if prog.pres.size:
        gs = ni.G[prog.pres] @ sig_sel.reshape(-1)
        r_p = 0.0
        if data.dynamic:
            r_p = prog.mt[prog.pres] * prog.ubar / data.dt**2
        reaction[prog.pres] = gs + r_p - prog.ftilde[prog.pres]
    off = prog.n_sigma + prog.nr
    lam_n = x[off : off + prog.nc]
    lam_t = np.zeros((prog.nc, d - 1))
    lam_t[prog.fric] = x[off + prog.nc : off + prog.nc + prog.nt].reshape(-1, d - 1)
    t4 = time.perf_counter()
    return StepSolution(
        du=du,
        sigma=sigma,
        deps_p=deps_p,
        reaction=reaction.reshape(N, d),
        lambda_n=lam_n,
        lambda_t=lam_t,
        status=status,
        iterations=iters,
        timings={
            "assembly": (t1 - t0) + (t4 - t3),
            "setup": t2 - t1,
            "solve": t3 - t2,
        },
        sizes={
            "variables": prog.nx,
            "rows": int(b.size),
            "nnz_A": int(A.nnz),
            "linear_solver": backend,
        },
    )


def _hint(status: str, data: StepData) -> str:
    """What the user can try for a failed status."""
    if status in ("PrimalInfeasible", "AlmostPrimalInfeasible"):
        if not data.dynamic:
            return (
                "the static problem has no admissible stress field: the load exceeds "
                "the collapse load; use displacement control or mode='dynamic'"
            )
        return "no admissible stress field; check strengths (c, phi) and cut-offs"
    if status in ("MaxIterations", "MaxTime"):
        return "raise max_iter/time_limit, reduce dt, or use accuracy='fast'"
    return (
        "reduce dt (the step is retried automatically when adaptive stepping is on), "
        "check material parameters for extreme ratios, or try linear_solver='qdldl'"
    )
