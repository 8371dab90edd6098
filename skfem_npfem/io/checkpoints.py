"""Restart checkpoints: the particle state and the run's metadata in one file.

A checkpoint is one uncompressed NumPy ``.npz`` file, usually named
``checkpoint_<step:06d>.npz`` (see :func:`checkpoint_path`). Format version
``"skfem-npfem-checkpoint/1"`` contains the keys

``__format__``
    0-d string array holding the format version.
``__meta__``
    0-d string array holding a JSON object. The simulation loop stores
    ``step`` (int), ``time`` (float), ``dt`` (float), ``scene`` (str) and
    ``parameters`` (dict of JSON values).
any other key
    One particle array each, first dimension = number of particles, for example
    ``x`` and ``v`` and ``a`` (N, d) positions, velocities and accelerations,
    ``stress`` (N, ...) Cauchy stress, ``eps_p`` (N,) equivalent plastic strain,
    ``mass`` (N,) and ``material`` (N,) integer material ids.  A subclass of
    :class:`~skfem_npfem.particles.Particles` adds its own arrays, which may
    have other lengths (FEM with remapping stores its elements ``cells`` and
    the Gauss-point state ``gp_stress``, ``gp_eps_p``).

Arrays must be numeric or bool (no object arrays) and finite.

:func:`write_checkpoint` and :func:`read_checkpoint` store and restore a
simulation's particles with its metadata (the loop's state and its step
records, written by :meth:`~skfem_npfem.run.simulation.Simulation.save_checkpoint`);
:func:`checkpoint_step` finds the checkpoint a run resumes from.
"""

from __future__ import annotations

import io
import json
import os
import re
import zlib
from collections.abc import Mapping
from pathlib import Path
from zipfile import BadZipFile

import numpy as np

from ..errors import CheckpointError, ParameterError
from ..particles import Particles
from .files import dumps, write_bytes
from .results import step_number

__all__ = [
    "CHECKPOINT_FORMAT",
    "checkpoint_path",
    "checkpoint_step",
    "clear_run_files",
    "clear_temporaries",
    "latest_checkpoint",
    "load_checkpoint",
    "read_checkpoint",
    "save_checkpoint",
    "write_checkpoint",
]

CHECKPOINT_FORMAT = "skfem-npfem-checkpoint/1"
_KNOWN_FORMATS = (CHECKPOINT_FORMAT,)
# zipfile raises NotImplementedError (unknown compression/version) and
# RuntimeError (encrypted flag) on corrupted headers.
_LOAD_ERRORS = (
    OSError,
    ValueError,
    TypeError,
    EOFError,
    BadZipFile,
    zlib.error,
    NotImplementedError,
    RuntimeError,
)


def checkpoint_path(folder: str | os.PathLike, step: int) -> Path:
    """Return ``folder / f"checkpoint_{step:06d}.npz"``."""
    return Path(folder) / f"checkpoint_{step_number('step', step):06d}.npz"


def latest_checkpoint(
    folder: str | os.PathLike, pattern: str = "checkpoint_*.npz"
) -> Path | None:
    """Return the checkpoint in ``folder`` with the largest step number, or None.

    The step number is the last group of digits in the file name.
    """
    best: tuple[int, Path] | None = None
    for f in Path(folder).glob(pattern):
        digits = re.findall(r"\d+", f.name.removesuffix(".npz"))
        if f.is_file() and digits and (best is None or int(digits[-1]) > best[0]):
            best = (int(digits[-1]), f)
    return None if best is None else best[1]


