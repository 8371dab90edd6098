"""The cone program of a limit analysis: dof map, rows, scaling and solve.

:func:`~.analysis.limit_analysis` maximises the multiplier ``lambda`` of a
reference load over stress fields in equilibrium with it (plus a dead load)
inside the yield cones.  This module builds that program on the step's
operator and cones (:func:`static_program`, :func:`dof_map`,
:func:`assemble`), scales it (:func:`scaling`) and solves it with Clarabel
(:func:`solve`); reading the collapse state back is :mod:`.analysis`'s.
docs/theory.md ("Limit analysis") derives it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import clarabel
import numpy as np
import scipy.sparse as sp

from ..boundary import Contacts
from ..errors import SolverError
from ..materials import Material
from ..step.conic import check_step_data
from ..step.families import cutoff, yield_cones
from ..step.program import ConeInput, Program
from ..step.solver import ACCEPTED, SolverOptions, solve_clarabel

__all__ = [
    "LimitProgram",
    "assemble",
    "dof_map",
    "limit_hint",
    "scaling",
    "solve",
    "static_program",
]


def dof_map(
    n_dofs: int, fixed: np.ndarray, tied: list[np.ndarray]
) -> tuple[sp.csc_matrix, int]:
    """``T`` (n_dofs x n_red): free dofs to velocity unknowns, tied dofs merged.

    Parameters
    ----------
    n_dofs : int
        Nodal degrees of freedom, ``d N`` (node-major).
    fixed : ndarray (n_dofs,) bool
        Dofs with zero velocity: no column.
    tied : list of int arrays
        Groups of dofs that share one unknown (fixed members left out).

    Returns
    -------
    T : csc_matrix (n_dofs, n_red)
        One 1 per free dof, in the column of its group's first free dof.
    n_red : int
        Velocity unknowns.
    """
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


@dataclass
class LimitProgram:
    """The assembled (unscaled) program of :func:`~.analysis.limit_analysis`.

    Attributes
    ----------
    T : csc_matrix (d N, n_red)
        Velocity unknowns to nodal dofs (:func:`dof_map`).
    n_red : int
        Velocity unknowns: equilibrium rows of the zero cone.
    nsig : int
        Stress variables; the multiplier is variable ``nsig``.
    A : csc_matrix
        Constraint matrix over ``[sigma | lambda]``.
    b : ndarray
        Constraint right-hand side.
    cones : list
        Clarabel cones of the rows of ``A``, in order.
    blocks : list
        Cone blocks (tension cut-offs, yield cones) that have rows.
    capped : bool
        The last row caps the multiplier.
    """

    T: sp.csc_matrix
    n_red: int
    nsig: int
    A: sp.csc_matrix
    b: np.ndarray
    cones: list
    blocks: list
    capped: bool


def static_program(
    operator: Any,
    materials: list[Material],
    material: np.ndarray,
    f0: np.ndarray,
    fixed: np.ndarray,
    strength: np.ndarray | None = None,
) -> Program:
    """The step's program on zero stresses: its yield cones and stress components.

    Parameters
    ----------
    operator : NodalIntegration
        Strain operator.
    materials : list of Material
        Associated plastic materials.
    material : ndarray (n_p,) int
        Material index per stress point.
    f0 : ndarray (N, d)
        Dead load, N.
    fixed : ndarray (N, d) bool
        Supports.
    strength : ndarray (n_p,), optional
        Factor on each point's cohesive strength (default 1).

    Returns
    -------
    Program
        Checked as a step's data is (:func:`~skfem_npfem.step.conic.check_step_data`).
    """
    d, N, n_p = operator.dim, operator.n_nodes, operator.n_points
    full = 4 if d == 2 else 6
    data = ConeInput(
        operator=operator,
        materials=materials,
        material=np.asarray(material),
        sigma_n=np.zeros((n_p, full)),
        force=f0,
        fixed=fixed,
        du_prescribed=np.zeros((N, d)),
        contacts=Contacts.empty(d),
        strength=None if strength is None else np.asarray(strength, float),
    )
    check_step_data(data)
    return Program(data)


def assemble(
    operator: Any,
    prog: Program,
    T: sp.csc_matrix,
    n_red: int,
    f1_red: np.ndarray,
    f0: np.ndarray,
    max_multiplier: float | None,
) -> LimitProgram:
    """Equilibrium rows, tension cut-offs, yield cones and the cap of the program.

    Variables are ``x = [sigma (n_p * n_s) | lambda]``; the rows are
    ``T^T (G sigma - lambda f1) = T^T f0`` (zero cone), then the cone blocks,
    then ``lambda <= max_multiplier`` if given.

    Parameters
    ----------
    operator : NodalIntegration
        Strain operator (its ``G``).
    prog : Program
        The step's program (:func:`static_program`).
    T : csc_matrix
        Dof map (:func:`dof_map`) with ``n_red`` columns.
    n_red : int
        Velocity unknowns.
    f1_red : ndarray (n_red,)
        Reference load on the velocity unknowns, ``T^T f1``.
    f0 : ndarray (N, d)
        Dead load.
    max_multiplier : float or None
        Cap on ``lambda``.

    Returns
    -------
    LimitProgram
    """
    nsig = operator.n_points * prog.ns
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
    capped = max_multiplier is not None
    return LimitProgram(T, n_red, nsig, A, b, cones, blocks, capped)


def scaling(
    operator: Any,
    prog: Program,
    lp: LimitProgram,
    f0: np.ndarray,
    f1: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Column and row scales of the program, and the multiplier's scale.

    Stresses are scaled by ``s*`` (the largest strength, or a load over the
    section), force rows by ``F* = s* h^(d-1)``, ``lambda`` by the multiplier
    ``lambda*`` at which the reference load over the section reaches ``s*``.

    Parameters
    ----------
    operator : NodalIntegration
        Strain operator (its volumes give ``h`` and the section).
    prog : Program
        The step's program (its yield cones' strengths).
    lp : LimitProgram
        The assembled program (its row counts).
    f0 : ndarray (N, d)
        Dead load.
    f1 : ndarray (d N,)
        Reference load.

    Returns
    -------
    col : ndarray (nsig + 1,)
        Variable scales: ``x = col * x_hat``.
    row : ndarray
        Row scales: ``A_hat = diag(row) A diag(col)``.
    lam_star : float
        Scale of the multiplier.
    """
    d, N = operator.dim, operator.n_nodes
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
    col = np.concatenate([np.full(lp.nsig, s_star), [lam_star]])
    row = np.concatenate(
        [np.full(lp.n_red, 1 / F_star)]
        + [np.full(blk.rows, 1 / s_star) for blk in lp.blocks]
        + [np.full(int(lp.capped), 1 / lam_star)]
    )
    return col, row, lam_star


