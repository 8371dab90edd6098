"""The ``analysis=limit`` mode of a scene: one cone program, no time stepping.

A scene with the parameter ``analysis`` (:func:`analysis_param`) builds its
particles, walls and model as usual; with ``analysis=limit`` its
:class:`~skfem_npfem.scenes.base.SceneRun` runs no step and its metrics come
from :func:`~skfem_npfem.limit.analysis.limit_analysis` (or
:func:`~skfem_npfem.limit.safety.strength_reduction`) on the initial mesh.  The
solve happens once, when the metrics are first asked for
(:func:`limit_scene_run`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ..errors import ParameterError, warn_user
from ..laws import prandtl_depth
from ..limit.analysis import LimitResult
from .base import SceneRun
from .params import Param

__all__ = [
    "ALMOST_SOLVED",
    "ANALYSES",
    "LIMIT_METRICS",
    "analysis_param",
    "check_limit_method",
    "limit_metrics",
    "limit_scene_run",
]

#: Values of the ``analysis`` parameter.
ANALYSES = ("incremental", "limit")

#: Metrics every limit-mode summary has.
LIMIT_METRICS = {
    "collapse_multiplier": "analysis=limit: collapse multiplier of the reference "
    "load, one cone program on the initial mesh (with refine=strain, the default, "
    "on the last lattice of refine_history)",
    "limit_status": "analysis=limit: Clarabel status of the (last) limit program",
    "cone_programs": "analysis=limit: cone programs solved",
    "plastic_fraction": "analysis=limit: volume fraction of the plastic zone of the "
    "collapse mechanism",
    "limit_wall_time": "analysis=limit: seconds spent building and solving the "
    "limit programs",
    "limit_iterations": "analysis=limit: interior-point iterations of all the "
    "limit programs",
    "limit_note": "analysis=limit: what an AlmostSolved program means for the "
    "result (null when every program was Solved)",
}

#: What ``AlmostSolved`` means for a multiplier or a factor of safety.
ALMOST_SOLVED = (
    "{n} of the {programs} limit program(s) ended AlmostSolved: Clarabel met its "
    "reduced tolerances (relative duality gap 5e-5, feasibility 1e-4) but not tol, "
    "so {what} is certain only to about 1e-4 relative (usually far better: it is "
    "where the solver stalled, next to the optimum); rerun with another tol (e.g. "
    "1e-9) to confirm its digits"
)


def analysis_param(incremental: str) -> Param:
    """The ``analysis`` parameter; ``incremental`` says what the default runs."""
    return Param(
        "analysis",
        "incremental",
        "-",
        f"incremental: {incremental}; limit: the collapse multiplier as one cone "
        "program on the initial mesh (no elasticity, no steps), solved again on "
        "lattices refined where its mechanism dissipates (refine=strain, the "
        "default with limit)",
        str,
        ANALYSES,
    )


#: Block depth / depth of Prandtl's mechanism that a footing's limit analysis
#: needs: the fixed base of a shallower block cuts the mechanism off and the
#: collapse load comes out too high with status Solved (N_c at the default 10 b
#: block: -1.6 % at 50 degrees, mechanism 8.1 b deep; +8.3 % at 55, 11.6 b;
#: +68 % at 60, 18.6 b).
MECHANISM_MARGIN = 1.2


def check_limit_method(values: Mapping[str, Any]) -> None:
    """Refuse what ``analysis=limit`` cannot do, before anything is built.

    A baseline method (limit analysis is one N-PFEM cone program), and a
    footing's soil block (``domain_width`` half-widths ``b`` deep) shallower than
    :data:`MECHANISM_MARGIN` times the depth of Prandtl's mechanism at the
    friction angle (:func:`~skfem_npfem.laws.prandtl_depth`).
    """
    if values.get("analysis") != "limit":
        return
    method = values.get("method", "npfem")
    if method != "npfem":
        raise ParameterError(
            "method", method, "npfem with analysis=limit (one N-PFEM cone program)"
        )
    domain, phi = values.get("domain_width"), values.get("phi")
    if domain is None or phi is None or values.get("material") == "tresca":
        return
    need = MECHANISM_MARGIN * prandtl_depth(phi)
    if domain < need:
        raise ParameterError(
            "domain_width",
            domain,
            f"at least {need:.3g} half-widths with phi = {phi:g}: the collapse "
            f"mechanism reaches {prandtl_depth(phi):.3g} b deep, and a block whose "
            "fixed base cuts it off gives a collapse load too high with no failed "
            "status (N_c +8.3 % at 55 degrees, +68 % at 60 in a 10 b block); "
            f"set domain_width={math.ceil(need)} where the scene allows it (the mesh "
            f"grows with it), or phi <= {_steepest(domain):.1f} for this block",
        )


def _steepest(domain: float) -> float:
    """The largest phi (degrees) whose mechanism a block ``domain`` b deep holds."""
    lo, hi = 0.0, 89.9
    if MECHANISM_MARGIN * prandtl_depth(lo) > domain:
        return 0.0
    for _ in range(60):  # bisection: prandtl_depth grows with phi
        mid = 0.5 * (lo + hi)
        lo, hi = (
            (mid, hi) if MECHANISM_MARGIN * prandtl_depth(mid) <= domain else (lo, mid)
        )
    return lo


def limit_metrics(
    res: LimitResult,
    volumes: np.ndarray,
    programs: int,
    wall_time: float | None = None,
    iterations: int | None = None,
    statuses: list[str] | None = None,
    what: str = "the collapse multiplier",
) -> dict:
    """The :data:`LIMIT_METRICS` of a limit result.

    ``wall_time``, ``iterations`` and ``statuses`` are of all the programs
    (default: those of ``res``, the one program); ``what`` names the result
    in the note on ``AlmostSolved`` programs, which is also warned.
    """
    volumes = np.asarray(volumes, float)
    statuses = [res.status] if statuses is None else list(statuses)
    almost = sum(s != "Solved" for s in statuses)
    note = None
    if almost:
        note = ALMOST_SOLVED.format(n=almost, programs=len(statuses), what=what)
        warn_user(note)
    return {
        "collapse_multiplier": float(res.multiplier),
        "limit_status": res.status,
        "cone_programs": int(programs),
        "plastic_fraction": float(volumes[res.plastic].sum() / volumes.sum()),
        "limit_wall_time": float(res.wall_time if wall_time is None else wall_time),
        "limit_iterations": int(res.iterations if iterations is None else iterations),
        "limit_note": note,
    }


def limit_scene_run(sim: Any, compute: Callable[[], dict]) -> SceneRun:
    """A run of no steps whose metrics are ``compute()`` (solved once, cached)."""
    cache: dict = {}

    def metrics(_sim: Any) -> dict:
        if "m" not in cache:
            cache["m"] = compute()
        return cache["m"]

    return SceneRun(sim, {"steps": 0}, metrics)
