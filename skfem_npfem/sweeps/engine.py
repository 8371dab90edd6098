"""Independent tasks on Dask with progress, ETA and failure records.

:func:`gather_tasks` submits named tasks to an open client and reports each
as it finishes; :func:`run_tasks` also opens (and closes) the cluster.  The
sweep uses both through :func:`~skfem_npfem.sweeps.sweep`; demos with their
own per-case function call :func:`run_tasks` directly.
"""

from __future__ import annotations

import math
import sys
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .cluster import CONNECT_TIMEOUT, dask_session
from .task import ByValue, call

__all__ = ["Outcome", "Progress", "gather_tasks", "run_tasks"]

#: Dask retries of a task that raised something other than a library error or
#: whose worker died (beyond the scheduler's own ``allowed-failures``).
RETRIES = 2


@dataclass
class Outcome:
    """How one task ended.

    Attributes
    ----------
    name : str
        Task (run) name.
    ok : bool
        True if the task returned.
    value : object
        What the task returned (None on failure).
    error : str
        ``"ErrorType: message"`` on failure, else "".
    wall_time : float
        Seconds the last attempt took on its worker (NaN when unknown).
    host : str
        Worker host of the last attempt ("" when unknown).
    """

    name: str
    ok: bool
    value: Any = None
    error: str = ""
    wall_time: float = math.nan
    host: str = ""


class Progress:
    """One line per finished task with the overall count and an ETA.

    Parameters
    ----------
    total : int
        Tasks to run.
    emit : callable or bool
        ``emit(line)``; True prints to stderr, False is silent.
    """

    def __init__(self, total: int, emit: Callable[[str], None] | bool = True) -> None:
        self.total = total
        self.done = 0
        self.failed = 0
        self.start = time.perf_counter()
        if emit is True:
            self.emit: Callable[[str], None] = _stderr
        elif emit is False or emit is None:
            self.emit = _silent
        else:
            self.emit = emit

    def finished(self, outcome: Outcome, detail: str = "") -> None:
        """Report one finished task."""
        self.done += 1
        self.failed += not outcome.ok
        elapsed = time.perf_counter() - self.start
        left = self.total - self.done
        what = f"ok in {_duration(outcome.wall_time)}" if outcome.ok else "FAILED"
        if detail:
            what += f" ({detail})"
        if not outcome.ok:
            what += f": {outcome.error}"
        eta = f", ETA {_duration(elapsed / self.done * left)}" if left else ""
        self.emit(
            f"[{self.done}/{self.total}] {outcome.name}: {what} | "
            f"{left} left, {_duration(elapsed)} elapsed{eta}"
        )


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def _silent(line: str) -> None:
    return None


def _duration(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "?"
    if seconds < 60:
        return f"{seconds:.1f} s"
    m, s = divmod(round(seconds), 60)
    h, m = divmod(m, 60)
    return f"{h}:{m:02d}:{s:02d}"


def gather_tasks(
    client: Any,
    fn: Callable[..., Any],
    tasks: Mapping[str, Sequence[Any]],
    *,
    retries: int = RETRIES,
    key_prefix: str | None = None,
    on_done: Callable[[Outcome], str | None] | None = None,
    progress: Callable[[str], None] | bool = True,
) -> dict[str, Outcome]:
    """Run ``fn(*args)`` for every ``name: args`` of ``tasks`` on ``client``.

    Parameters
    ----------
    client : distributed.Client
        Open client.
    fn : callable
        Importable (or picklable) function run on the workers.
    tasks : dict
        Task name -> argument tuple.
    retries : int
        Dask retries per task (see :data:`RETRIES`).
    key_prefix : str, optional
        Prefix of the Dask keys (shown on the dashboard); default random.
    on_done : callable, optional
        ``on_done(outcome)`` on this process as each task finishes; what it
        returns is added to the progress line.
    progress : callable or bool
        Progress lines (see :class:`Progress`).

    Returns
    -------
    dict
        Task name -> :class:`Outcome`, in the order of ``tasks``.
    """
    from distributed import as_completed

    fn = portable(fn)
    prefix = key_prefix or f"task-{uuid.uuid4().hex[:8]}"
    futures = {
        client.submit(
            call, fn, tuple(args), key=f"{prefix}-{name}", retries=retries, pure=False
        ): name
        for name, args in tasks.items()
    }
    report = Progress(len(futures), progress)
    outcomes: dict[str, Outcome] = {}
    for fut in as_completed(list(futures), loop=client.loop):
        name = futures[fut]
        try:
            rec = fut.result()
        except (KeyboardInterrupt, SystemExit):
            raise
        except BaseException as exc:  # raised after the retries, lost, cancelled
            outcome = Outcome(name, False, error=f"{type(exc).__name__}: {exc}")
        else:
            outcome = Outcome(
                name,
                rec["ok"],
                rec.get("value"),
                rec.get("error", ""),
                rec.get("wall_time", math.nan),
                rec.get("host", ""),
            )
        fut.release()
        detail = on_done(outcome) if on_done is not None else None
        report.finished(outcome, detail or "")
        outcomes[name] = outcome
    return {name: outcomes[name] for name in tasks}


def importable(module_name: str, file: str | None) -> bool:
    """True if ``module_name`` resolves to ``file`` from an entry of ``sys.path``.

    Local workers start with this process's ``sys.path``; a module that was
    loaded some other way (a test module under pytest's importlib mode, a
    file loaded by path) cannot be imported by name on a worker.
    """
    if file is None:
        return True  # built-in or namespace: nothing to ship
    target = Path(file).resolve()
    rel = Path(*module_name.split("."))
    for entry in sys.path:
        base = Path(entry or ".").resolve() / rel
        if target in (base.with_suffix(".py"), base / "__init__.py"):
            return True
    return False


def portable(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn``, or a copy of it carried by value if workers could not import it.

    Dask pickles a function by its module's name; a worker that cannot import
    that module fails to unpickle the task, its connection to the scheduler
    dies and the sweep would wait forever.  Such a function is pickled with
    its module's code (cloudpickle, by value) instead.
    """
    name = getattr(fn, "__module__", None)
    module = sys.modules.get(name or "")
    if module is None or name == "__main__":
        return fn  # cloudpickle already ships __main__ functions by value
    if importable(name, getattr(module, "__file__", None)):
        return fn
    return ByValue(fn)


def run_tasks(
    fn: Callable[..., Any],
    tasks: Mapping[str, Sequence[Any]],
    *,
    workers: int | None = None,
    scheduler: Any = None,
    retries: int = RETRIES,
    connect_timeout: float = CONNECT_TIMEOUT,
    progress: Callable[[str], None] | bool = True,
) -> dict[str, Outcome]:
    """Run named tasks on a local Dask cluster or an existing scheduler.

    The cluster options are those of :func:`~skfem_npfem.sweeps.sweep`; the
    tasks are those of :func:`gather_tasks`.  A task raising a library error
    (:class:`~skfem_npfem.errors.NpfemError`) fails at once; other exceptions
    and lost workers are retried ``retries`` times.

    Examples
    --------
    >>> def square(x):
    ...     return x * x
    >>> out = run_tasks(square, {"a": (2,), "b": (3,)}, workers=1, progress=False)
    >>> [o.value for o in out.values()]
    [4, 9]
    """
    emit = Progress(0, progress).emit
    with dask_session(workers, scheduler, connect_timeout) as session:
        emit(f"{len(tasks)} tasks on {session.where}" + _dash(session.dashboard))
        return gather_tasks(
            session.client, fn, tasks, retries=retries, progress=progress
        )


def _dash(link: str) -> str:
    return f"; dashboard {link}" if link else ""
