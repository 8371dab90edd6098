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
    "LOCK_NAME",
    "atomic_path",
    "check_not_held",
    "check_writable_dir",
    "dumps",
    "folder_lock",
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


#: Name of the lock file a run holds in its output folder.
LOCK_NAME = ".skfem-npfem.lock"


@contextmanager
def folder_lock(folder: str | os.PathLike, name: str = "out") -> Iterator[Path]:
    """Hold the output folder for one run; refuse if another run holds it.

    Creates ``folder`` if needed and takes an exclusive ``flock`` on
    ``folder/.skfem-npfem.lock`` (the lock file holds the process id).  The
    operating system releases the lock when the process ends in any way, so a
    run killed with SIGKILL never leaves the folder locked; the empty lock
    file itself stays.  Where ``fcntl`` is not available (Windows) or the file
    system cannot lock, the folder is used without a lock.

    Raises
    ------
    ParameterError
        Naming ``name``, the folder and the process that holds it.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> with folder_lock(folder):
    ...     with folder_lock(folder):  # a second run into the same folder
    ...         pass
    Traceback (most recent call last):
    ...
    skfem_npfem.errors.ParameterError: invalid out=...
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        fcntl = None
    folder = Path(folder)
    path = folder / LOCK_NAME
    folder.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        if fcntl is not None:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                raise _held(fd, folder, name) from None
            except OSError:  # pragma: no cover - a file system without locks
                pass
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield path
    finally:
        os.close(fd)


def _held(fd: int, folder: Path, name: str) -> ParameterError:
    """The error for ``folder``, whose lock (open as ``fd``) another run holds."""
    holder = os.pread(fd, 64, 0).decode(errors="replace").strip()
    who = f"process {holder}" if holder.isdigit() else "another process"
    return ParameterError(
        name,
        str(folder),
        f"a folder no other run is writing to ({who} is running "
        f"into it and holds {LOCK_NAME}); wait for it to finish or "
        "choose another folder",
    )


def check_not_held(folder: str | os.PathLike, name: str = "out") -> None:
    """Refuse a folder another run holds, without taking it or creating anything.

    What a run in progress has written is staged, not yet in ``folder``, so
    looking there for a checkpoint (``--resume``) would say "no checkpoint"
    when the truth is that another run is writing to it.

    Raises
    ------
    ParameterError
        As :func:`folder_lock` does, if another process holds the lock.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> check_not_held(folder)  # nobody holds it
    >>> with folder_lock(folder):
    ...     check_not_held(folder)
    Traceback (most recent call last):
    ...
    skfem_npfem.errors.ParameterError: invalid out=...
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        return
    path = Path(folder) / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # no lock file: no run has held the folder
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            raise _held(fd, Path(folder), name) from None
        except OSError:  # pragma: no cover - a file system without locks
            return
        fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


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
    name: str,
    folder: str | os.PathLike,
    target: str | os.PathLike | None = None,
    *,
    create: bool = True,
) -> Path:
    """Check that files can be written in ``folder`` (created if ``create``).

    ``target`` is a file to be written there later (it must not be a folder).
    Checked before a run starts, so a long run never ends in an unwritable
    path.  With ``create=False`` a missing folder is not created: its nearest
    existing parent must be a writable folder (so the folder can be created
    later), and nothing is left behind.

    Raises
    ------
    ParameterError
        Naming ``name`` and the path, if the folder cannot be used.
    """
    folder = Path(folder)
    shown = target if target is not None else folder
    kind = "file path" if target is not None else "directory"
    try:
        if create:
            folder.mkdir(parents=True, exist_ok=True)
        probe_dir = folder
        while not create and not probe_dir.exists() and probe_dir != probe_dir.parent:
            probe_dir = probe_dir.parent
        if not probe_dir.is_dir():
            raise NotADirectoryError(20, f"{probe_dir} is not a directory")
        probe = probe_dir / f".skfem-npfem-write-test-{os.getpid()}"
        probe.write_text("")
        probe.unlink()
    except OSError as err:
        raise ParameterError(
            name, str(shown), f"a writable {kind} ({err.strerror or err})"
        ) from None
    if target is not None and Path(target).is_dir():
        raise ParameterError(name, str(target), "a file path, not a directory")
    return folder
