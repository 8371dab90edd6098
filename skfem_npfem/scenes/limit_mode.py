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

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..limit.analysis import LimitResult, check_friction_angle
from .base import SceneRun
from .params import Param

__all__ = [
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
    "load, one cone program on the initial mesh",
    "limit_status": "analysis=limit: Clarabel status of the (last) limit program",
    "cone_programs": "analysis=limit: cone programs solved",
    "plastic_fraction": "analysis=limit: volume fraction of the plastic zone of the "
    "collapse mechanism",
    "limit_wall_time": "analysis=limit: seconds spent building and solving the "
    "limit programs",
}


def analysis_param(incremental: str) -> Param:
    """The ``analysis`` parameter; ``incremental`` says what the default runs."""
    return Param(
        "analysis",
        "incremental",
        "-",
        f"incremental: {incremental}; limit: the collapse multiplier as one cone "
        "program on the initial mesh (no elasticity, no steps)",
        str,
        ANALYSES,
    )


def check_limit_method(values: Mapping[str, Any]) -> None:
    """Refuse what ``analysis=limit`` cannot do, before anything is built.

    A baseline method (limit analysis is one N-PFEM cone program), and a
    friction angle above :data:`~skfem_npfem.limit.analysis.MAX_FRICTION_ANGLE`
    (:func:`~skfem_npfem.limit.analysis.check_friction_angle`) when the
    material uses it.
    """
    method = values.get("method", "npfem")
    if values.get("analysis") != "limit":
        return
    if method != "npfem":
        raise ParameterError(
            "method", method, "npfem with analysis=limit (one N-PFEM cone program)"
        )
    if values.get("material", "tresca") != "tresca" and values.get("phi") is not None:
        check_friction_angle(values["phi"])


def limit_metrics(
    res: LimitResult,
    volumes: np.ndarray,
    programs: int,
    wall_time: float | None = None,
) -> dict:
    """The :data:`LIMIT_METRICS` of a limit result (``wall_time``: of all programs)."""
    volumes = np.asarray(volumes, float)
    return {
        "collapse_multiplier": float(res.multiplier),
        "limit_status": res.status,
        "cone_programs": int(programs),
        "plastic_fraction": float(volumes[res.plastic].sum() / volumes.sum()),
        "limit_wall_time": float(res.wall_time if wall_time is None else wall_time),
    }


def limit_scene_run(sim: Any, compute: Callable[[], dict]) -> SceneRun:
    """A run of no steps whose metrics are ``compute()`` (solved once, cached)."""
    cache: dict = {}

    def metrics(_sim: Any) -> dict:
        if "m" not in cache:
            cache["m"] = compute()
        return cache["m"]

    return SceneRun(sim, {"steps": 0}, metrics)
