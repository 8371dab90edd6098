"""What a Dask worker runs: one scene run in its own folder, resumable.

Kept free of Dask imports so that it pickles by reference and runs anywhere
skfem-npfem is installed.
"""

from __future__ import annotations

import json
import socket
import sys
import time
import traceback
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import CheckpointError, NpfemError
from ..io import write_bytes
from ..scenes import run_scene

__all__ = ["SUMMARY", "ByValue", "call", "has_checkpoint", "run_one", "same_parameters"]

#: File name of a run's JSON summary inside its folder.
SUMMARY = "summary.json"
#: File name of a failed run's error report inside its folder.
ERROR = "error.txt"


class ByValue:
    """A function pickled with its module's code, for workers that lack it.

    Parameters
    ----------
    fn : callable
        The function; its module must be in ``sys.modules``.
    """

    def __init__(self, fn: Callable[..., Any]) -> None:
        import cloudpickle

        module = sys.modules[fn.__module__]
        cloudpickle.register_pickle_by_value(module)
        try:
            self.payload = cloudpickle.dumps(fn)
        finally:
            cloudpickle.unregister_pickle_by_value(module)
        self.name = getattr(fn, "__qualname__", repr(fn))

    def __call__(self, *args: Any) -> Any:
        """Unpickle the function and call it with ``args``."""
        import cloudpickle

        return cloudpickle.loads(self.payload)(*args)

    def __repr__(self) -> str:
        return f"ByValue({self.name})"


def call(fn: Any, args: tuple) -> dict[str, Any]:
    """Run ``fn(*args)``; library errors become a failure record, not an exception.

    Errors of the library (:class:`~skfem_npfem.errors.NpfemError`: bad
    parameters, a solver failure) are final and returned as
    ``{"ok": False, "error": ...}``.  Any other exception propagates, so that
    Dask retries the task (``retries``) before the sweep records it.
    """
    start = time.perf_counter()
    try:
        value = fn(*args)
    except NpfemError as err:
        return {
            "ok": False,
            "error": f"{type(err).__name__}: {err}",
            "wall_time": time.perf_counter() - start,
            "host": socket.gethostname(),
        }
    return {
        "ok": True,
        "value": value,
        "wall_time": time.perf_counter() - start,
        "host": socket.gethostname(),
    }


def has_checkpoint(folder: Path) -> bool:
    """True if ``folder`` holds a checkpoint a run can continue from."""
    return folder.is_dir() and any(folder.glob("checkpoint_*.npz"))


def same_parameters(saved: dict[str, Any], values: dict[str, Any]) -> bool:
    """Whether a stored summary ran with ``values`` (solver threads may differ).

    A value left at None (a derived default) matches the value the stored run
    derived for it: the summary records derived defaults at the values used,
    which follow from the other parameters.
    """
    now = json.loads(json.dumps(values, default=str))
    keys = (set(saved) | set(now)) - {"threads"}
    return all(now.get(k) is None or saved.get(k) == now.get(k) for k in keys)


def run_one(
    scene: str, overrides: dict[str, Any], folder: str, values: dict[str, Any]
) -> dict[str, Any]:
    """Run one sweep case in ``folder`` (on a worker); return its summary.

    A summary already in the folder with the same parameters is returned as is
    (an earlier attempt finished).  A folder with a checkpoint is resumed from
    it (the worker of an earlier attempt was lost); an unusable checkpoint is
    discarded and the run starts afresh.  On a library error the traceback is
    written to ``error.txt`` in the folder and the error re-raised.

    Warnings of the run are not printed on the worker (its stderr mixes all
    runs); they are returned, and the sweep prints them with the run's line.

    Returns
    -------
    dict
        ``summary`` (as :func:`~skfem_npfem.run_scene` returns it), ``resumed``
        (continued from a checkpoint), ``note`` and ``warnings`` (messages).
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = _run_one(scene, overrides, folder, values)
    result["warnings"] = list(dict.fromkeys(str(w.message) for w in caught))
    return result


def _run_one(
    scene: str, overrides: dict[str, Any], folder: str, values: dict[str, Any]
) -> dict[str, Any]:
    out = Path(folder)
    summary_path = out / SUMMARY
    if summary_path.is_file():
        try:
            old = json.loads(summary_path.read_text())
        except (OSError, ValueError):
            old = None
        if old is not None and same_parameters(old.get("parameters", {}), values):
            return {"summary": old, "resumed": False, "note": "finished before"}
    resume, note = has_checkpoint(out), ""
    try:
        try:
            summary = run_scene(
                scene, overrides, out=out, summary=summary_path, resume=resume
            )
        except CheckpointError as err:
            if not resume:
                raise
            note = f"checkpoint not usable ({err}); started afresh"
            for old_file in out.glob("checkpoint_*.npz"):
                old_file.unlink()
            resume = False
            summary = run_scene(scene, overrides, out=out, summary=summary_path)
    except NpfemError:
        out.mkdir(parents=True, exist_ok=True)
        write_bytes(out / ERROR, traceback.format_exc().encode())
        raise
    (out / ERROR).unlink(missing_ok=True)
    return {"summary": summary, "resumed": resume, "note": note}
