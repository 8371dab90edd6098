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
from typing import Any

import numpy as np

from ...constants import GRAVITY
from ...limit.undrained import UndrainedStrength
from ...materials import Material
from ...mesh.regions import CrossSection
from ...mesh.section_water import section_water
from ...particles import Particles
from ...water import Water, WaterTable
from ..water import derive_drainage, is_wet, scene_water
from .section import section_of

__all__ = [
    "derive_slope_drainage",
    "section_has_water",
    "section_table",
    "slope_water",
    "static_pressure",
    "undrained_metrics",
    "wet_particles",
]


def section_table(sec: CrossSection, rho_w: float = 1000.0) -> WaterTable | None:
    """The water table of a cross-section file's phreatic line (None: none)."""
    return section_water(sec, rho_w)


def section_has_water(values: Mapping[str, Any]) -> bool:
    """The run's cross-section file gives a phreatic line (``"water"``)."""
    return bool(values.get("geometry")) and section_of(values)[0].water is not None


def derive_slope_drainage(values: dict[str, Any]) -> None:
    """Fill ``drainage``: a section file's water line counts as a water level.

    Without ``water_level``, a cross-section file with a phreatic line makes
    the soil ``drained`` by default (``drainage=dry`` ignores the line);
    otherwise :func:`~skfem_npfem.scenes.water.derive_drainage`.
    """
    if values.get("water_level") is None and section_has_water(values):
        if values.get("drainage") is None:
            values["drainage"] = "drained"
        return
    derive_drainage(values)


def slope_water(values: Mapping[str, Any], sec: CrossSection) -> Water | None:
    """The slope's :class:`~skfem_npfem.Water` (None: dry).

    The scene's ``water_level`` sets the table; without one, the section
    file's phreatic line (:func:`section_table`) does.
    """
    if not is_wet(values):
        return None
    table = None
    if values.get("water_level") is None:
        table = section_table(sec, float(values["rho_w"]))
    if table is None:
        return scene_water(values)
    return Water(values["drainage"], table, float(values["rho_w"]))


def static_pressure(water: Water | None, x: np.ndarray) -> np.ndarray | None:
    """The static pore pressure at ``x`` under gravity (None when dry), Pa."""
    return None if water is None else water.static_pressure(x, GRAVITY)


def wet_particles(particles: Particles, water: Water | None) -> Particles:
    """The initial particles with the table's hydrostatic pore pressure, no excess.

    Dry (``water`` None): the particles as they are.
    """
    if water is None:
        return particles
    p0 = water.static_pressure(particles.x, GRAVITY)
    return particles.replace(pore_pressure=p0, excess_pore_pressure=0 * p0)


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
