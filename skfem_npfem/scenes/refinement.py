"""Adaptive limit analysis: particles added where the collapse mechanism dissipates.

``refine=strain`` with ``analysis=limit`` solves the limit analysis (or the
factor of safety) on the scene's lattice, marks the fewest nodes whose cells
carry ``refine_share`` of the mechanism's plastic power
(:func:`~skfem_npfem.mesh.refine.mark_share`), halves the spacing round them
(:func:`~skfem_npfem.mesh.refine.split_around`), triangulates again and
solves again: at most ``refine_cycles`` times, stopping when the multiplier
has changed by less than ``refine_tol`` (relative) in two successive cycles
(one small change can be a stall: a refinement that moved the result little
before the next one moved it again).  A
limit analysis carries no history, so nothing is mapped between the lattices:
each cycle is a fresh program on more particles.  docs/theory.md ("Adaptive
limit analysis") says why the plastic power is the indicator.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Generic, TypeVar

import numpy as np

from ..errors import ParameterError
from ..mesh.refine import mark_share, split_around
from ..run.control import end_line
from ..run.refining import Refiner
from .params import POSITIVE, Param

__all__ = [
    "INSERT_METRICS",
    "INSERT_PARAMS",
    "REFINE_METRICS",
    "REFINE_PARAMS",
    "SLOPE_REFINE_PARAMS",
    "Adapted",
    "adapt",
    "check_refine",
    "insert_metrics",
    "insert_params",
    "progress_lines",
    "refiner_from",
    "strategies",
]

#: The refinement strategies (``none``: the uniform lattice).
REFINE_CHOICES = ("none", "strain")


def strategies(values: Mapping[str, Any]) -> frozenset[str]:
    """The strategies ``refine`` names (``a+b`` names two; ``none``: none).

    An unset ``refine`` (None) is its default: ``strain`` with
    ``analysis=limit`` (the adaptive limit analysis wins on accuracy for the
    wall time, docs/validation/adaptive_limit.md), ``none`` otherwise.
    """
    refine = values.get("refine", "none")
    if refine is None:
        refine = "strain" if values.get("analysis") == "limit" else "none"
    return frozenset(s for s in str(refine).split("+") if s != "none")


REFINE_PARAMS = [
    Param(
        "refine",
        None,
        "-",
        "analysis=limit: none (the uniform lattice) or strain (adaptive: the "
        "spacing is halved where the collapse mechanism's plastic power "
        "concentrates and the program solved again, until the result changes "
        "by less than refine_tol in two successive cycles; default strain "
        "with analysis=limit, none otherwise)",
        str,
        REFINE_CHOICES,
    ),
    Param(
        "refine_tol",
        0.005,
        "-",
        "refine=strain: stop when the result has changed by less than this "
        "(relative) in two successive cycles",
        float,
        **POSITIVE,
    ),
    Param(
        "refine_cycles",
        6,
        "-",
        "refine=strain: largest number of refinements",
        int,
        lo=1,
        hi=12,
    ),
    Param(
        "refine_share",
        0.6,
        "-",
        "refine=strain: share of the mechanism's plastic power whose cells are "
        "refined each cycle (the fewest nodes that carry it)",
        float,
        lo=0.0,
        hi=1.0,
        lo_open=True,
    ),
]

REFINE_METRICS = {
    "refine_history": "refine=strain: one row [particles, result, seconds] per "
    "cycle (the first on the uniform lattice; seconds of that cycle's programs); "
    "null without refinement",
}


#: ``refine=strain`` and ``...+strain`` in a run (help of ``refine``).
STRAIN_HELP = (
    "; strain: before each step the target spacing is halved at the fewest "
    "particles that carry refine_share of the last step's plastic power "
    "(plastic shear-strain rate times cell volume) and particles are added "
    "on their edges longer than refine_ratio times it, only there: where the "
    "soil flows plastically (needs refine_ratio > 1.414); {s}+strain: both"
)


def insert_params(
    strategy: str, what: str, ratio: float = 1.6, strain: bool = False
) -> list[Param]:
    """``refine`` (``none`` or ``strategy``), ``refine_ratio``, ``refine_merge``.

    ``what`` says what ``refine=strategy`` does besides the insertion;
    ``ratio`` is the default ``refine_ratio`` (0: no insertion by default);
    ``strain`` adds ``strain`` and ``strategy+strain`` (the target halved
    where the plastic strain rate concentrates, :func:`refiner_from`) and
    ``refine_share``.
    """
    more = ["strain", f"{strategy}+strain"] if strain else []
    named = f"{strategy} or strain" if strain else strategy
    params = [
        Param(
            "refine",
            "none",
            "-",
            f"none (the particles stay as made) or {strategy} ({what}with "
            "refine_ratio > 0, before each step a particle is added at the middle "
            "of every edge stretched beyond refine_ratio times its particles' "
            "spacing: where the soil thins; mass and momentum kept)"
            + (STRAIN_HELP.format(s=strategy) if strain else ""),
            str,
            ("none", strategy, *more),
        ),
        Param(
            "refine_ratio",
            ratio,
            "-",
            f"refine={named}: an edge longer than this times the smaller "
            "spacing of its two particles is split (> 1.414, the diagonal of "
            "the lattice; 0: no particle is added)",
            float,
            lo=0.0,
            hi=4.0,
        ),
        Param(
            "refine_merge",
            0.0,
            "-",
            f"refine={named}: two particles closer than this times the larger "
            "spacing of the two are merged into one (mass and momentum kept; "
            "0: never; below refine_ratio / 2)",
            float,
            lo=0.0,
            hi=0.7,
            hi_open=True,
        ),
    ]
    if strain:
        params.append(
            Param(
                "refine_share",
                0.5,
                "-",
                "refine=strain: share of the last step's plastic "
                "power whose particles (the fewest that carry it) get half "
                "their spacing as target",
                float,
                lo=0.0,
                hi=1.0,
                lo_open=True,
            )
        )
    return params


#: Particle insertion in the penetration scenes (round the pushed body).
INSERT_PARAMS = insert_params(
    "bodies", "the lattice is graded round the body's path, as without; ", strain=True
)

#: The slope: an adaptive factor of safety, insertion in its run-out, or both.
SLOPE_REFINE_PARAMS = [
    Param(
        "refine",
        None,
        "-",
        "none (the uniform lattice), strain (the factor of safety adaptive: "
        "the spacing is halved where its mechanism's plastic power "
        "concentrates and the program solved again, until F has changed by "
        "less than refine_tol in two successive cycles; with analysis=limit "
        "and before a run-out), surface "
        "(runout=true: before each step of the run-out a particle is added at "
        "the middle of every edge stretched beyond refine_ratio times its "
        "particles' spacing, where the sliding soil thins; mass and momentum "
        "kept; it also fills the crack behind the slide, so the crest settles "
        "less) or strain+surface (both); default strain with analysis=limit, "
        "none otherwise",
        str,
        ("none", "strain", "surface", "strain+surface"),
    ),
    *REFINE_PARAMS[1:],
    *insert_params("surface", "")[1:],
]

INSERT_METRICS = {
    "inserted": "refine: particles added during the run (0 without refinement)",
    "merged": "refine with refine_merge > 0: pairs of particles merged into one "
    "during the run",
    "n_particles_final": "particles at the end of the run (n_particles plus the "
    "inserted ones, less the merged pairs)",
}


def refiner_from(
    values: Mapping[str, Any], strategy: str | None = None
) -> Refiner | None:
    """The run's :class:`~skfem_npfem.run.refining.Refiner`.

    None with ``refine=none`` (or when ``refine`` does not name
    ``strategy``, the insertion strategy of a scene that has others), or
    when it would neither add (``refine_ratio`` 0) nor merge
    (``refine_merge`` 0) particles.  ``strain`` (a scene whose ``refine``
    offers it, :func:`insert_params`) halves the target where the plastic
    strain rate concentrates (``refine_share``,
    :class:`~skfem_npfem.run.refining.Refiner`'s ``strain_share``) and splits
    only the edges there; ``...+strain`` also every stretched edge.

    Raises
    ------
    ParameterError
        For a ``refine_ratio`` in (0, sqrt(2)], or 0 with ``strain``.
    """
    chosen = strategies(values)
    if not chosen or (strategy is not None and strategy not in chosen):
        return None
    ratio = values["refine_ratio"]
    if 0.0 < ratio <= math.sqrt(2.0):
        raise ParameterError(
            "refine_ratio",
            ratio,
            "0 (no insertion) or a number > 1.414 (the lattice's diagonal over "
            "its spacing: an undeformed lattice would be split everywhere)",
        )
    strain = "strain" in chosen and strategy is None and "refine_share" in values
    if strain and ratio == 0.0:
        raise ParameterError(
            "refine_ratio",
            ratio,
            f"a number > 1.414 with refine={values['refine']} (e.g. 1.6: the "
            "particles are added on the edges longer than refine_ratio times "
            "the halved spacing)",
        )
    if ratio == 0.0 and values["refine_merge"] == 0.0:
        return None  # a graded lattice only: its mesher carries the spacing
    if not strain:
        return Refiner(ratio or None, values["refine_merge"])
    return Refiner(
        ratio,
        values["refine_merge"],
        strain_share=values["refine_share"],
        stretched=bool(chosen - {"strain"}),  # strain alone: round the flow only
    )


def insert_metrics(sim: Any) -> dict[str, int]:
    """``inserted``, ``merged`` and ``n_particles_final`` of a run (its records).

    The records survive a checkpoint, so a resumed run counts the particles
    added before it too.
    """
    added = sum(r.extra.get("inserted", 0.0) for r in sim.records)
    merged = sum(r.extra.get("merged", 0.0) for r in sim.records)
    return {
        "inserted": int(added),
        "merged": int(merged),
        "n_particles_final": int(sim.particles.n),
    }


B = TypeVar("B")


@dataclass
class Adapted(Generic[B]):
    """The last cycle of an adaptive analysis.

    Attributes
    ----------
    body : object
        The last lattice (what ``rebuild`` returned).
    result : object
        What ``solve`` returned for it.
    history : list of [int, float, float]
        Particles, result and seconds of every cycle.
    converged : bool
        The last two changes were below the tolerance.
    """

    body: B
    result: Any
    history: list[list[float]] = field(default_factory=list)
    converged: bool = False


def check_refine(
    values: dict[str, Any],
    limit_stage: bool = False,
    insertion: str | None = None,
    runs: bool = False,
) -> None:
    """Fill ``refine``'s default in place; refuse a strategy the run would not use.

    Parameters
    ----------
    values : dict
        ``refine`` (None: ``strain`` with ``analysis=limit``, else ``none``,
        :func:`strategies`) and ``analysis``.
    limit_stage : bool
        The scene's incremental run has a limit analysis of its own (the
        slope's factor of safety), which ``strain`` refines.
    insertion : str, optional
        The scene's insertion strategy (particles added during a run).
    runs : bool
        The scene steps (so that ``insertion`` has a run to act on).
    """
    chosen = strategies(values)
    if values.get("refine") is None:
        values["refine"] = "+".join(sorted(chosen)) or "none"
    limit = values.get("analysis") == "limit"
    if "strain" in chosen and not (limit or limit_stage):
        raise ParameterError(
            "refine",
            values["refine"],
            "none unless analysis=limit (this scene's incremental run keeps "
            "its lattice; footing-penetration, cone-penetration and "
            "column-collapse add particles where the soil flows with "
            "refine=strain)",
        )
    if insertion is not None and insertion in chosen and not runs:
        raise ParameterError(
            "refine",
            values["refine"],
            f"without {insertion} unless the particles flow (analysis="
            f"incremental with runout=true): {insertion} adds particles "
            "during the run-out",
        )


def adapt(
    values: Mapping[str, Any],
    body: B,
    solve: Callable[[B], tuple[Any, float, np.ndarray]],
    points: Callable[[B], tuple[np.ndarray, np.ndarray]],
    rebuild: Callable[[np.ndarray], B],
    report: Callable[[str], None] | None = None,
) -> Adapted[B]:
    """Solve, refine where the mechanism dissipates, solve again.

    Parameters
    ----------
    values : mapping
        ``refine_tol``, ``refine_cycles`` and ``refine_share``.
    body : object
        The first (uniform) lattice.
    solve : callable
        ``solve(body) -> (result, number, dissipation)``: the analysis, the
        number whose change stops the cycles, the plastic power per node.
    points : callable
        ``points(body) -> (pts, t)``: the lattice's points (n, 2) and
        triangles (3, m).
    rebuild : callable
        ``rebuild(pts) -> body``: a lattice on new points.
    report : callable, optional
        Called with one line per cycle (particles, result, its change, the
        cycle's seconds): a long adaptive run's progress
        (:func:`progress_lines`).

    Returns
    -------
    Adapted
    """
    history: list[list[float]] = []
    t0 = time.perf_counter()
    result, number, power = solve(body)
    history.append([len(points(body)[0]), number, time.perf_counter() - t0])
    if report is not None:
        report(_cycle_line(values, history))
    small = 0  # successive cycles whose change was below the tolerance
    for _ in range(values["refine_cycles"]):
        pts, t = points(body)
        marked = mark_share(power, values["refine_share"])
        t0 = time.perf_counter()
        new_body = rebuild(split_around(pts, t, marked))
        new_result, new_number, new_power = solve(new_body)
        history.append([len(points(new_body)[0]), new_number, time.perf_counter() - t0])
        if report is not None:
            report(_cycle_line(values, history))
        change = abs(new_number - number) / max(abs(new_number), 1e-300)
        body, result, number, power = new_body, new_result, new_number, new_power
        small = small + 1 if change < values["refine_tol"] else 0
        if small == 2:
            return Adapted(body, result, history, True)
    return Adapted(body, result, history, False)


def _cycle_line(values: Mapping[str, Any], history: list[list[float]]) -> str:
    """One progress line of an adaptive limit analysis (the last cycle)."""
    n, number, seconds = history[-1]
    k = len(history) - 1
    head = f"refine=strain cycle {k}/{values['refine_cycles']}: {int(n)} particles"
    if k == 0:
        return f"{head}, result {number:.6g} (the given lattice), {seconds:.1f} s"
    change = number / history[-2][1] - 1.0
    return f"{head}, result {number:.6g} ({100 * change:+.2f} %), {seconds:.1f} s"


def progress_lines(enabled: bool) -> Callable[[str], None] | None:
    """A reporter that prints each line on stderr (None: ``enabled`` false).

    The progress of a limit analysis's refinement cycles, which take no time
    steps (a run's steps have :class:`~skfem_npfem.run.control.Progress`).
    """
    if not enabled:
        return None

    def report(line: str) -> None:
        end_line()
        print(line, file=sys.stderr, flush=True)

    return report
