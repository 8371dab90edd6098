"""One N-PFEM time step as a Clarabel cone program.

The mixed (stress-based) step of docs/theory.md ("The mixed step", "Scaling"):

    minimise   1/2 sum_p V_p (s_p - s_n,p)^T C (s_p - s_n,p)
               + 1/2 sum_j dt^2/m~_j r_j^2
               - (prescribed-displacement work) + sum_c g_c lambda_c
    subject to (G s + r - N lambda_n - T lambda_t)_F = f~_F     (equilibrium)
               lambda_n >= 0, |lambda_t| <= mu lambda_bar_n    (contact)
               k_p - a_p^T s_p >= || M s_p ||                    (yield cone per point)

:func:`solve_step` runs four named stages:

1. **build** (:func:`build_program`): the objective terms and row families of
   :mod:`skfem_npfem.step.families` on the step's
   :class:`~skfem_npfem.step.program.Program`;
2. **scale** (:func:`scale_program`): non-dimensionalise with a stress scale
   ``s*``, a length ``h`` and a displacement scale ``U*`` (``s* h / E`` for
   static steps, smaller when inertia dominates: :func:`displacement_scale`);
   without it the interior-point method needs several times the iterations or
   fails (docs/theory.md, "Scaling");
3. **solve** (:func:`~skfem_npfem.step.solver.solve_clarabel`), with the refined
   retry;
4. **recover** (:func:`recover`): the displacement increment is the multiplier
   of the equilibrium rows, ``du_F = -z_eq`` (Clarabel's stationarity is
   ``P x + q + A^T z = 0``), then stresses, plastic strains, reactions and
   contact forces.

The stress unknowns are the *increments* ``ds = s - s_n``: the equilibrium
right-hand side becomes the out-of-balance force ``f~ - G s_n`` and each cone is
shifted by ``s_n``.  This is the same program (same feasible set and optimum),
but the solver's relative tolerance then bounds the error of the increment
rather than that of the total stress, which keeps a body at rest at rest and a
small step accurate (docs/extremes.md).  The static variant drops the inertial
force ``r``.  Stresses live at the operator's stress points, displacements at
its nodes (:mod:`skfem_npfem.step.program`).
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError, SolverError
from ..profiles import check_factors
from .families import OBJECTIVE_TERMS, ROW_FAMILIES
from .program import Assembled, ConeInput, Program, assemble
from .solver import ACCEPTED, SolverOptions, hint, solve_clarabel

__all__ = [
    "ConeSolution",
    "Scaled",
    "build_program",
    "cell_size",
    "check_step_data",
    "displacement_scale",
    "recover",
    "scale_program",
    "solve_step",
    "stress_scale",
]


@dataclass
class ConeSolution:
    """The solver's raw solution of one cone program (:func:`solve_step`).

    Arrays on the program's nodes and stress points, not yet on the particles
    (stresses not yet rotated); :func:`~skfem_npfem.advance` turns it into new
    particles and keeps it as ``step.solution``.

    Attributes
    ----------
    du : ndarray (N, d)
        Displacement increment at the nodes (from the equilibrium duals), m.
    sigma : ndarray (n_p, n_full)
        End-of-step stress at the stress points (full Voigt, not yet rotated), Pa.
    deps_p : ndarray (n_p, n_full)
        Plastic strain increment (engineering shear).
    reaction : ndarray (N, d)
        Reaction forces on prescribed dofs (zero elsewhere), N.
    lambda_n : ndarray (nc,)
        Contact normal forces on the body, N.
    lambda_t : ndarray (nc, d-1)
        Contact tangential forces on the body, N.
    status : str
        Clarabel status.
    iterations : int
        Interior-point iterations.
    timings : dict
        Seconds spent in ``assembly``, ``setup`` and ``solve``.
    sizes : dict
        Variables, rows and nonzeros of the program, and the linear solver.
    pore_pressure : ndarray (n_p,) or None
        Excess pore pressure at the end of the step, Pa (compression
        positive; None in a dry step).  With water, ``sigma`` is the
        effective stress.
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
    pore_pressure: np.ndarray | None = None


