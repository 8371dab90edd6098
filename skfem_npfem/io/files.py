"""Writing files safely: one atomic writer, one JSON encoder, one folder check.

Atomic writes
-------------
:func:`atomic_path` yields a hidden temporary path beside the target
(``.tmp_<name>``); when the block that fills it finishes, the temporary file is
flushed to disk (``fsync``) and renamed over the target with :func:`os.replace`,
and in every case the temporary is removed.  A crash or a kill therefore never
leaves a half-written file under a final name.  :func:`write_bytes` and
:func:`write_json` are the byte and JSON forms.

JSON
----
:func:`to_jsonable` is the package's one JSON policy: numpy scalars become
Python numbers, arrays and tuples become lists, keys become strings, and
**NaN and +-inf become null** (JSON has no such numbers; a reader gets ``None``
where a value is undefined, e.g. a metric that needs more steps).  Any other
object raises ``TypeError``.  Summaries, ``scene.json``, the ``.vtu.series``
index and checkpoint metadata are all written through it.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError

__all__ = [
    "atomic_path",
    "check_writable_dir",
    "dumps",
    "to_jsonable",
    "write_bytes",
    "write_json",
]


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path to fill; then sync it and rename it to ``path``.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> with atomic_path(folder / "a.txt") as tmp:
    ...     _ = tmp.write_text("done")
    >>> sorted(p.name for p in folder.iterdir()), (folder / "a.txt").read_text()
    (['a.txt'], 'done')
    """
    path = Path(path)
    tmp = path.with_name(f".tmp_{path.name}")
    try:
        yield tmp
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; return the path."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def to_jsonable(obj: Any) -> Any:
    """Plain JSON values of ``obj`` (the package's JSON policy, see the module).

    Examples
    --------
    >>> to_jsonable({"a": np.float64(1.5), 2: (np.nan, np.arange(2))})
    {'a': 1.5, '2': [None, [0, 1]]}
    """
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if obj is None or isinstance(obj, str | int | float):
        return obj
    raise TypeError(f"{type(obj).__name__} is not JSON serializable")


def dumps(obj: Any, indent: int | None = None) -> str:
    """``obj`` as JSON text under the package's policy (:func:`to_jsonable`)."""
    return json.dumps(to_jsonable(obj), indent=indent, allow_nan=False)


def write_json(path: str | os.PathLike, obj: Any, indent: int | None = 1) -> Path:
    """Write ``obj`` as JSON atomically (folders are created); return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_bytes(path, dumps(obj, indent=indent).encode())


def check_writable_dir(
    name: str, folder: str | os.PathLike, target: str | os.PathLike | None = None
) -> Path:
    """Create ``folder`` if needed and check that files can be written in it.

    ``target`` is a file to be written there later (it must not be a folder).
    Checked before a run starts, so a long run never ends in an unwritable
    path.

    Raises
    ------
    ParameterError
        Naming ``name`` and the path, if the folder cannot be used.
    """
    folder = Path(folder)
    shown = target if target is not None else folder
    kind = "file path" if target is not None else "directory"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / ".skfem-npfem-write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as err:
        raise ParameterError(
            name, str(shown), f"a writable {kind} ({err.strerror or err})"
        ) from None
    if target is not None and Path(target).is_dir():
        raise ParameterError(name, str(target), "a file path, not a directory")
    return folder