def solve(
    lp: LimitProgram,
    col: np.ndarray,
    row: np.ndarray,
    lam_star: float,
    options: SolverOptions,
    d: int,
) -> tuple[Any, np.ndarray, np.ndarray]:
    """Solve the scaled program (minimise ``-lambda / lambda*``) with Clarabel.

    Parameters
    ----------
    lp : LimitProgram
        The assembled program.
    col, row : ndarray
        Its column and row scales (:func:`scaling`).
    lam_star : float
        Scale of the multiplier (the duals come back per unit power).
    options : SolverOptions
        Clarabel settings.
    d : int
        Dimension (for the solver's defaults).

    Returns
    -------
    res
        Clarabel's result (status, iterations, linear solver).
    x : ndarray (nsig + 1,)
        Stresses and multiplier, unscaled.
    z : ndarray
        Row duals, unscaled to unit power of the reference load.

    Raises
    ------
    SolverError
        When the status is not accepted (``DualInfeasible``: an unbounded
        multiplier).
    """
    A_hat = (sp.diags(row) @ lp.A @ sp.diags(col)).tocsc()
    q_hat = np.zeros(lp.nsig + 1)
    q_hat[-1] = -1.0  # minimise -lambda / lambda*
    P_hat = sp.csc_matrix((lp.nsig + 1, lp.nsig + 1))
    res = solve_clarabel(P_hat, q_hat, A_hat, row * lp.b, lp.cones, options, d)
    if res.status not in ACCEPTED:
        raise SolverError(res.status, None, res.iterations, limit_hint(res.status))
    return res, col * res.x, lam_star * row * res.z


def limit_hint(status: str) -> str:
    """What a user can try when a limit program fails with ``status``.

    A limit program has no time or load steps (the step's hints name them):
    it is one cone program on the initial mesh, so the advice is about its
    supports, its strengths and the solver.

    Examples
    --------
    >>> limit_hint("DualInfeasible")[:30]
    'the multiplier is unbounded: n'
    """
    if status in ("DualInfeasible", "AlmostDualInfeasible"):
        return "the multiplier is unbounded: no collapse mechanism (check supports)"
    if status in ("PrimalInfeasible", "AlmostPrimalInfeasible"):
        return (
            "no stress field carries the dead load alone (multiplier 0): the body "
            "collapses under its fixed loads; check strengths (c, phi) and supports"
        )
    if status in ("MaxIterations", "MaxTime"):
        return (
            "raise max_iter/time_limit, or use a coarser spacing (fewer cones); "
            "limit analysis has no steps to shorten"
        )
    return (
        "limit analysis has no steps to shorten: check the materials for "
        "extreme ratios (c against rho g times the size, steep friction "
        "cones), try a coarser or finer spacing, or linear_solver='qdldl'"
    )