def save_checkpoint(
    path: str | os.PathLike, arrays: Mapping[str, np.ndarray], meta: Mapping
) -> Path:
    """Write a checkpoint atomically (format described in the module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        Target ``.npz`` file; its folder must exist.
    arrays : mapping of str to numpy.ndarray
        Finite numeric or bool arrays; names must not start with ``__``.
    meta : mapping
        JSON-serializable metadata, encoded by the package's JSON policy
        (:func:`~skfem_npfem.io.files.to_jsonable`: numpy values converted,
        NaN and inf stored as null).

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    data: dict[str, np.ndarray] = {}
    for name, arr in arrays.items():
        a = np.asarray(arr)
        if (
            not isinstance(name, str)
            or name.startswith("__")
            or a.dtype.kind not in "biufc"
        ):
            raise ParameterError(f"arrays[{name!r}]", a.dtype, "numeric, not __name")
        if a.dtype.kind in "fc" and not np.isfinite(a).all():
            raise ParameterError(f"arrays[{name!r}]", "NaN/inf", "finite values only")
        data[name] = a
    try:
        meta_json = dumps(dict(meta))
    except (TypeError, ValueError) as exc:
        raise ParameterError("meta", meta, f"JSON-serializable ({exc})") from exc
    data["__meta__"] = np.array(meta_json)
    data["__format__"] = np.array(CHECKPOINT_FORMAT)
    buf = io.BytesIO()
    np.savez(buf, **data)
    return write_bytes(path, buf.getvalue())


def load_checkpoint(path: str | os.PathLike) -> tuple[dict[str, np.ndarray], dict]:
    """Load and validate a checkpoint written by :func:`save_checkpoint`.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.npz`` checkpoint.

    Returns
    -------
    arrays : dict of str to numpy.ndarray
        The particle arrays (without the ``__format__``/``__meta__`` keys).
    meta : dict
        The decoded metadata.

    Raises
    ------
    CheckpointError
        If the file is missing, truncated, not an npz file, of an unknown
        format version, has corrupt metadata or contains NaN/inf.
    """
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"checkpoint {path}: file does not exist")
    try:
        z = np.load(path, allow_pickle=False)
        if not isinstance(z, np.lib.npyio.NpzFile):
            raise TypeError("a single .npy array")
        with z:
            data = {k: z[k] for k in z.files}
    except _LOAD_ERRORS as exc:
        raise CheckpointError(
            f"checkpoint {path}: truncated or not an npz file ({exc})"
        ) from exc
    fmt = data.pop("__format__", None)
    if fmt is None:
        raise CheckpointError(f"checkpoint {path}: no __format__ key (not ours?)")
    if str(fmt) not in _KNOWN_FORMATS:
        raise CheckpointError(
            f"checkpoint {path}: unknown format version {str(fmt)!r}, "
            f"known: {', '.join(_KNOWN_FORMATS)}"
        )
    try:
        meta = json.loads(str(data.pop("__meta__")))
        if not isinstance(meta, dict):
            raise TypeError("not a JSON object")
    except (KeyError, ValueError, TypeError) as exc:
        raise CheckpointError(f"checkpoint {path}: bad metadata ({exc})") from exc
    for name, a in data.items():
        if a.dtype.kind in "fc" and not np.isfinite(a).all():
            raise CheckpointError(f"checkpoint {path}: array {name!r} has NaN/inf")
    return data, meta


def checkpoint_step(out: str | os.PathLike) -> tuple[Path, int]:
    """Latest checkpoint in ``out`` and its step (from the file name).

    Raises
    ------
    CheckpointError
        If ``out`` holds no checkpoint.
    """
    path = latest_checkpoint(out) if Path(out).is_dir() else None
    if path is None:
        raise CheckpointError(
            f"{out}: no checkpoint_*.npz to resume from (run without --resume)"
        )
    return path, int(path.stem.rsplit("_", 1)[-1])


def write_checkpoint(
    folder: str | os.PathLike, step: int, particles: Particles, meta: Mapping
) -> Path:
    """Write ``folder/checkpoint_<step>.npz`` with the particles and ``meta``."""
    Path(folder).mkdir(parents=True, exist_ok=True)
    path = checkpoint_path(folder, step)
    return save_checkpoint(path, particles.arrays(), meta)


def read_checkpoint(
    path: str | os.PathLike, cls: type[Particles] = Particles
) -> tuple[Particles, dict]:
    """The particles and metadata of a checkpoint (see :func:`load_checkpoint`).

    ``cls`` is :class:`Particles` or a subclass with more fields (for example
    the Gauss-point state of FEM with remapping); its ``from_arrays`` reads
    them back and raises :class:`~skfem_npfem.errors.ParameterError` if one is
    missing.
    """
    arrays, meta = load_checkpoint(path)
    return cls.from_arrays(arrays), meta


#: Names of a run's files in its folder (and in ``plots/``), removed before a
#: fresh run's files take their place: steps, indexes, checkpoints, the
#: mechanism of a limit analysis, ``scene.json`` and a ``summary.json``.
RUN_FILES = re.compile(
    r"\.?(?:\.tmp_)?(?:checkpoint_\d+\.npz|result_\d+\.vtu|result\.pvd"
    r"|result\.vtu\.series|scene\.json|mechanism\.npz|summary\.json)"
)
PLOT_FILES = re.compile(r"[\w.+-]+\.(?:png|gif|mp4)")
#: Temporaries of the atomic writer (:func:`~skfem_npfem.io.files.atomic_path`)
#: that a killed run can leave beside its files.
TEMPORARY_FILES = re.compile(r"\.tmp_[\w.+-]+")


def clear_temporaries(folder: str | os.PathLike) -> list[Path]:
    """Remove the atomic writer's temporaries (``.tmp_<name>``) in ``folder``.

    A write that fails removes its own temporary, but a process killed hard
    (SIGKILL, a power cut) can leave one, possibly empty; nothing ever reads
    it.  A run, fresh or resumed, calls this when it takes the folder (also
    in ``plots/``).  Returns the files removed.
    """
    folder = Path(folder)
    removed = []
    for sub in (folder, folder / "plots"):
        if not sub.is_dir():
            continue
        for f in sorted(sub.iterdir()):
            if TEMPORARY_FILES.fullmatch(f.name) and f.is_file():
                f.unlink(missing_ok=True)
                removed.append(f)
    return removed


def clear_run_files(folder: str | os.PathLike) -> list[Path]:
    """Remove the files an earlier run left in ``folder``; return them.

    Only the package's own names are touched (:data:`RUN_FILES`: checkpoints,
    result steps and their indexes, ``mechanism.npz``, ``summary.json``,
    ``scene.json``, and the pictures in ``plots/``), and a summary of another
    name that ``scene.json`` says the run wrote there; other files stay.
    ``scene.json`` goes last, so a removal cut short can be repeated.  A fresh
    run calls this before its own files take their place, so that a later
    ``--resume`` can never pick up another run's checkpoint.
    """
    folder = Path(folder)
    removed = []
    summary = _summary_name(folder)
    for sub, pattern, extra in (
        (folder, RUN_FILES, summary),
        (folder / "plots", PLOT_FILES, None),
    ):
        if not sub.is_dir():
            continue
        files = sorted(sub.iterdir(), key=lambda f: (f.name == "scene.json", f.name))
        for f in files:
            if (pattern.fullmatch(f.name) or f.name == extra) and f.is_file():
                f.unlink(missing_ok=True)
                removed.append(f)
    return removed


def _summary_name(folder: Path) -> str | None:
    """The name of the summary ``folder/scene.json`` records, if any."""
    try:
        name = json.loads((folder / "scene.json").read_text()).get("summary")
    except (OSError, ValueError, AttributeError):
        return None
    return name if isinstance(name, str) and name == Path(name).name else None
