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

:func:`limit_analysis` solves one program (built, scaled and solved by
:mod:`.program`); :func:`~.safety.strength_reduction` finds the
factor of safety ``F`` of Mohr-Coulomb materials (``c/F``, ``tan(phi)/F``) such
that the gravity multiplier is 1, with a safeguarded secant iteration on
``log lambda(log F)`` (one cone program per iterate).
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError
from ..materials import Material
from ..mesh.smoothing import nodal_integration
from ..step.program import Program
from ..step.solver import SolverOptions
from .program import (
    LimitProgram,
    assemble,
    dof_map,
    scaling,
    solve,
    static_program,
)

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


def _strain_operator(operator: Any, materials: list[Material]) -> Any:
    """The nodal-integration operator of ``operator`` (a mesh is turned into one).

    Parameters
    ----------
    operator : NodalIntegration or skfem.Mesh
        An operator (returned as it is) or a mesh.
    materials : list of Material
        Materials of the body: a 2-D material that needs ``sigma_zz`` adds it
        to the stress components.

    Returns
    -------
    NodalIntegration
    """
    if hasattr(operator, "G"):
        return operator
    d = operator.p.shape[0]
    comp = tuple(range(6)) if d == 3 else (0, 1, 3)
    if d == 2 and any(m.needs_zz(2) for m in materials):
        comp = (0, 1, 2, 3)
    return nodal_integration(operator, comp)


def _checked_map(velocity_map: Any, tied: Any, n_dofs: int) -> tuple[Any, int]:
    """``velocity_map`` as a CSC matrix and its number of unknowns, checked.

    Raises
    ------
    ParameterError
        If it is not ``(n_dofs, n)`` with ``n >= 1`` and finite entries, or
        if ``tied`` is given beside it.
    """
    if tied is not None:
        raise ParameterError(
            "tied", "given with velocity_map", "None (put the ties in the map)"
        )
    T = sp.csc_matrix(velocity_map, dtype=float)
    if T.shape[0] != n_dofs or T.shape[1] < 1 or not np.all(np.isfinite(T.data)):
        raise ParameterError(
            "velocity_map",
            f"matrix of shape {T.shape}",
            f"a finite ({n_dofs}, n) matrix, n >= 1 (d N rows, node-major)",
        )
    return T, int(T.shape[1])


def _checked_loads(
    load: np.ndarray,
    dead_load: np.ndarray | None,
    fixed: np.ndarray | None,
    N: int,
    d: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reference load, dead load and supports as ``(N, d)`` arrays, checked.

    Parameters
    ----------
    load, dead_load, fixed : array_like or None
        As in :func:`limit_analysis` (``None``: no dead load, no supports).
    N, d : int
        Nodes and dimension of the operator.

    Returns
    -------
    load, f0 : ndarray (N, d) float
    fixed : ndarray (N, d) bool

    Raises
    ------
    ParameterError
        For a wrong shape or a non-finite load.
    """
    load = np.asarray(load, float)
    if load.shape != (N, d) or not np.all(np.isfinite(load)):
        raise ParameterError("load", f"array of shape {load.shape}", f"({N}, {d})")
    f0 = np.zeros((N, d)) if dead_load is None else np.asarray(dead_load, float)
    if f0.shape != (N, d) or not np.all(np.isfinite(f0)):
        raise ParameterError("dead_load", f"array of shape {f0.shape}", f"({N}, {d})")
    fixed = np.zeros((N, d), bool) if fixed is None else np.asarray(fixed, bool)
    if fixed.shape != (N, d):
        raise ParameterError("fixed", f"array of shape {fixed.shape}", f"({N}, {d})")
    return load, f0, fixed


def _collapse_state(
    operator: Any,
    prog: Program,
    lp: LimitProgram,
    x: np.ndarray,
    z: np.ndarray,
    plastic_fraction: float,
) -> dict[str, Any]:
    """Multiplier, mechanism, stresses, strain rates and plastic zone of a solution.

    Parameters
    ----------
    operator : NodalIntegration
        Strain operator.
    prog : Program
        The step's program (its stress components).
    lp : LimitProgram
        The assembled program (dof map, sizes).
    x, z : ndarray
        Unscaled primal and dual solution (:func:`~.program.solve`).
    plastic_fraction : float
        Threshold of the plastic zone on the dissipation density.

    Returns
    -------
    dict
        The :class:`LimitResult` fields ``multiplier``, ``velocity``,
        ``sigma``, ``strain_rate``, ``dissipation`` and ``plastic``.
    """
    d, N, n_p = operator.dim, operator.n_nodes, operator.n_points
    full = 4 if d == 2 else 6
    u = -(lp.T @ z[: lp.n_red])
    sig_sel = x[: lp.nsig].reshape(n_p, prog.ns)
    sigma = np.zeros((n_p, full))
    comp = list(prog.comp)
    sigma[:, comp] = sig_sel
    rate = np.zeros((n_p, full))
    rate[:, comp] = operator.strain(u.reshape(N, d))
    diss = operator.volumes * np.einsum("ps,ps->p", sig_sel, rate[:, comp])
    density = diss / operator.volumes
    plastic = density > plastic_fraction * max(float(density.max(initial=0.0)), 0.0)
    return {
        "multiplier": float(x[-1]),
        "velocity": u.reshape(N, d),
        "sigma": sigma,
        "strain_rate": rate,
        "dissipation": diss,
        "plastic": plastic,
    }


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
    strength: np.ndarray | None = None,
    velocity_map: Any = None,
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
    strength : ndarray (n_p,), optional
        Factor on each point's cohesive strength (a soil profile,
        :attr:`~skfem_npfem.Particles.strength`); default 1.
    velocity_map : sparse matrix (d N, n), optional
        The nodal velocities (node-major) as a linear map of ``n`` unknowns,
        for kinematics that ``fixed`` and ``tied`` cannot say: a node on a
        smooth rigid body's face moves with the body normal to the face and
        freely along it (``u = V e + a t``).  It replaces the map ``fixed``
        and ``tied`` make (``tied`` must then be None; ``fixed`` still marks
        the supports of the program's data).  The reference load must do work
        through it (``velocity_map^T load`` not zero).

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
    operator = _strain_operator(operator, materials)
    d, N = operator.dim, operator.n_nodes
    load, f0, fixed = _checked_loads(load, dead_load, fixed, N, d)
    prog = static_program(operator, materials, material, f0, fixed, strength)
    if velocity_map is None:
        T, n_red = dof_map(d * N, fixed.reshape(-1), list(tied or []))
    else:
        T, n_red = _checked_map(velocity_map, tied, d * N)
    f1 = load.reshape(-1)
    f1_red = T.T @ f1
    if not np.any(f1_red):
        raise ParameterError(
            "load", "no work", "a load acting on at least one free degree of freedom"
        )
    lp = assemble(operator, prog, T, n_red, f1_red, f0, max_multiplier)
    col, row, lam_star = scaling(operator, prog, lp, f0, f1)
    res, x, z = solve(lp, col, row, lam_star, options, d)
    return LimitResult(
        **_collapse_state(operator, prog, lp, x, z, plastic_fraction),
        status=res.status,
        iterations=res.iterations,
        wall_time=time.perf_counter() - t0,
        sizes={
            "variables": lp.nsig + 1,
            "rows": int(lp.b.size),
            "nnz_A": int(lp.A.nnz),
            "linear_solver": res.linear_solver,
        },
    )
