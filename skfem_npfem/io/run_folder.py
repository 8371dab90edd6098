"""A run's output folder: earlier results stay until the new run has its own.

A fresh run into a folder ``DIR`` that holds an earlier run's results writes
into a hidden staging folder ``DIR/.staging-<pid>/`` first (same file system,
so every move below is a rename).  Once it has something to keep -- a finished
step (a VTU or a checkpoint of step 1 or later), or the end of a run without
steps (a limit analysis: its summary and mechanism) -- it *commits*: the
earlier run's files are removed (:func:`~skfem_npfem.io.checkpoints.clear_run_files`)
and its own are moved into ``DIR``, where it then writes directly.  A run that
fails before (a set-up error, its first solve, an interrupt in step 1) is
*abandoned*: its staging folder is removed and ``DIR`` is left as it was.

The commit is itself made safe against a kill: the staging folder is first
renamed ``.commit-<pid>`` (the new files are complete), renamed
``.moving-<pid>`` once the earlier files are gone, and removed when its files
are moved.  The next run into ``DIR`` (:meth:`RunFolder.open`, under the folder
lock) finishes such a commit and removes a staging folder a killed run left.
So ``DIR`` holds the earlier complete results or the new run's, never a mix.

:class:`RunFolder` does this for the scene runner; a resumed run continues in
``DIR`` (nothing is staged).
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from .checkpoints import clear_run_files, clear_temporaries
from .files import folder_lock

__all__ = ["RunFolder", "finish_commits"]

_STAGING, _COMMIT, _MOVING = ".staging-", ".commit-", ".moving-"
#: A file of a finished step: a result step or a checkpoint (step number).
_STEP_FILE = re.compile(r"(?:result|checkpoint)_(\d+)\.(?:vtu|npz)")


def _move_in(moving: Path, folder: Path) -> None:
    """Move every file of ``moving`` into ``folder``, then remove ``moving``."""
    for f in sorted(moving.iterdir()):
        os.replace(f, folder / f.name)
    moving.rmdir()


def _commit(staged: Path, folder: Path) -> None:
    """Replace the earlier run's files in ``folder`` by those of ``staged``."""
    commit = staged.with_name(_COMMIT + staged.name.removeprefix(_STAGING))
    os.replace(staged, commit)
    _finish(commit, folder)


def _finish(commit: Path, folder: Path) -> None:
    """Finish a commit at any of its stages (see the module docstring)."""
    if commit.name.startswith(_COMMIT):
        clear_run_files(folder)
        moving = commit.with_name(_MOVING + commit.name.removeprefix(_COMMIT))
        os.replace(commit, moving)
        commit = moving
    _move_in(commit, folder)


def finish_commits(folder: str | os.PathLike) -> list[Path]:
    """Finish the commits and remove the staging folders a killed run left.

    Call only while holding the folder
    (:func:`~skfem_npfem.io.files.folder_lock`): a running run's staging
    folder is its own.  Returns the staging folders removed.
    """
    folder = Path(folder)
    removed = []
    for sub in sorted(folder.iterdir()) if folder.is_dir() else ():
        if not sub.is_dir():
            continue
        if sub.name.startswith((_COMMIT, _MOVING)):
            _finish(sub, folder)
        elif sub.name.startswith(_STAGING):
            shutil.rmtree(sub, ignore_errors=True)
            removed.append(sub)
    return removed


