"""The slope's pore water: its table, the static pore pressure, the strengths.

``drainage``, ``water_level`` and ``rho_w`` are the scene parameters every
soil scene shares (:mod:`skfem_npfem.scenes.water`).  With water the
section's density is the saturated one; the particles carry the effective
stress and the static pore pressure of the table; the factor of safety loads
the skeleton with the saturated weight and the pore pressure's force
(drained), or uses the undrained strengths of the initial effective stresses
(undrained; :mod:`skfem_npfem.limit.undrained`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from ...constants import GRAVITY
from ...limit.undrained import UndrainedStrength
from ...materials import Material
from ...mesh.regions import CrossSection
from ...water import Water, WaterTable
from ..water import scene_water

__all__ = [
    "recorded_parameters",
    "section_table",
    "slope_water",
    "static_pressure",
    "undrained_metrics",
]


def section_table(sec: CrossSection) -> WaterTable | None:
    """The water line of a cross-section file, if it has one.

    HOOK (to be wired when cross-section files carry a water line): return
    ``skfem_npfem.mesh.section_file.section_water(sec, rho_w)`` for a
    section with ``sec.water``.  Until then a section has no water line of
    its own, and the scene's ``water_level`` is the only table.
    """
    return None


def slope_water(values: Mapping[str, Any], sec: CrossSection) -> Water | None:
    """The slope's :class:`~skfem_npfem.Water` (None: dry).

    The scene's ``water_level`` sets the table; without one, the section
    file's water line (:func:`section_table`) does, when it has one.
    """
    water = scene_water(values)
    table = section_table(sec)
    if water is None or table is None or values.get("water_level") is not None:
        return water
    return replace(water, table=table)


def static_pressure(water: Water | None, x: np.ndarray) -> np.ndarray | None:
    """The static pore pressure at ``x`` under gravity (None when dry), Pa."""
    return None if water is None else water.static_pressure(x, GRAVITY)


def undrained_metrics(mats: list[Material]) -> dict[str, float]:
    """``undrained_strength_min/max`` of the undrained strengths (empty if none).

    Parameters
    ----------
    mats : list of Material
        The materials of the factor of safety (unreduced).

    Returns
    -------
    dict
        The smallest and largest ``s_u`` over every point, Pa.
    """
    s_u = [m.s_u for m in mats if isinstance(m, UndrainedStrength)]
    if not s_u:
        return {}
    s = np.concatenate(s_u)
    return {
        "undrained_strength_min": float(s.min()),
        "undrained_strength_max": float(s.max()),
    }


#: The water parameters of a dry slope (:func:`recorded_parameters`).
DRY_VALUES = {"drainage": "dry", "water_level": None, "rho_w": 1000.0}


def recorded_parameters(values: Mapping[str, Any]) -> dict[str, Any]:
    """The parameters a run records: a dry run's without the water parameters.

    A dry run writes the records it wrote before the scene had pore water
    (its checkpoints, bit for bit; a checkpoint of then resumes now).
    """
    return {k: v for k, v in values.items() if DRY_VALUES.get(k, k) != v}
