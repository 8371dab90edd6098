"""The comparison studies' runner: one scene configuration per process, on Dask.

A comparison of methods measures wall time and *peak memory* per
configuration, so each configuration runs in a fresh Python process
(``python -m skfem_npfem run SCENE --set ... --out FOLDER --summary ...``): the
peak resident memory of a long-lived worker would carry the largest earlier
run.  :func:`run_cases` hands the configurations to
:func:`skfem_npfem.sweeps.run_tasks` (a local Dask cluster or a scheduler),
whose tasks each start one such process.

Every configuration has its own folder (``ROOT/NAME``) with the run's
checkpoints, result files, ``summary.json``, ``log.txt`` and ``source.txt``
(the :func:`~skfem_npfem.io.provenance.source_sha1` of the library that ran
it), so a study is resumable: a configuration whose folder holds a summary with
the same parameters from the same library source is not run again, one with a
checkpoint but no summary continues from it (``--resume``), and a failed one
is tried again on the next call.  After a change of the library every
configuration runs afresh (its old checkpoints are deleted): a study measures
one version of the code.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from skfem_npfem.errors import NpfemError
from skfem_npfem.io import dumps, latest_checkpoint, to_jsonable, write_bytes
from skfem_npfem.io.provenance import source_sha1
from skfem_npfem.scenes import run_scene
from skfem_npfem.sweeps import run_tasks

__all__ = [
    "Case",
    "case_args",
    "run_case",
    "run_cases",
    "study_arguments",
    "study_folders",
]

#: A configuration: (scene name, parameter values).
Case = tuple[str, Mapping[str, Any]]


def case_args(params: Mapping[str, Any]) -> list[str]:
    """``--set name=value`` arguments (None values are left to the default).

    Examples
    --------
    >>> case_args({"spacing": 0.05, "method": "spfem", "damping": None, "x": True})
    ['--set', 'spacing=0.05', '--set', 'method=spfem', '--set', 'x=true']
    """
    out: list[str] = []
    for name, value in params.items():
        if value is None:
            continue
        text = str(value).lower() if isinstance(value, bool) else repr(value)
        out += ["--set", f"{name}={text.strip(chr(39))}"]
    return out


def _source(folder: Path) -> str | None:
    """The library source hash a run folder was made with (None: unknown)."""
    path = folder / "source.txt"
    return path.read_text().strip() if path.is_file() else None


def _prepare(folder: Path) -> bool:
    """Make ``folder`` ready for a run of this library; True: resume in it.

    Checkpoints and summaries of another library source are deleted.
    """
    folder.mkdir(parents=True, exist_ok=True)
    sha = source_sha1()
    if _source(folder) != sha:
        for old in [*folder.glob("checkpoint_*.npz"), folder / "summary.json"]:
            old.unlink(missing_ok=True)
        write_bytes(folder / "source.txt", sha.encode())
    return latest_checkpoint(folder) is not None


def _finished(folder: Path, scene: str, params: Mapping[str, Any]) -> dict | None:
    """The folder's summary if it is of this configuration and code, else None."""
    path = folder / "summary.json"
    if not path.is_file() or _source(folder) != source_sha1():
        return None
    try:
        summary = json.loads(path.read_text())
    except ValueError:
        return None
    saved = summary.get("parameters", {})
    want = to_jsonable(dict(params))
    same = all(saved.get(k) == v for k, v in want.items() if v is not None)
    return summary if same and summary.get("scene") == scene else None


