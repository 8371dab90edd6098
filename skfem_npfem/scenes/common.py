"""Helpers shared by the scenes: solver parameters and the result writer."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..conic import LINEAR_SOLVERS, SolverOptions
from .base import Param

__all__ = ["make_writer", "solver_from", "solver_params"]


def solver_params() -> list[Param]:
    """Parameters every scene exposes for the cone solver."""
    return [
        Param(
            "linear_solver", "auto", "-", "Clarabel direct solver", str, LINEAR_SOLVERS
        ),
        Param("threads", 0, "-", "solver threads (0: automatic)", int, lo=0),
        Param(
            "tol",
            1e-8,
            "-",
            "interior-point tolerances",
            float,
            lo=0,
            hi=1e-2,
            lo_open=True,
            hi_open=True,
        ),
    ]


def solver_from(values: dict[str, Any]) -> SolverOptions:
    """SolverOptions from resolved scene values."""
    return SolverOptions(
        linear_solver=values["linear_solver"],
        max_threads=values["threads"],
        tol=values["tol"],
    )


def make_writer(
    out: str | Path | None, resume: bool = False, resume_after_step: int | None = None
):
    """A :class:`~skfem_npfem.io.ResultWriter` for ``out`` (None: no output)."""
    if out is None:
        return None
    from ..io import ResultWriter

    return ResultWriter(out, resume_after_step=resume_after_step)