def solve_step(
    data: ConeInput, options: SolverOptions | None = None, step: int | None = None
) -> ConeSolution:
    """Assemble and solve one N-PFEM step.

    Parameters
    ----------
    data : ConeInput
        Operators, state and loads of the step.
    options : SolverOptions, optional
        Clarabel settings.
    step : int, optional
        Step index, used in error messages.

    Returns
    -------
    ConeSolution

    Raises
    ------
    SolverError
        If Clarabel's status is not Solved/AlmostSolved or the result is not finite.
    """
    options = options or SolverOptions()
    t0 = time.perf_counter()
    check_step_data(data)
    prog, program = build_program(data, options.strength_floor)
    scaled = scale_program(prog, program, options.scaling)
    t1 = time.perf_counter()
    res = solve_clarabel(
        scaled.P,
        scaled.q,
        scaled.A,
        scaled.b,
        program.cones,
        options,
        prog.dim,
        coupled=bool(data.stabilisation) or couples_pore_pressures(data),
    )
    if res.status not in ACCEPTED:
        hint_ = hint(res.status, data.dynamic)
        raise SolverError(res.status, step, res.iterations, hint_)
    x = scaled.col * res.x
    z = scaled.J * scaled.row * res.z
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
        hint_ = hint("NonFinite", data.dynamic)
        raise SolverError("NonFinite", step, res.iterations, hint_)
    t2 = time.perf_counter()
    sol = recover(prog, x, z, res.status, res.iterations)
    t3 = time.perf_counter()
    sol.timings = {
        "assembly": (t1 - t0) + (t3 - t2),
        "setup": res.setup,
        "solve": res.solve,
    }
    sol.sizes = {
        "variables": prog.nx,
        "rows": int(program.b.size),
        "nnz_A": int(program.A.nnz),
        "linear_solver": res.linear_solver,
    }
    return sol


def couples_pore_pressures(data: ConeInput) -> bool:
    """Whether the objective couples neighbouring excess pore pressures.

    The pressure projection and Darcy's term of an undrained or coupled step
    put a graph Laplacian of the nodes into ``P``; like the stabilisation's
    coupling of the stresses, it makes the factor denser, and faer then beats
    qdldl (1 377-particle Mohr-Coulomb block, coupled, plane strain: 0.30 s
    against 0.54 s a solve, the drained step 0.24 s with qdldl;
    ``benchmarks/coupled_cost.py``).
    """
    pore = data.pore
    if pore is None or not pore.undrained:
        return False
    return pore.projection is not None or pore.darcy is not None


def build_program(
    data: ConeInput, strength_floor: float = 0.0
) -> tuple[Program, Assembled]:
    """Stage 1: the objective terms and row families of the step, stacked.

    ``strength_floor``: see :class:`~skfem_npfem.step.solver.SolverOptions`.
    """
    prog = Program(data, strength_floor)
    terms = [term(prog) for term in OBJECTIVE_TERMS]
    blocks = [family(prog) for family in ROW_FAMILIES]
    return prog, assemble(prog, terms, blocks)


@dataclass
class Scaled:
    """The non-dimensional program handed to Clarabel and its scales.

    ``x = col * x_hat``, ``z = J * row * z_hat`` (``J = F* U*``).
    """

    P: sp.csc_matrix
    q: np.ndarray
    A: sp.csc_matrix
    b: np.ndarray
    col: np.ndarray
    row: np.ndarray
    J: float


def scale_program(prog: Program, program: Assembled, scaling: bool = True) -> Scaled:
    """Stage 2: non-dimensionalise (docs/theory.md, "Scaling").

    Variables and rows in stress units are divided by ``s*``, those in force
    units by ``F* = s* h^(d-1)``; the objective by ``J* = F* U*``.
    """
    d = prog.dim
    h = cell_size(prog)
    if scaling:
        s_star = stress_scale(prog)
        F_star = s_star * h ** (d - 1)
        U_star = displacement_scale(prog, F_star, h)
    else:
        s_star = F_star = U_star = 1.0
    J_star = F_star * U_star
    unit = {"stress": s_star, "force": F_star}
    col = prog.layout.column_scale(unit)
    row = np.concatenate(
        [np.full(blk.rows, 1 / unit[blk.unit]) for blk in program.blocks]
    )
    Dc = sp.diags(col)
    A_hat = (sp.diags(row) @ program.A @ Dc).tocsc()
    P_hat = sp.triu((Dc @ program.P @ Dc / J_star).tocsc(), format="csc")
    return Scaled(
        P=P_hat,
        q=col * program.q / J_star,
        A=A_hat,
        b=row * program.b,
        col=col,
        row=row,
        J=J_star,
    )


def cell_size(prog: Program) -> float:
    """Length scale ``h = (|Omega| / N)^(1/d)``: the volume per displacement node.

    The displacement scale (and with it the scaling of the equilibrium duals)
    is per node, so ``h`` counts nodes, not stress points: an operator with
    several stress points per node (Gauss points of FEM elements) has the same
    ``h`` as nodal integration on the same mesh.
    """
    op = prog.data.operator
    return float(np.sum(op.volumes) / max(op.n_nodes, 1)) ** (1.0 / prog.dim)


