"""The scenery of a result folder: what its scene says a picture shows.

:func:`scenery` reads ``scene.json`` of a result folder (written by the scene
runner) and asks that scene for its :class:`~skfem_npfem.scenes.scenery.Scenery`
(the scene's ``scenery`` hook).  A folder of an unknown scene gets an empty
scenery, so the pictures still have axes in metres; one whose parameters carry
a column's scales (``aspect``, ``length``) also gets the normalised time.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from ..constants import GRAVITY
from ..scenes import SCENES
from ..scenes.scenery import Scenery, number, time_label

__all__ = ["scenery"]


def scenery(folder: str | Path) -> Scenery:
    """The scenery of the result in ``folder`` (from its ``scene.json``)."""
    folder = Path(folder)
    try:
        info: Any = json.loads((folder / "scene.json").read_text())
        params = dict(info.get("parameters", {}))
        name = str(info.get("scene", ""))
    except (OSError, ValueError, AttributeError, TypeError):
        return Scenery()
    scene = SCENES.get(name)
    if scene is not None and scene.scenery is not None:
        return scene.scenery(params, folder)
    s = Scenery(scene=name)
    aspect, length = number(params, "aspect"), number(params, "length")
    if aspect and length:
        g = number(params, "gravity", GRAVITY) or GRAVITY
        s.tau = math.sqrt(aspect * length / g)
        s.label = time_label(s.tau)
    return s
