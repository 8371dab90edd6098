"""Every file the package writes, and reading them back.

* :mod:`~skfem_npfem.io.files` -- the one atomic writer (:func:`atomic_path`:
  temporary file, ``fsync``, rename, clean-up), the one JSON encoder
  (:func:`to_jsonable`: NaN and inf are written as ``null``) and the check of
  an output folder before a run;
* :mod:`~skfem_npfem.io.results` -- the VTU + PVD result series
  (:class:`ResultWriter`, :func:`read_pvd`, :func:`read_step`);
* :mod:`~skfem_npfem.io.checkpoints` -- restart checkpoints (format
  ``skfem-npfem-checkpoint/1``) and the simulation state they hold;
* :mod:`~skfem_npfem.io.run_folder` -- a run's output folder
  (:class:`RunFolder`): a fresh run is staged until it has a finished step,
  so a run that fails early leaves the earlier results as they were.

Scene summaries and ``scene.json`` (:mod:`skfem_npfem.scenes`) and the
pictures of :mod:`skfem_npfem.viz.plot` are written through the same atomic writer.
"""

from __future__ import annotations

from .checkpoints import (
    CHECKPOINT_FORMAT,
    checkpoint_path,
    checkpoint_step,
    latest_checkpoint,
    load_checkpoint,
    read_checkpoint,
    save_checkpoint,
    write_checkpoint,
)
from .files import (
    LOCK_NAME,
    atomic_path,
    check_not_held,
    check_writable_dir,
    dumps,
    folder_lock,
    to_jsonable,
    write_bytes,
    write_json,
)
from .results import ResultWriter, read_pvd, read_step, step_time, water_point_data
from .run_folder import RunFolder

__all__ = [
    "CHECKPOINT_FORMAT",
    "LOCK_NAME",
    "ResultWriter",
    "RunFolder",
    "atomic_path",
    "check_not_held",
    "check_writable_dir",
    "checkpoint_path",
    "checkpoint_step",
    "dumps",
    "folder_lock",
    "latest_checkpoint",
    "load_checkpoint",
    "read_checkpoint",
    "read_pvd",
    "read_step",
    "save_checkpoint",
    "step_time",
    "to_jsonable",
    "water_point_data",
    "write_bytes",
    "write_checkpoint",
    "write_json",
]