def recover(
    prog: Program, x: np.ndarray, z: np.ndarray, status: str, iterations: int
) -> ConeSolution:
    """Stage 4: du, stresses, plastic strains, reactions and contact forces.

    ``x`` and ``z`` are the unscaled primal and dual solutions; the equilibrium
    rows come first, so ``du_F = -z[:n_free]``.  ``status`` and ``iterations``
    are Clarabel's.
    """
    data, op, d = prog.data, prog.data.operator, prog.dim
    N, comp = prog.n_nodes, list(prog.comp)
    du = np.zeros(d * N)
    if prog.tie is None:
        du[prog.free] = -z[: prog.free.size]
    else:  # a tied group's one row moves all its dofs
        du[prog.free] = -(prog.tie.T @ z[: prog.tie.shape[0]])
    du[prog.pres] = prog.ubar
    du = du.reshape(N, d)
    dsig = x[prog.slice("sigma")].reshape(prog.n_points, prog.ns)
    sig_sel = prog.sig_n + dsig
    sigma = np.array(data.sigma_n, dtype=float, copy=True)
    sigma[:, comp] = sig_sel
    deps_p = np.zeros_like(sigma)
    deps_p[:, comp] = op.strain(du) - np.einsum("nij,nj->ni", prog.compliance, dsig)
    if data.eigenstrain is not None:  # Bbar du = C ds + deps_p + e
        deps_p[:, comp] -= data.eigenstrain[:, comp]
    # Elastic points have no plastic strain (avoid round-off noise of B du - C ds).
    deps_p[np.array([not m.plastic for m in data.materials])[data.material]] = 0.0
    if d == 2 and 2 not in comp:
        # Plane strain: sigma_zz is elastic with eps_zz = 0 (docs/theory.md,
        # "The mixed step").
        nu = np.array([m.nu for m in data.materials])[data.material]
        sigma[:, 2] = data.sigma_n[:, 2] + nu * (dsig[:, 0] + dsig[:, 1])
    # Reactions on prescribed dofs: R = G s + r - f~.
    reaction = np.zeros(d * N)
    pore = None
    if data.pore is not None:
        pore = np.asarray(data.pore.excess, float).copy()
        if prog.size("pore"):
            pore = pore + x[prog.slice("pore")]
        if data.pore.drained is not None:
            pore[np.asarray(data.pore.drained, int)] = 0.0  # exactly, not to tol
    if prog.pres.size:
        gs = op.G[prog.pres] @ sig_sel.reshape(-1)
        if pore is not None and np.any(pore):
            gs = gs - prog.Q[prog.pres] @ pore
        r_p = 0.0
        if data.dynamic:
            r_p = prog.mt[prog.pres] * prog.ubar / data.dt**2
        reaction[prog.pres] = gs + r_p - prog.ftilde[prog.pres]
    lam_t = np.zeros((prog.size("lambda_n"), d - 1))
    lam_t[prog.fric] = x[prog.slice("lambda_t")].reshape(-1, d - 1)
    return ConeSolution(
        du=du,
        sigma=sigma,
        deps_p=deps_p,
        reaction=reaction.reshape(N, d),
        lambda_n=x[prog.slice("lambda_n")],
        lambda_t=lam_t,
        status=status,
        iterations=iterations,
        pore_pressure=pore,
    )


def check_step_data(data: ConeInput) -> None:
    """Refuse inputs that would otherwise give NaN or silent garbage.

    Raises
    ------
    ParameterError
        For material ids outside ``materials``, a degenerate mesh element
        (zero area/volume: its P1 gradients are infinite), a non-positive or
        non-finite ``stress_scale``, an eigenstrain not shaped like the
        stresses or not finite, or (dynamic steps) a time step, mass or
        velocity that is not finite and positive where required; and a
        static step of a body that nothing holds (:func:`_check_supported`).
    """
    op = data.operator
    n, n_nodes = op.n_points, op.n_nodes
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
            f"an index into the {n_mat} material(s), 0..{n_mat - 1} (point {i})",
        )
    op.check()
    if data.eigenstrain is not None:
        e = np.asarray(data.eigenstrain, float)
        shape = np.shape(data.sigma_n)
        if e.shape != shape or not np.all(np.isfinite(e)):
            raise ParameterError(
                "eigenstrain", f"array of shape {e.shape}", f"finite, {shape}"
            )
    for name, positive in (("strength", False), ("stiffness", True)):
        if getattr(data, name) is not None:
            check_factors(name, getattr(data, name), len(data.sigma_n), positive)
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
        if m.shape != (n_nodes,) or not np.all(np.isfinite(m) & (m > 0)):
            raise ParameterError(
                "mass",
                f"array of shape {m.shape}",
                f"({n_nodes},) finite masses > 0 (kg)",
            )
        v = np.asarray(data.v_n, float)
        if v.shape != (n_nodes, op.dim) or not np.all(np.isfinite(v)):
            raise ParameterError(
                "v_n",
                f"array of shape {v.shape}",
                f"({n_nodes}, {op.dim}), finite (m/s)",
            )
    else:
        _check_supported(data)


