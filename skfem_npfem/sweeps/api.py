"""``skfem_npfem.sweep``: many runs of one scene on Dask, gathered in one table."""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ..errors import ParameterError
from ..scenes import get_scene
from .cluster import (
    CONNECT_TIMEOUT,
    check_options,
    dask_session,
    require_dask,
    solver_threads,
)
from .engine import RETRIES, Outcome, Progress, gather_tasks
from .plan import Run, check_spec, plan_runs, write_json
from .table import TABLE_CSV, build_rows, write_table
from .task import SUMMARY, run_one, same_parameters

__all__ = ["sweep"]


def sweep(
    scene: str,
    grid: Mapping[str, Sequence[Any]] | None = None,
    *,
    out: str | Path,
    fixed: Mapping[str, Any] | None = None,
    cases: Sequence[Mapping[str, Any]] | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    threads: int | None = None,
    retries: int = RETRIES,
    connect_timeout: float = CONNECT_TIMEOUT,
    progress: Callable[[str], None] | bool = True,
) -> Any:
    """Run a scene over a parameter grid on Dask and return the table of results.

    Every run writes its own folder ``out/runs/NAME`` (VTU series, checkpoints,
    ``summary.json``), with ``NAME`` made of the varied values (for example
    ``E=1e+07_nu=0.3``).  Runs whose folder already holds a summary with the
    same parameters are not run again; a run whose folder holds a checkpoint
    continues from it.  A run that fails is recorded (``status``/``error``
    columns, ``error.txt`` in its folder) and does not stop the others.

    Parameters
    ----------
    scene : str
        Scene name (see ``skfem-npfem scenes``).
    grid : dict, optional
        Parameter name -> list of values; the runs are the Cartesian product
        (the first name varies slowest).  Values are numbers, booleans or
        strings as on the command line.
    out : path
        Sweep folder: ``runs/``, ``sweep.json``, ``table.csv`` (and
        ``table.parquet`` when pyarrow is installed).
    fixed : dict, optional
        Parameter values shared by every run (``--set``).
    cases : list of dict, optional
        Explicit runs instead of a ``grid`` (each a dict of overrides).
    workers : int, optional
        Worker processes of the local cluster (default: one per available core).
    scheduler : str, Client or Cluster, optional
        Run on an existing Dask scheduler (``tcp://HOST:PORT``), an open
        ``distributed.Client`` or a cluster object such as dask-jobqueue's
        ``SLURMCluster``; default: a local cluster started for this sweep.
    threads : int, optional
        Solver threads per run (the scene's ``threads``); default: the cores
        of a machine divided by its Dask worker threads (at least 1).  A
        ``threads`` in ``fixed`` or ``grid`` wins.
    retries : int
        Dask retries of a run that raised an unexpected exception or lost its
        worker (library errors are final and not retried).
    connect_timeout : float
        Seconds to wait for ``scheduler`` to answer.
    progress : bool or callable
        One line per finished run with the count and an ETA (stderr; a
        callable receives the lines instead; False: silent).

    Returns
    -------
    pandas.DataFrame
        One row per run in grid order; columns documented in
        :mod:`skfem_npfem.sweeps.table` and docs/sweep.md.

    Raises
    ------
    ParameterError
        Unknown scene or parameter, an empty, malformed or repeated grid entry,
        a value a parameter does not allow, an ``out`` holding a different
        sweep, or an unreachable scheduler.
    NpfemError
        Dask or pandas is not installed (the message says how to install them).

    Examples
    --------
    >>> table = sweep(  # doctest: +SKIP
    ...     "elastic-column",
    ...     {"spacing": [0.5, 0.25], "nu": [0.2, 0.3]},
    ...     fixed={"mode": "static"},
    ...     out="out/sweep",
    ... )
    >>> table[["spacing", "nu", "sigma_v_rel_l2"]]  # doctest: +SKIP
    """
    the_scene = get_scene(scene)
    runs = plan_runs(the_scene, grid, fixed, cases)
    require_dask()
    check_options(workers, scheduler, connect_timeout)
    if threads is not None and (
        isinstance(threads, bool) or not isinstance(threads, int) or threads < 1
    ):
        raise ParameterError("threads", threads, "an integer >= 1 (or None: automatic)")
    if not isinstance(retries, int) or retries < 0:
        raise ParameterError("retries", retries, "an integer >= 0")
    root = Path(out)
    _check_out(root)
    varied = list(runs[0].varied) if grid is not None else _union(runs)
    check_spec(
        root,
        {
            "scene": scene,
            "fixed": {k: v for k, v in runs[0].overrides.items() if k not in varied},
            "grid": {
                k: list(dict.fromkeys(_key(r.varied[k]) for r in runs if k in r.varied))
                for k in varied
            },
        },
    )
    emit = Progress(0, progress).emit
    records = {r.name: _finished(root, r) for r in runs}
    todo = [r for r in runs if records[r.name] is None]
    emit(
        f"sweep {scene}: {_plural(len(runs), 'run')}, "
        f"{len(runs) - len(todo)} finished before, "
        f"{len(todo)} to run; folder {root}"
    )
    if todo:
        records.update(
            _run_all(
                scene,
                root,
                todo,
                workers,
                scheduler,
                threads,
                retries,
                connect_timeout,
                progress,
            )
        )
    rows = build_rows([r.name for r in runs], varied, records)
    table = write_table(rows, root)
    failed = sum(rec["status"] != "ok" for rec in records.values())
    emit(
        f"table: {root / TABLE_CSV} ({_plural(len(runs), 'run')}, {failed} failed"
        + (", see the error column)" if failed else ")")
    )
    return table


