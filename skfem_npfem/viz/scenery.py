"""The scenery of a result folder: what its scene says a picture shows.

:func:`scenery` reads ``scene.json`` of a result folder (written by the scene
runner) and asks that scene for its :class:`~skfem_npfem.scenes.scenery.Scenery`
(the scene's ``scenery`` hook).  A folder of an unknown scene gets an empty
scenery, so the pictures still have axes in metres; one whose parameters carry
a column's scales (``aspect``, ``length``) also gets the normalised time.
A run with pore water (a ``water_level`` parameter, ``drainage`` not dry)
gets its water table, unless its scene drew one already (a section's line).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..constants import GRAVITY
from ..errors import NpfemError
from ..mesh.section_file import read_cross_section
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
        return _water(scene.scenery(params, folder), params)
    s = Scenery(scene=name)
    aspect, length = number(params, "aspect"), number(params, "length")
    if aspect and length:
        g = number(params, "gravity", GRAVITY) or GRAVITY
        s.tau = math.sqrt(aspect * length / g)
        s.label = time_label(s.tau)
    return _water(s, params)


def _water(s: Scenery, params: dict) -> Scenery:
    """The run's water table, unless its scene drew one: a section's, or a level.

    A cross-section file (the ``geometry`` parameter) with a ``water`` line
    gives that line; else a ``water_level`` parameter a horizontal table.
    A run with ``drainage=dry`` has none.
    """
    if s.water_line is not None or s.water_level is not None:
        return s
    if params.get("drainage") == "dry":
        return s
    geometry = params.get("geometry")
    if isinstance(geometry, str) and geometry and Path(geometry).is_file():
        try:
            line = getattr(read_cross_section(geometry), "water", None)
        except (NpfemError, OSError, ValueError, KeyError, TypeError):
            line = None
        if line is not None:
            s.water_line = np.asarray(line, dtype=float)
            return s
    s.water_level = number(params, "water_level")
    return s
