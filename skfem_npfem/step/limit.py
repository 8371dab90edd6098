"""Limit analysis: the collapse multiplier of a body as one cone program.

The step's cone program without elasticity, inertia or time: on the same
nodal-integration operator ``G`` and the same yield cones, find the largest
factor ``lambda`` on a reference load ``f1`` (on top of a fixed load ``f0``)
that a stress field in equilibrium can carry,

    maximise   lambda
    subject to T^T (G sigma - lambda f1) = T^T f0        (zero cone)
               k_p - a_p^T sigma_p >= || M sigma_p ||    (one SOC per point)
               a_c^T sigma_p <= k_c                      (tension cut-offs)

``T`` maps the velocity unknowns to the nodal degrees of freedom: fixed dofs
have no column, tied dofs (a rigid footing) share one.  The program is the
static form (lower-bound in spirit, mixed in its discretisation: the
equilibrium rows are the nodal-integration ones, not pointwise equilibrium).
The collapse mechanism comes back from the duals exactly as the step's
displacement does, ``u = -T z_eq``, normalised so that the reference load does
unit power (``f1 . u = 1``); the plastic strain rates are the cone duals over
the cell volumes, ``B u = A_K^T z_K / V``, and the dissipated power sums to
``lambda + f0 . u`` (strong duality).  docs/theory.md ("Limit analysis")
derives it.

:func:`limit_analysis` solves one program; :func:`~.safety.strength_reduction` finds the
factor of safety ``F`` of Mohr-Coulomb materials (``c/F``, ``tan(phi)/F``) such
that the gravity multiplier is 1, with a safeguarded secant iteration on
``log lambda(log F)`` (one cone program per iterate).
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field
from typing import Any

import clarabel
import numpy as np
import scipy.sparse as sp

from ..boundary import Contacts
from ..errors import ParameterError, SolverError
from ..materials import Material
from .families import cutoff, yield_cones
from .program import ConeInput, Program
from .solver import ACCEPTED, SolverOptions, hint, solve_clarabel

__all__ = ["LimitResult", "associated", "limit_analysis"]

#: Fraction of the largest dissipation density above which a point counts as
#: plastic (interior-point duals are never exactly zero).
PLASTIC_FRACTION = 1e-2


@dataclass
class LimitResult:
    """The collapse state of one limit analysis (:func:`limit_analysis`).

    Attributes
    ----------
    multiplier : float
        Collapse multiplier ``lambda`` on the reference load.
    velocity : ndarray (N, d)
        Collapse mechanism, normalised to unit power of the reference load
        (``sum(load * velocity) = 1``), m/s per unit of that power.
    sigma : ndarray (n_p, n_full)
        A stress field at collapse (full Voigt; components that are not cone
        variables are zero), Pa.
    strain_rate : ndarray (n_p, n_full)
        Plastic strain rate of the mechanism (engineering shear).
    dissipation : ndarray (n_p,)
        Plastic power dissipated in each cell, ``V_p sigma_p . strain_rate_p``.
    plastic : ndarray (n_p,) bool
        Cells whose dissipation density exceeds ``plastic_fraction`` of the
        largest one (the plastic zone of the mechanism).
    status : str
        Clarabel status.
    iterations : int
        Interior-point iterations.
    wall_time : float
        Seconds for building, solving and reading back the program.
    sizes : dict
        Variables, rows, nonzeros and the linear solver.
    """

    multiplier: float
    velocity: np.ndarray
    sigma: np.ndarray
    strain_rate: np.ndarray
    dissipation: np.ndarray
    plastic: np.ndarray
    status: str
    iterations: int
    wall_time: float
    sizes: dict = field(default_factory=dict)


def associated(material: Material) -> Material:
    """The material with associated flow (``psi = phi``): limit analysis uses it.

    The bound theorems need normality; a material with ``psi < phi`` is
    analysed with its ``phi`` cone (the frozen-friction device of the step is
    a time-stepping device and has no meaning without a previous stress).
    """
    if getattr(material, "psi", None) is None or material.psi == material.phi:
        return material
    out = copy.copy(material)
    out.psi = out.phi
    return out


def _dof_map(
    n_dofs: int, fixed: np.ndarray, tied: list[np.ndarray]
) -> tuple[sp.csc_matrix, int]:
    """``T`` (n_dofs x n_red): free dofs to velocity unknowns, tied dofs merged."""
    red = np.full(n_dofs, -1, dtype=np.int64)
    free = ~fixed
    owner = np.arange(n_dofs)
    for group in tied:
        g = np.asarray(group, dtype=np.int64).reshape(-1)
        g = g[free[g]]
        if g.size:
            owner[g] = g[0]
    roots = np.flatnonzero(free & (owner == np.arange(n_dofs)))
    red[roots] = np.arange(roots.size)
    dofs = np.flatnonzero(free)
    red[dofs] = red[owner[dofs]]
    T = sp.csc_matrix(
        (np.ones(dofs.size), (dofs, red[dofs])), shape=(n_dofs, roots.size)
    )
    return T, int(roots.size)


def limit_analysis(
    operator: Any,
    materials: list[Material],
    material: np.ndarray,
    load: np.ndarray,
    *,
    dead_load: np.ndarray | None = None,
    fixed: np.ndarray | None = None,
    tied: list[np.ndarray] | None = None,
    options: SolverOptions | None = None,
    plastic_fraction: float = PLASTIC_FRACTION,
    max_multiplier: float | None = None,
) -> LimitResult:
    """Collapse multiplier of a reference load, as one cone program.

    Parameters
    ----------
    operator : NodalIntegration or skfem.Mesh
        Strain operator of the body (a mesh is turned into
        :func:`~skfem_npfem.mesh.smoothing.nodal_integration` with the stress
        components the materials need).
    materials : list of Material
        Plastic materials (their elastic constants are not used).  Flow is
        taken associated (:func:`associated`).
    material : ndarray (n_p,) int
        Material index per stress point.
    load : ndarray (N, d)
        Reference nodal load ``f1`` that the multiplier scales, N.
    dead_load : ndarray (N, d), optional
        Load ``f0`` held fixed (default none), N.
    fixed : ndarray (N, d) bool, optional
        Dofs with zero velocity (supports).
    tied : list of int arrays, optional
        Groups of dof indices (node-major, ``d * node + axis``) that move
        together: a rigid smooth footing is the vertical dofs of its nodes.
    options : SolverOptions, optional
        Clarabel settings.
    plastic_fraction : float
        Threshold of :attr:`LimitResult.plastic`.
    max_multiplier : float, optional
        Cap on ``lambda`` (one more row).  A cohesionless body under its own
        weight carries any multiple of it or none, so its multiplier is
        unbounded or zero; with a cap the program says which.

    Returns
    -------
    LimitResult

    Raises
    ------
    ParameterError
        For inconsistent shapes, an elastic material, or a reference load that
        does no work on any velocity unknown.
    SolverError
        When Clarabel does not solve the program.  ``DualInfeasible`` means an
        unbounded multiplier (no mechanism: e.g. every dof fixed);
        ``PrimalInfeasible`` that the dead load alone exceeds the strength.
    """
    t0 = time.perf_counter()
    options = options or SolverOptions()
    materials = [associated(m) for m in materials]
    if any(not m.plastic for m in materials):
        raise ParameterError(
            "materials", materials, "plastic materials only (a yield cone each)"
        )
    if not hasattr(operator, "G"):
        from ..mesh.smoothing import nodal_integration

        d = operator.p.shape[0]
        comp = tuple(range(6)) if d == 3 else (0, 1, 3)
        if d == 2 and any(m.needs_zz(2) for m in materials):
            comp = (0, 1, 2, 3)
        operator = nodal_integration(operator, comp)
    d, N, n_p = operator.dim, operator.n_nodes, operator.n_points
    load = np.asarray(load, float)
    if load.shape != (N, d) or not np.all(np.isfinite(load)):
        raise ParameterError("load", f"array of shape {load.shape}", f"({N}, {d})")
    f0 = np.zeros((N, d)) if dead_load is None else np.asarray(dead_load, float)
    if f0.shape != (N, d) or not np.all(np.isfinite(f0)):
        raise ParameterError("dead_load", f"array of shape {f0.shape}", f"({N}, {d})")
    fixed = np.zeros((N, d), bool) if fixed is None else np.asarray(fixed, bool)
    if fixed.shape != (N, d):
        raise ParameterError("fixed", f"array of shape {fixed.shape}", f"({N}, {d})")
    full = 4 if d == 2 else 6
    data = ConeInput(
        operator=operator,
        materials=materials,
        material=np.asarray(material),
        sigma_n=np.zeros((n_p, full)),
        force=f0,
        fixed=fixed,
        du_prescribed=np.zeros((N, d)),
        contacts=Contacts(np.zeros(0, int), np.zeros((0, d)), np.zeros(0), np.zeros(0)),
    )
    from .conic import check_step_data

    check_step_data(data)
    prog = Program(data)
    T, n_red = _dof_map(d * N, fixed.reshape(-1), list(tied or []))
    f1 = load.reshape(-1)
    f1_red = T.T @ f1
    if not np.any(f1_red):
        raise ParameterError(
            "load", "no work", "a load acting on at least one free degree of freedom"
        )
    # Variables x = [sigma (n_p * n_s) | lambda].
    ns = prog.ns
    nsig = n_p * ns
    A_eq = sp.hstack(
        [(T.T @ operator.G).tocsc(), sp.csc_matrix(-f1_red[:, None])], format="csc"
    )
    b_eq = T.T @ f0.reshape(-1)
    blocks = [blk for blk in (cutoff(prog), yield_cones(prog)) if blk.rows]
    cone_rows = [
        sp.hstack([blk.A[:, :nsig], sp.csc_matrix((blk.rows, 1))]) for blk in blocks
    ]
    A = sp.vstack([A_eq, *cone_rows], format="csc")
    b = np.concatenate([b_eq] + [blk.b for blk in blocks])
    cones: list = [clarabel.ZeroConeT(n_red)]
    for blk in blocks:
        cones += blk.cones
    if max_multiplier is not None:
        cap = sp.csc_matrix(([1.0], ([0], [nsig])), shape=(1, nsig + 1))
        A = sp.vstack([A, cap], format="csc")
        b = np.concatenate([b, [float(max_multiplier)]])
        cones.append(clarabel.NonnegativeConeT(1))
    # Scaling: stresses by s* (the largest strength, or a load over the
    # section), force rows by F* = s* h^(d-1), lambda by the multiplier at
    # which the reference load over the section reaches s*.
    h = float(np.sum(operator.volumes) / max(N, 1)) ** (1.0 / d)
    s_star = max([float(np.max(c.k, initial=0.0)) for _, c in prog.yield_cones])
    section = float(np.sum(operator.volumes)) ** ((d - 1) / d)
    s_star = max(
        s_star, float(np.abs(f0).sum()) / section, float(np.abs(f1).sum()) / section
    )
    if not s_star > 0:
        s_star = 1.0
    F_star = s_star * h ** (d - 1)
    lam_star = s_star * section / float(np.abs(f1).sum())
    col = np.concatenate([np.full(nsig, s_star), [lam_star]])
    row = np.concatenate(
        [np.full(n_red, 1 / F_star)]
        + [np.full(blk.rows, 1 / s_star) for blk in blocks]
        + [np.full(int(max_multiplier is not None), 1 / lam_star)]
    )
    A_hat = (sp.diags(row) @ A @ sp.diags(col)).tocsc()
    q_hat = np.zeros(nsig + 1)
    q_hat[-1] = -1.0  # minimise -lambda / lambda*
    P_hat = sp.csc_matrix((nsig + 1, nsig + 1))
    res = solve_clarabel(P_hat, q_hat, A_hat, row * b, cones, options, d)
    if res.status not in ACCEPTED:
        if res.status in ("DualInfeasible", "AlmostDualInfeasible"):
            why = "the multiplier is unbounded: no collapse mechanism (check supports)"
        else:
            why = hint(res.status, False)
        raise SolverError(res.status, None, res.iterations, why)
    x = col * res.x
    z = lam_star * row * res.z
    lam = float(x[-1])
    u = -(T @ z[:n_red])
    sig_sel = x[:nsig].reshape(n_p, ns)
    sigma = np.zeros((n_p, full))
    comp = list(prog.comp)
    sigma[:, comp] = sig_sel
    rate = np.zeros((n_p, full))
    rate[:, comp] = operator.strain(u.reshape(N, d))
    diss = operator.volumes * np.einsum("ps,ps->p", sig_sel, rate[:, comp])
    density = diss / operator.volumes
    plastic = density > plastic_fraction * max(float(density.max(initial=0.0)), 0.0)
    return LimitResult(
        multiplier=lam,
        velocity=u.reshape(N, d),
        sigma=sigma,
        strain_rate=rate,
        dissipation=diss,
        plastic=plastic,
        status=res.status,
        iterations=res.iterations,
        wall_time=time.perf_counter() - t0,
        sizes={
            "variables": nsig + 1,
            "rows": int(b.size),
            "nnz_A": int(A.nnz),
            "linear_solver": res.linear_solver,
        },
    )
