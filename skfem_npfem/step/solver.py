"""Clarabel: solver settings and the solve of one scaled cone program.

:class:`SolverOptions` holds the settings (linear-solver backend, threads,
tolerances, presets); :func:`solve_clarabel` runs Clarabel once, and once more
with iterative refinement when a solve without it ends in
``InsufficientProgress`` or ``NumericalError``; :func:`hint` says what a user
can try for a failed status.
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass

import clarabel
import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError
from .backends import (
    choose_linear_solver,
    faer_threads,
    mkl_available,
    pardiso_thread_count,
    pardiso_threads,
)

__all__ = [
    "ACCEPTED",
    "ACCURACY_PRESETS",
    "LINEAR_SOLVERS",
    "ClarabelResult",
    "SolverOptions",
    "hint",
    "solve_clarabel",
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
        dimension and size (:func:`skfem_npfem.step.backends.choose_linear_solver`):
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
    strength_floor : float
        Raise every yield strength ``k`` below this fraction of the largest
        strength of the same cone (per step) to that fraction (0: off).  The
        frozen-friction cone of a cohesionless particle whose lagged stress is
        (nearly) zero has ``k`` at the solver's noise level, i.e. a cone with
        (almost) no interior, and a few hundred such particles (a free
        surface, grains in flight) make the interior-point method stall
        (``AlmostSolved`` after 30-50 iterations).  ``1e-6`` removes the
        stalls and ~20 % of the iterations of a 3D collapse and changes the
        solution by about as much as the solver tolerance does
        (docs/performance.md).
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
    strength_floor: float = 0.0

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
        f = self.strength_floor
        if isinstance(f, bool) or not (
            isinstance(f, numbers.Real) and math.isfinite(f) and 0 <= f < 1e-2
        ):
            raise ParameterError("strength_floor", f, "a fraction in [0, 1e-2)")

    def resolved_linear_solver(
        self, n_variables: int, dim: int, coupled: bool = False
    ) -> str:
        """The backend actually used (``auto`` resolved by problem size).

        ``coupled``: the objective couples the stresses or the excess pore
        pressures of neighbouring particles (the stabilisation; the pore
        pressure's projection and Darcy terms), see :func:`choose_linear_solver`.

        Raises
        ------
        ParameterError
            If ``mkl`` is requested but MKL Pardiso cannot be loaded.
        """
        if self.linear_solver == "auto":
            return choose_linear_solver(n_variables, dim, coupled)
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
class ClarabelResult:
    """What one (possibly repeated) Clarabel solve returned.

    Attributes
    ----------
    x, z : ndarray
        Primal and dual solutions of the scaled program.
    status : str
        Clarabel's status of the last solve.
    iterations : int
        Interior-point iterations of all solves.
    linear_solver : str
        Backend used.
    setup, solve : float
        Seconds in Clarabel's constructor (of the first solve, with the
        backend set-up) and in the solve(s).
    """

    x: np.ndarray
    z: np.ndarray
    status: str
    iterations: int
    linear_solver: str
    setup: float
    solve: float


#: Statuses of a solve that stalled on the KKT solves' accuracy (not on the
#: program): :func:`solve_clarabel` repeats it with refinement, then qdldl.
STALLED = ("InsufficientProgress", "NumericalError")


def solve_clarabel(
    P: sp.csc_matrix,
    q: np.ndarray,
    A: sp.csc_matrix,
    b: np.ndarray,
    cones: list,
    options: SolverOptions,
    dim: int,
    coupled: bool = False,
) -> ClarabelResult:
    """Solve ``min 1/2 x^T P x + q^T x`` s.t. ``A x + s = b``, ``s`` in ``cones``.

    ``P`` is the upper triangle.  Without iterative refinement the KKT solves
    can be too inaccurate near the optimum (seen in 3D at tol 1e-6): a solve
    ending in ``InsufficientProgress`` or ``NumericalError`` is then repeated
    once with refinement.  ``coupled`` (stresses or pore pressures coupled in
    ``P``) steers the automatic backend
    (:func:`~skfem_npfem.step.backends.choose_linear_solver`).  When that
    automatic choice was MKL Pardiso or faer and the solve still ends in one
    of these statuses, it is repeated once more with qdldl: a coupled cone in
    a large graded domain stalled at a step that qdldl solved in 30
    iterations.  A step that
    solves the first time is not touched, so every such run is unchanged.
    """
    t0 = time.perf_counter()
    backend = options.resolved_linear_solver(A.shape[1], dim, coupled)
    with pardiso_threads(options.max_threads if backend == "mkl" else 0):
        settings = options.clarabel_settings(backend)
        solver = clarabel.DefaultSolver(P, q, A, b, cones, settings)
        t1 = time.perf_counter()
        sol = solver.solve()
        status = str(sol.status)
        iters = int(sol.iterations)
        if status in STALLED and not settings.iterative_refinement_enable:
            settings.iterative_refinement_enable = True
            sol = clarabel.DefaultSolver(P, q, A, b, cones, settings).solve()
            status = str(sol.status)
            iters += int(sol.iterations)
        if status in STALLED and backend != "qdldl" and options.linear_solver == "auto":
            backend = "qdldl"
            settings = options.clarabel_settings(backend)
            settings.iterative_refinement_enable = True
            sol = clarabel.DefaultSolver(P, q, A, b, cones, settings).solve()
            status = str(sol.status)
            iters += int(sol.iterations)
    t2 = time.perf_counter()
    return ClarabelResult(
        x=np.asarray(sol.x),
        z=np.asarray(sol.z),
        status=status,
        iterations=iters,
        linear_solver=backend,
        setup=t1 - t0,
        solve=t2 - t1,
    )


def hint(status: str, dynamic: bool) -> str:
    """What the user can try for a failed status."""
    if status in ("PrimalInfeasible", "AlmostPrimalInfeasible"):
        if not dynamic:
            return (
                "the static problem has no admissible stress field: the load exceeds "
                "the collapse load; use displacement control or mode='dynamic'"
            )
        return "no admissible stress field; check strengths (c, phi) and cut-offs"
    # Static steps have no time step to reduce: their dt is a load increment
    # (the footing's settlement), so the advice names smaller load steps.
    smaller = "reduce dt" if dynamic else "use smaller load steps (more steps)"
    if status in ("MaxIterations", "MaxTime"):
        return f"raise max_iter/time_limit, {smaller}, or use accuracy='fast'"
    retried = " (the step is retried automatically when adaptive stepping is on)"
    return (
        f"{smaller}{retried if dynamic else ''}, check material parameters for "
        "extreme ratios, or try linear_solver='qdldl'"
    )
