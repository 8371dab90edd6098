"""Ready problems (scenes) shared by the API, the CLI, the demos and the tests.

One folder per scene family: ``elastic/`` (``elastic-column``), ``footing/``
(``strip-footing``, ``footing-penetration``, ``cone-penetration``),
``collapse/`` (``column-collapse``), ``slope/`` (``slope``) and
``consolidation/`` (``consolidation``).  What every
family uses stays here, at the top: the scene framework (``base``), declared
and read-only parameters (``params``), the size, memory and step-count checks
(``limits``), the parameters and helpers the scenes share (``common``), the
method of a run (``methods``), the ``analysis=limit`` mode (``limit_mode``)
and the description of a scene's pictures (``scenery``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..errors import ParameterError
from .base import Scene
from .collapse import COLUMN_COLLAPSE
from .consolidation import CONSOLIDATION
from .elastic import ELASTIC_COLUMN
from .footing import CONE_PENETRATION, FOOTING_PENETRATION, STRIP_FOOTING
from .params import Param
from .slope import SLOPE

__all__ = ["SCENES", "Param", "Scene", "get_scene", "run_scene"]

SCENES: dict[str, Scene] = {
    s.name: s
    for s in (
        ELASTIC_COLUMN,
        STRIP_FOOTING,
        COLUMN_COLLAPSE,
        SLOPE,
        FOOTING_PENETRATION,
        CONE_PENETRATION,
        CONSOLIDATION,
    )
}


def get_scene(name: str) -> Scene:
    """Look up a scene by name.

    Raises
    ------
    ParameterError
        If ``name`` is not one of :data:`SCENES` (the message lists them).
    """
    if name not in SCENES:
        raise ParameterError("scene", name, "one of " + ", ".join(SCENES))
    return SCENES[name]


def run_scene(
    name: str,
    overrides: dict[str, Any] | None = None,
    *,
    out: str | Path | None = None,
    summary: str | Path | None = None,
    progress: bool | None = False,
    resume: bool = False,
) -> dict[str, Any]:
    """Run a scene and return its summary dict.

    Parameters
    ----------
    name : str
        Scene name (see ``skfem-npfem scenes``).
    overrides : dict, optional
        Parameter values (numbers or strings as on the command line).
    out : path, optional
        Folder for the VTU series (``result.pvd``) and checkpoints.
    summary : path, optional
        Also write the summary as JSON there.
    progress : bool or None
        Progress line on stderr (None: when stderr is a terminal).
    resume : bool
        Continue from the latest checkpoint in ``out``.  Without it, a run
        into ``out`` first removes the files of an earlier run there.

    Raises
    ------
    ParameterError
        For a bad value, or a run estimated to need more memory than this
        machine has or more than 1e6 steps (``size_check=False`` overrides).
    RunInterrupted
        On SIGINT/SIGTERM, after the step in progress, a checkpoint (with
        ``out``) and the partial summary (``"interrupted": true``, also in
        ``err.summary``).
    """
    return get_scene(name).run(
        overrides, out=out, summary=summary, progress=progress, resume=resume
    )
