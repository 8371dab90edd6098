"""Scene framework: named problems with documented parameters.

A scene is one source of truth for a ready problem: the library API, the CLI,
the demos and the tests all build it through :func:`run_scene`.  Each scene
declares its parameters (name, default, unit, allowed values) and turns a
parameter dict into a :class:`~skfem_npfem.Simulation` plus a metrics
function for the JSON summary.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..errors import CheckpointError, ParameterError, RunInterrupted
from ..io import (
    RunFolder,
    check_not_held,
    check_writable_dir,
    checkpoint_step,
    load_checkpoint,
    to_jsonable,
    write_json,
)
from .limits import check_steps
from .params import Param, Values

__all__ = [
    "DEFAULT_CHECKPOINT_EVERY",
    "RESUME_MAY_CHANGE",
    "WATER_METRICS_DOC",
    "Scene",
    "SceneRun",
    "water_metrics",
]

#: Steps between checkpoints of scenes that do not choose (``checkpoint_every``).
DEFAULT_CHECKPOINT_EVERY = 20


#: The metrics every run with pore water adds to its scene's own (a scene
#: with a ``drainage`` parameter lists them in its :attr:`Scene.metrics_doc`).
WATER_METRICS_DOC = {
    "pore_pressure_max": "largest pore pressure (static plus excess, "
    "compression positive) of the last step, Pa (runs with water only)",
    "excess_pore_pressure_max": "largest excess pore pressure (above the "
    "water table's static field) of the last step, Pa (not drained runs)",
    "excess_pore_pressure_min": "smallest excess pore pressure of the last "
    "step, Pa: negative where the soil dilates (not drained runs)",
}


def water_metrics(sim: Any) -> dict[str, float]:
    """:data:`WATER_METRICS_DOC` of a run's last step; empty for a dry run.

    The last step is the last one written (a run always writes it); the
    excess pore pressure not of a drained run (which has none).
    Before the first step the particles carry no pore pressure: no metrics.
    """
    p, water = sim.particles, getattr(sim.model, "water", None)
    if water is None or p.pore_pressure is None:
        return {}
    out = {"pore_pressure_max": float(np.max(p.pore_pressure, initial=0.0))}
    if water.drainage != "drained" and p.excess_pore_pressure is not None and p.n:
        out["excess_pore_pressure_max"] = float(np.max(p.excess_pore_pressure))
        out["excess_pore_pressure_min"] = float(np.min(p.excess_pore_pressure))
    return out


@dataclass
class SceneRun:
    """What a scene's ``build`` returns.

    Attributes
    ----------
    simulation : Simulation
        Ready to run.
    run_kwargs : dict
        Arguments of :meth:`Simulation.run` (``steps``, ``t_end`` or ``stop``).
    metrics : callable
        ``metrics(sim) -> dict`` of documented scene metrics.
    derived : dict
        Values of derived parameters known only once the run is built (e.g.
        the slope's ``reduction``, from its factor of safety); the summary's
        ``parameters`` records them in place of their null.
    """

    simulation: Any
    run_kwargs: dict
    metrics: Callable[[Any], dict]
    history: list = field(default_factory=list)
    derived: dict = field(default_factory=dict)


@dataclass
class Scene:
    """A named problem with documented parameters and metrics.

    Attributes
    ----------
    name : str
        Scene name used on the command line.
    description : str
        One paragraph.
    params : list of Param
        Parameters with defaults and units.
    build : callable
        ``build(values: Values, out: Path | None, progress: bool | None) ->
        SceneRun``: the run of resolved values (:meth:`resolve`).
    metrics_doc : dict
        Summary metric name -> description (with unit).
    scenery : callable or None
        ``scenery(parameters: dict, folder: Path | None) -> Scenery``: what a
        picture of a result shows besides the particles (floor, walls, outline,
        reference values, step labels); see :mod:`skfem_npfem.scenes.scenery`.
    derive : callable or None
        ``derive(values: dict) -> None``: the scene's one resolving function,
        which fills the defaults derived from other parameters (e.g. a spacing
        from a height) in place, before the run is built.
    time_params : tuple of str or None
        ``(step, end)``: the scene's parameters that set how many steps a
        run of ``t_end`` takes (the time step, and the one that sets the
        run's end, ``t_end`` or, where the end is where a body has got to, its
        ``penetration``); the step-count error names them.  None for a scene
        whose runs count their ``steps`` instead.
    ignored : callable or None
        ``ignored(values: dict, given: frozenset) -> None``: refuses (raises
        :class:`~skfem_npfem.errors.ParameterError`) or warns about given
        parameters that the chosen material, analysis or option does not use
        (e.g. ``phi`` with ``material=tresca``), before anything is derived.
    """

    name: str
    description: str
    params: list[Param]
    build: Callable[..., SceneRun]
    metrics_doc: dict[str, str]
    scenery: Callable[..., Any] | None = None
    derive: Callable[[dict[str, Any]], Any] | None = None
    time_params: tuple[str, str] | None = ("dt", "t_end")
    ignored: Callable[[dict[str, Any], frozenset[str]], None] | None = None

    def __post_init__(self) -> None:
        if any(p.name == "drainage" for p in self.params):
            self.metrics_doc = self.metrics_doc | {
                k: v for k, v in WATER_METRICS_DOC.items() if k not in self.metrics_doc
            }

    def resolve(self, overrides: Mapping[str, Any] | None = None) -> Values:
        """The values of a run: defaults, validated overrides, derived defaults.

        The derived defaults are filled by :attr:`derive`; the values are
        read-only from here on.
        """
        values = self.checked(overrides)
        if self.derive is not None:
            self.derive(values)
        return Values(values)

    def checked(self, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """Defaults updated with validated overrides (no derived defaults yet)."""
        if overrides is not None and not isinstance(overrides, Mapping):
            raise ParameterError(
                "overrides",
                overrides,
                "a dict of parameter name -> value, e.g. {'E': 2e7}",
            )
        by_name = {p.name: p for p in self.params}
        values = {p.name: p.default for p in self.params}
        for key, val in (overrides or {}).items():
            if key not in by_name:
                raise ParameterError(
                    "parameter",
                    key,
                    f"scene '{self.name}' has parameters: " + ", ".join(by_name),
                )
            values[key] = by_name[key].check(val)
        if self.ignored is not None:
            self.ignored(values, frozenset(overrides or {}))
        return values

    def run(
        self,
        overrides: Mapping[str, Any] | None = None,
        *,
        out: str | Path | None = None,
        summary: str | Path | None = None,
        progress: bool | None = None,
        resume: bool = False,
    ) -> dict[str, Any]:
        """Build and run the scene; return (and optionally write) the summary.

        Every check (parameters, paths, the scene's own checks while it is
        built, the resume point, the step count) runs before a file in ``out``
        is touched, so a refused run leaves an earlier run's results intact.
        Then the run holds ``out`` (:func:`~skfem_npfem.io.folder_lock`; a
        second run into the same folder at the same time is refused).  A
        fresh run (``resume=False``) is staged
        (:class:`~skfem_npfem.io.RunFolder`): the files of an earlier run there
        (steps, index, checkpoints, ``mechanism.npz``, the summary,
        ``scene.json``, ``plots/``) are replaced by its own once it has a
        finished step (or has ended, for a run without steps), and stay as
        they were if it fails before.  On SIGINT/SIGTERM the run stops after
        its current step, writes a checkpoint and the partial summary
        (``"interrupted": true``) and raises
        :class:`~skfem_npfem.errors.RunInterrupted`.
        """
        values = self.resolve(overrides)
        start = time.perf_counter()
        for name, path in (("out", out), ("--summary", summary)):
            if path is not None and not str(path).strip():
                raise ParameterError(name, str(path), "a path (not empty)")
        if out is not None:
            check_writable_dir("out", out, create=False)
        if summary is not None:
            check_writable_dir("--summary", Path(summary).parent, summary, create=False)
        checkpoint = self._resume_point(out, values) if resume else None
        folder = None if out is None else RunFolder(out, fresh=checkpoint is None)
        out = None if folder is None else folder.path  # a fresh run is staged
        srun = self.build(values, out=out, progress=progress, resume=resume)
        sim = srun.simulation
        run_kwargs = dict(srun.run_kwargs)
        _attach_checkpoints(sim, out, values)
        if checkpoint is not None:
            sim.restore(checkpoint)
            _check_not_past_end(sim, run_kwargs, checkpoint)
            if run_kwargs.get("steps") is not None:  # steps counts from step 0
                run_kwargs["steps"] = run_kwargs["steps"] - sim.step
        _check_step_count(sim, run_kwargs, values, self.time_params)
        with folder.hold() if folder is not None else nullcontext():
            if folder is not None:
                folder.watch(sim)
                # lets `skfem-npfem plot DIR` find the scene and its scales
                write_json(
                    Path(out) / "scene.json",
                    {"scene": self.name, "parameters": dict(values)}
                    | folder.names(summary),
                )
                opener = getattr(sim.writer, "open", None)
                if callable(opener):
                    opener()
            try:
                sim.run(**run_kwargs)
            except RunInterrupted as err:
                err.summary = self._result(srun, values, start, err)
                if summary is not None:
                    write_json(_target(folder, summary), err.summary)
                    err.summary_path = Path(summary)
                raise
            result = self._result(srun, values, start)
            if summary is not None:
                write_json(_target(folder, summary), result)
        return result

    def _result(
        self,
        srun: SceneRun,
        values: Values,
        start: float,
        interrupt: RunInterrupted | None = None,
    ) -> dict[str, Any]:
        """The summary of a finished (or interrupted) run."""
        sim = srun.simulation
        result = {
            "scene": self.name,
            "parameters": _used(values, srun),
            "metrics": srun.metrics(sim) | water_metrics(sim),
            "solver": sim.summary(),
            "wall_time_total": time.perf_counter() - start,
            "history": [r.as_dict() for r in sim.records],
            "version": __version__,
            "interrupted": interrupt is not None,
        }
        if interrupt is not None:
            result["interrupted_by"] = interrupt.signal_name
            result["checkpoint"] = (
                None if interrupt.checkpoint is None else str(interrupt.checkpoint)
            )
        return result

    def _resume_point(self, out: str | Path | None, values: Values) -> Path:
        """The latest checkpoint of ``out``, checked against this scene and values."""
        if out is None:
            raise ParameterError("resume", True, "needs out (a folder)")
        # A run in progress stages its checkpoints: its lock is the news.
        check_not_held(out)
        path, step = checkpoint_step(out)
        _, meta = load_checkpoint(path)
        if meta.get("scene", self.name) != self.name:
            raise CheckpointError(
                f"{path}: written by scene {meta['scene']!r}, not {self.name!r}"
            )
        saved = meta.get("parameters")
        if saved is not None:
            saved = to_jsonable(saved)
            now = to_jsonable(dict(values))
            # A parameter the checkpointed version did not have yet, left at
            # its default now, is the behaviour that version had: not a change.
            defaults = to_jsonable({p.name: p.default for p in self.params})
            # A dry run records no water parameters (its derived drainage "dry").
            defaults["drainage"] = "dry"
            added = {k for k in set(now) - set(saved) if now[k] == defaults.get(k)}
            changed = sorted(
                k
                for k in (set(saved) | set(now)) - added
                if k not in RESUME_MAY_CHANGE and saved.get(k) != now.get(k)
            )
            if changed:
                raise CheckpointError(
                    f"{path}: parameters differ from the checkpointed run "
                    f"({', '.join(changed)}); resume with the same --set values"
                )
        if meta.get("step") != step:
            raise CheckpointError(f"{path}: holds step {meta.get('step')}, not {step}")
        return path


def _target(folder: RunFolder | None, summary: str | Path) -> Path:
    """Where the summary is written now (staged if it goes into the folder)."""
    return Path(summary) if folder is None else folder.file(summary)


def _check_not_past_end(sim: Any, run_kwargs: dict, checkpoint: Path) -> None:
    """Refuse to resume from a checkpoint beyond the requested end."""
    t_end, steps = run_kwargs.get("t_end"), run_kwargs.get("steps")
    where = f"{checkpoint.name} is at step {sim.step}, t = {sim.time:.6g} s"
    fresh = "a shorter run needs a fresh run (without --resume)"
    if t_end is not None and sim.time > t_end * (1 + 1e-12):
        raise ParameterError(
            "t_end", t_end, f"at least {sim.time:.6g} s to resume: {where}; {fresh}"
        )
    if steps is not None and sim.step > steps:
        raise ParameterError(
            "steps", steps, f"at least {sim.step} to resume: {where}; {fresh}"
        )


def _check_step_count(
    sim: Any, run_kwargs: dict, values: Values, time_params: tuple[str, str] | None
) -> None:
    """Refuse a run that plans more than :data:`~.limits.MAX_STEPS` steps.

    ``time_params`` are the scene's ``(step, end)`` parameters
    (:attr:`Scene.time_params`), which the error tells the user to change.
    """
    t_end, steps = run_kwargs.get("t_end"), run_kwargs.get("steps")
    by_time = math.inf
    if t_end is not None:
        by_time = max(t_end - sim.time, 0.0) / sim.dt_max
    if by_time <= (math.inf if steps is None else steps):
        if t_end is not None:
            step, end = time_params or ("dt", "t_end")
            name = step if step in values else end
            run_time = "t_end" if end == "t_end" else f"the run's time (set by {end})"
            check_steps(
                by_time,
                values,
                name,
                f"{run_time}/{step} = {t_end:g}/{sim.dt_max:g} s",
                f"raise {step} or lower {end}",
            )
    else:
        name = next(
            (k for k in ("steps", "max_steps") if values.get(k) == steps), "steps"
        )
        check_steps(steps, values, name, "", "use fewer steps")


#: Parameters that may differ when a run is resumed (they do not change the
#: steps already taken).
RESUME_MAY_CHANGE = frozenset(
    {
        "t_end",
        "steps",
        "output_every",
        "checkpoint_every",
        "threads",
        "reproducible",
        "size_check",
    }
)


def _attach_checkpoints(sim: Any, out: str | Path | None, values: Values) -> None:
    """Checkpoint into ``out`` unless the scene already chose a folder."""
    if out is None or sim.checkpoint_dir is not None:
        return
    sim.checkpoint_dir = Path(out)
    if not sim.checkpoint_every:
        sim.checkpoint_every = int(
            values.get("checkpoint_every") or DEFAULT_CHECKPOINT_EVERY
        )


#: Parameters a scene may leave to the model it builds: the values of the run.
_FROM_MODEL = ("stabilisation", "stabilisation_mode", "volume_correction")


def _used(values: Values, srun: SceneRun) -> dict[str, Any]:
    """The run's parameters with every derived default at the value it used.

    ``values`` as resolved, then what the build derived (:attr:`SceneRun.derived`)
    and the fidelity options the model was built with, for those left at None.
    """
    model = srun.simulation.model
    built = {k: getattr(model, k) for k in _FROM_MODEL if k in values}
    used = dict(values)
    for key, value in (srun.derived | built).items():
        if used.get(key) is None:
            used[key] = value
    return used