def _check_supported(data: ConeInput) -> None:
    """Refuse a static step whose load moves the body as a rigid body.

    With no fixed degree of freedom and no contact row (no wall or body
    touches it), a translation strains nothing; a static step then has no
    equilibrium if the load has a resultant along it (gravity on a body
    nothing supports), and Clarabel calls the program infeasible, which
    reads like a load above the collapse load.  Said here instead.
    """
    if np.any(data.fixed) or np.asarray(data.contacts.node).size:
        return
    op = data.operator
    force = np.asarray(data.force, float).reshape(op.n_nodes, op.dim)
    total = float(np.abs(force).sum())
    for k in range(op.dim):
        resultant = float(force[:, k].sum())
        if not abs(resultant) > 1e-9 * total:
            continue
        u = np.zeros((op.n_nodes, op.dim))
        u[:, k] = 1.0
        if np.max(np.abs(op.strain(u)), initial=0.0) > 1e-8:
            continue  # not a rigid motion (the radius in axisymmetry)
        raise ParameterError(
            "mode",
            "static",
            f"a supported body: nothing holds it (no fixed degree of freedom, no "
            f"wall or body touching it), so its load (resultant {resultant:.4g} N "
            f"along axis {k}) moves it as a rigid body, which a static step does "
            "not support; fix degrees of freedom (Particles(fixed=...)), add a "
            "wall (Model(walls=...)) or a body, or use mode='dynamic'",
        )


def stress_scale(prog: Program) -> float:
    """Characteristic stress s* for scaling (user value or an automatic one).

    The largest of: the current stress, the plastic strengths, the total
    external load spread over the body's cross-section (``rho g H`` for a column
    under gravity, up to a factor of order one), and the stress ``E |e|`` of a
    prescribed eigenstrain ``e`` if it were confined (it sets the increments of
    an unloaded body, e.g. a volume correction).
    """
    data, op = prog.data, prog.data.operator
    if data.stress_scale is not None:
        return float(data.stress_scale)
    cands = [float(np.max(np.abs(data.sigma_n), initial=0.0))]
    section = float(op.volumes.sum()) ** ((op.dim - 1) / op.dim)
    cands.append(float(np.abs(np.asarray(data.force)).sum()) / section)
    cands += [float(np.max(cone.k)) for _, cone in prog.yield_cones]
    if data.eigenstrain is not None:
        e = float(np.max(np.abs(data.eigenstrain)))
        cands.append(max(m.E for m in data.materials) * e)
    s = max(cands)
    if not s > 0.0:
        s = min(m.E for m in data.materials) * 1e-6
    return s


def displacement_scale(prog: Program, F_star: float, h: float) -> float:
    """Displacement scale ``U* = F* / (k_el + k_in)`` (docs/theory.md, "Scaling").

    ``k_el = E h^(d-2)`` is the stiffness of one smoothing cell and
    ``k_in = m~ / dt^2`` (mean modified nodal mass, dynamic steps only) its
    inertia.  The static choice, ``U* = s* h / E``, is the ``k_in = 0``
    case; it stays right while the CFL number ``c dt / h`` is of order one or
    larger.  For small time steps the increment is governed by inertia,
    ``du ~ F* dt^2 / m~``, which is ``(c dt / h)^2`` times the static scale: the
    scaled duals (``du = -U* z_eq``) would then be tiny and ``du`` (hence the
    velocity) would lose its digits to round-off and the solver tolerance
    (a column at rest moved at ``|v| ~ g t`` for ``dt = 1e-9`` s).  With both
    terms the scaled increment stays of order one in every regime, and nothing
    changes when ``k_in << k_el``.
    """
    data = prog.data
    k_el = min(m.E for m in data.materials) * h ** (prog.dim - 2)
    k_in = 0.0
    if data.dynamic and prog.mt.size:
        k_in = float(np.mean(prog.mt)) / data.dt**2
    return F_star / (k_el + k_in)