def run_case(scene: str, params: Mapping[str, Any], folder: str | Path) -> dict:
    """Run one configuration in a new process (or reuse its finished summary).

    Parameters
    ----------
    scene : str
    params : mapping
        Scene parameters (``None``: the default).
    folder : path
        The configuration's folder (created).

    Returns
    -------
    dict
        The run's JSON summary (as ``skfem-npfem run --summary``).

    Raises
    ------
    NpfemError
        If the run fails; the message ends with the last line of its log.
    """
    folder = Path(folder)
    done = _finished(folder, scene, params)
    if done is not None:
        return done
    resume = _prepare(folder)
    summary, log = folder / "summary.json", folder / "log.txt"
    cmd = [sys.executable, "-m", "skfem_npfem", "run", scene, "--quiet"]
    cmd += ["--out", str(folder), "--summary", str(summary), *case_args(params)]
    if resume:
        cmd.append("--resume")
    env = dict(os.environ)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[var] = "1"
    with open(log, "w") as fh:
        rc = subprocess.call(cmd, env=env, stdout=fh, stderr=subprocess.STDOUT)
    if rc != 0 or not summary.is_file():
        lines = log.read_text().strip().splitlines() or ["(no output)"]
        raise NpfemError(f"{scene} in {folder} failed (exit {rc}): {lines[-1]}")
    return json.loads(summary.read_text())


def run_cases(
    cases: Mapping[str, Case],
    root: str | Path,
    *,
    workers: int | None = None,
    scheduler: Any = None,
    progress: bool = True,
) -> dict[str, dict | None]:
    """Run named configurations, each in its own process, on Dask.

    Parameters
    ----------
    cases : mapping of name to (scene, params)
    root : path
        Each case runs in ``root / name``.
    workers, scheduler, progress
        As :func:`skfem_npfem.sweeps.run_tasks`; ``workers=0`` (and no
        scheduler) runs the cases here, one after another, without Dask or new
        processes (quick checks: wall times stay comparable, peak memory is
        the largest so far of this process).

    Returns
    -------
    dict
        Summary per name; None for a failed case (its error is in
        ``root/name/log.txt``).
    """
    root = Path(root)
    todo = {
        name: (scene, dict(params), str(root / name))
        for name, (scene, params) in cases.items()
        if _finished(root / name, scene, params) is None
    }
    results: dict[str, dict | None] = {}
    if todo and workers == 0 and scheduler is None:
        results.update({k: _in_process(*args) for k, args in todo.items()})
    elif todo:
        outcomes = run_tasks(
            run_case, todo, workers=workers, scheduler=scheduler, progress=progress
        )
        results.update({k: (o.value if o.ok else None) for k, o in outcomes.items()})
    for name, (scene, params) in cases.items():
        if name not in results:
            results[name] = _finished(root / name, scene, params)
    return {name: results[name] for name in cases}


def _in_process(scene: str, params: dict, folder: str) -> dict:
    """One case in this process (``run_cases(..., workers=0)``)."""
    folder_ = Path(folder)
    resume = _prepare(folder_)
    clean = {k: v for k, v in params.items() if v is not None}
    summary = run_scene(
        scene,
        clean,
        out=folder_,
        summary=folder_ / "summary.json",
        progress=False,
        resume=resume,
    )
    return json.loads(dumps(summary))  # as read back from the file (NaN: None)


def study_arguments(parser: Any, out: Path, work: Path) -> None:
    """The command-line options every comparison study shares.

    ``--quick`` (reduced runs in this process), ``--out`` (JSON and figures;
    default ``out``, with ``--quick`` the work folder), ``--work`` (run folders),
    ``--workers`` and ``--scheduler`` (Dask).
    """
    parser.add_argument("--quick", action="store_true", help="reduced, in-process")
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help=f"default {out} (--quick: the work folder)",
    )
    parser.add_argument("--work", type=Path, default=work, help="run folders")
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        help="Dask workers (default: one per core; 0: in this process)",
    )
    parser.add_argument("--scheduler", default=None, help="Dask scheduler address")


def study_folders(args: Any, out: Path, mode: str) -> tuple[Path, Path, int | None]:
    """``(work folder, output folder, workers)`` of a study's parsed options."""
    work = args.work / mode
    workers = 0 if args.quick and args.workers is None else args.workers
    return work, args.out or (work if args.quick else out), workers