def _check_out(root: Path) -> None:
    try:
        (root / "runs").mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ParameterError(
            "--out", str(root), f"a writable folder ({err.strerror or err})"
        ) from None


def _union(runs: Sequence[Run]) -> list[str]:
    names: dict[str, None] = {}
    for r in runs:
        names.update(dict.fromkeys(r.varied))
    return list(names)


def _key(value: Any) -> Any:
    return value if isinstance(value, int | float | str | bool) else str(value)


def _finished(root: Path, run: Run) -> dict[str, Any] | None:
    """The record of a run finished by an earlier invocation, else None."""
    path = root / "runs" / run.name / SUMMARY
    if not path.is_file():
        return None
    try:
        summary = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not same_parameters(summary.get("parameters", {}), run.values):
        return None
    return {"status": "ok", "summary": summary, "resumed": False, "error": ""}


def _run_all(
    scene: str,
    root: Path,
    todo: Sequence[Run],
    workers: int | None,
    scheduler: Any,
    threads: int | None,
    retries: int,
    connect_timeout: float,
    progress: Callable[[str], None] | bool,
) -> dict[str, dict[str, Any]]:
    """Run ``todo`` on Dask; one record per run."""
    emit = Progress(0, progress).emit
    by_name = {r.name: r for r in todo}
    records: dict[str, dict[str, Any]] = {}
    with dask_session(workers, scheduler, connect_timeout) as session:
        n = threads if threads is not None else solver_threads(session.client)
        emit(
            f"running on {session.where}, {_plural(n, 'solver thread')} per run"
            + (f"; dashboard {session.dashboard}" if session.dashboard else "")
        )
        tasks = {}
        for r in todo:
            over = dict(r.overrides)
            if "threads" in r.values:  # every scene has it; a custom one may not
                over.setdefault("threads", n)
            values = {**r.values, **over}
            folder = (root / "runs" / r.name).absolute()  # workers have other cwds
            tasks[r.name] = (scene, over, str(folder), values)

        def done(outcome: Outcome) -> str:
            rec = _record(root, by_name[outcome.name], outcome)
            records[outcome.name] = rec
            return _detail(rec)

        gather_tasks(
            session.client,
            run_one,
            tasks,
            retries=retries,
            key_prefix=f"sweep-{scene}",
            on_done=done,
            progress=progress,
        )
    return records


def _record(root: Path, run: Run, outcome: Outcome) -> dict[str, Any]:
    """The table record of a finished task; keeps summary.json on this machine.

    Workers on other machines without a shared file system write their summary
    there; the copy here lets a rerun skip the run all the same.
    """
    if not outcome.ok:
        return {
            "status": "failed",
            "error": outcome.error,
            "values": run.values,
            "resumed": False,
        }
    summary = outcome.value["summary"]
    path = root / "runs" / run.name / SUMMARY
    if not path.is_file():
        write_json(path, summary)
    return {
        "status": "ok",
        "error": "",
        "summary": summary,
        "resumed": bool(outcome.value.get("resumed")),
        "note": outcome.value.get("note", ""),
        "warnings": list(outcome.value.get("warnings", [])),
    }


def _detail(rec: dict[str, Any]) -> str:
    if rec["status"] != "ok":
        return ""
    solver = rec["summary"].get("solver", {})
    steps, its = solver.get("steps", "?"), solver.get("ipm_iterations_total", "?")
    parts = [
        _plural(steps, "step"),
        _plural(its, "IPM iteration"),
    ]
    if rec.get("resumed"):
        parts.append("resumed from its checkpoint")
    if rec.get("note"):
        parts.append(rec["note"])
    parts += [f"warning: {msg}" for msg in rec.get("warnings", [])]
    return ", ".join(parts)


def _plural(n: Any, word: str) -> str:
    return f"{n} {word}{'s' * (n != 1)}"