class RunFolder:
    """The output folder of one run, staged while the run is fresh.

    Parameters
    ----------
    folder : str or os.PathLike
        The output folder ``DIR``.
    fresh : bool
        True: stage the run (see the module docstring); False (a resumed
        run): write into ``DIR`` directly.

    Attributes
    ----------
    folder : pathlib.Path
        ``DIR``.
    path : pathlib.Path
        Where the run writes (give it to the scene's ``build``): the staging
        folder of a fresh run, else ``DIR``.  It is created by :meth:`hold`.
    committed : bool
        True once the run's files are in ``DIR`` (always, for a resumed run).

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "scene.json").write_text("earlier")
    >>> run = RunFolder(d, fresh=True)
    >>> with run.hold():
    ...     _ = (run.path / "scene.json").write_text("new")
    ...     (d / "scene.json").read_text()  # the earlier run's, until the end
    'earlier'
    >>> (d / "scene.json").read_text(), run.path == d
    ('new', True)
    """

    def __init__(self, folder: str | os.PathLike, *, fresh: bool) -> None:
        self.folder = Path(folder)
        self.path = self.folder / f"{_STAGING}{os.getpid()}" if fresh else self.folder
        self.committed = not fresh
        self._staged = self.path
        self._sim: Any = None

    def file(self, path: str | os.PathLike) -> Path:
        """Where to write ``path`` now: a file directly in ``DIR`` is staged."""
        path = Path(path)
        return self.path / path.name if self.names(path) else path

    def names(self, summary: str | os.PathLike | None) -> dict[str, str]:
        """``{"summary": name}`` if the summary goes into ``DIR``, else ``{}``.

        For ``scene.json``: the next fresh run removes that file with the
        others (:func:`~skfem_npfem.io.checkpoints.clear_run_files`).
        """
        if summary is None or Path(summary).parent.resolve() != self.folder.resolve():
            return {}
        return {"summary": Path(summary).name}

    def watch(self, sim: Any) -> None:
        """Commit ``sim``'s run as soon as it has written a finished step.

        Sets the simulation's ``after_output`` hook; after the commit its
        writer and checkpoints continue in ``DIR``.
        """
        self._sim = sim
        sim.after_output = self.keep_if_steps

    def has_steps(self) -> bool:
        """True if the staging folder holds a finished step (step >= 1)."""
        if not self._staged.is_dir():
            return False
        return any(
            (m := _STEP_FILE.fullmatch(f.name)) and int(m[1]) >= 1
            for f in self._staged.iterdir()
        )

    def keep_if_steps(self, *_: Any) -> None:
        """Commit if the run has written a finished step (else do nothing)."""
        if not self.committed and self.has_steps():
            self.commit()

    def commit(self) -> None:
        """Replace the earlier run's files in ``DIR`` with this run's."""
        if not self.committed:
            self.committed = True
            self.path = self.folder
            self._retarget()
            _commit(self._staged, self.folder)
        elif self._staged != self.folder and self._staged.is_dir():
            # Files written to the staging path after the commit (a scene that
            # kept the path, e.g. for its mechanism) follow the others.
            moving = self._staged.with_name(
                _MOVING + self._staged.name.removeprefix(_STAGING)
            )
            os.replace(self._staged, moving)
            _move_in(moving, self.folder)

    def abandon(self) -> None:
        """Remove the staging folder: ``DIR`` keeps the earlier run's files."""
        if not self.committed:
            shutil.rmtree(self._staged, ignore_errors=True)

    def _retarget(self) -> None:
        """Point the watched simulation's writer and checkpoints at ``DIR``."""
        sim = self._sim
        if sim is None:
            return
        staged = self._staged.resolve()
        checkpoints = getattr(sim, "checkpoint_dir", None)
        if checkpoints is not None and Path(checkpoints).resolve() == staged:
            sim.checkpoint_dir = self.folder
        mover = getattr(sim.writer, "move_to", None)
        if callable(mover) and Path(sim.writer.out_dir).resolve() == staged:
            mover(self.folder)

    def moved(self, path: Any) -> Any:
        """``path`` after the commit (a staged file's name in ``DIR``)."""
        staged = self._staged.resolve()
        if (
            self.committed
            and path is not None
            and Path(path).parent.resolve() == staged
        ):
            return self.folder / Path(path).name
        return path

    @contextmanager
    def hold(self, name: str = "out") -> Iterator[RunFolder]:
        """Hold ``DIR`` for the run; commit or abandon the staged files at the end.

        Takes the folder lock (:func:`~skfem_npfem.io.files.folder_lock`),
        finishes what a killed run left (:func:`finish_commits`, the atomic
        writer's temporaries) and creates the staging folder.  A run that
        ends normally is committed; one that raises is committed if it has a
        finished step (:meth:`has_steps`: the new run's results up to its last
        checkpoint are kept, and can be resumed), else abandoned.
        """
        with folder_lock(self.folder, name):
            finish_commits(self.folder)
            clear_temporaries(self.folder)  # what a killed run may have left
            self._staged.mkdir(exist_ok=True)
            try:
                yield self
            except BaseException as err:
                if self.committed or self.has_steps():
                    self.commit()
                else:
                    self.abandon()
                self._report(err)
                raise
            self.commit()

    def _report(self, err: BaseException) -> None:
        """The files an error names (``RunInterrupted``), where they are now.

        A staged checkpoint or summary is named in ``DIR`` after the commit,
        and is None if the run was abandoned.
        """
        for attr in ("checkpoint", "summary_path"):
            path = getattr(err, attr, None)
            if path is not None:
                path = self.moved(path)
                setattr(err, attr, path if Path(path).is_file() else None)
