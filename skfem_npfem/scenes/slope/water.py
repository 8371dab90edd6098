"""The slope's pore water: its table, the static pore pressure, the strengths.

``drainage``, ``water_level`` and ``rho_w`` are the scene parameters every
soil scene shares (:mod:`skfem_npfem.scenes.water`).  A cross-section file
may give the water instead: a phreatic line (a table) or heads (a steady
seepage, :class:`~skfem_npfem.water.Seepage`, solved on the particles'
mesh; with both, the heads set the pore pressure).  With water the
section's density is the saturated one; the particles carry the effective
stress and the static pore pressure; the factor of safety loads
the skeleton with the saturated weight and the pore pressure's force
(drained), or uses the undrained strengths of the initial effective stresses
(undrained; :mod:`skfem_npfem.limit.undrained`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ...constants import GRAVITY
from ...limit.undrained import UndrainedStrength
from ...materials import Material
from ...mesh.regions import CrossSection
from ...mesh.section_water import section_water
from ...particles import Particles
from ...water import HeadBoundary, Seepage, Water, WaterTable
from ..water import derive_drainage, is_wet, scene_water
from .section import section_of

__all__ = [
    "derive_slope_drainage",
    "section_has_water",
    "section_seepage",
    "section_table",
    "slope_water",
    "static_pressure",
    "surface_pressure",
    "undrained_metrics",
    "wet_particles",
]


def section_table(sec: CrossSection, rho_w: float = 1000.0) -> WaterTable | None:
    """The water table of a cross-section file's phreatic line (None: none)."""
    return section_water(sec, rho_w)


def section_seepage(sec: CrossSection) -> Seepage | None:
    """The steady seepage of a cross-section file's ``"heads"`` (None: none).

    The conductivity is the materials' ``k`` in the section's material order
    (the particles' material ids), or one uniform ``k`` when no material
    gives one: the heads of a soil of one conductivity do not depend on its
    value (``div(k grad h) = 0`` is ``div(grad h) = 0``).  The reader
    (:func:`~skfem_npfem.mesh.section_file.read_cross_section`) has checked
    that every material gives ``k`` when any does.
    """
    if not sec.heads:
        return None
    heads = [HeadBoundary(line, head, name) for name, line, head in sec.heads]
    ks = [props.get("k") for props in sec.materials.values()]
    if any(k is None for k in ks):
        return Seepage(heads)
    return Seepage(heads, k=ks)


def section_has_water(values: Mapping[str, Any]) -> bool:
    """The run's cross-section file gives a phreatic line or heads."""
    if not values.get("geometry"):
        return False
    sec = section_of(values)[0]
    return sec.water is not None or bool(sec.heads)


def derive_slope_drainage(values: dict[str, Any]) -> None:
    """Fill ``drainage``: a section file's water counts as a water level.

    Without ``water_level``, a cross-section file with a phreatic line or
    heads makes the soil ``drained`` by default (``drainage=dry`` ignores
    them); otherwise :func:`~skfem_npfem.scenes.water.derive_drainage`.
    """
    if values.get("water_level") is None and section_has_water(values):
        if values.get("drainage") is None:
            values["drainage"] = "drained"
        return
    derive_drainage(values)


def slope_water(values: Mapping[str, Any], sec: CrossSection) -> Water | None:
    """The slope's :class:`~skfem_npfem.Water` (None: dry).

    The scene's ``water_level`` sets the table; without one, the section
    file's heads (a steady seepage, :func:`section_seepage`) or else its
    phreatic line (:func:`section_table`) do: with both, the heads win (the
    seepage's head boundaries stand for the free water).
    """
    if not is_wet(values):
        return None
    if values.get("water_level") is None:
        rho_w = float(values["rho_w"])
        seepage = section_seepage(sec)
        if seepage is not None:
            return Water(values["drainage"], rho_w=rho_w, seepage=seepage)
        table = section_table(sec, rho_w)
        if table is not None:
            return Water(values["drainage"], table, rho_w)
    return scene_water(values)


def static_pressure(
    water: Water | None,
    x: np.ndarray,
    t: np.ndarray | None = None,
    material: np.ndarray | None = None,
) -> np.ndarray | None:
    """The static pore pressure at ``x`` under gravity (None when dry), Pa.

    A seepage is solved on the mesh ``t`` (3, ne) whose nodes are ``x``, with
    the nodes' material ids ``material`` (its conductivities); a table
    needs neither.
    """
    if water is None:
        return None
    return water.static_pressure(x, GRAVITY, t=t, material=material)


def surface_pressure(
    water: Water,
    x: np.ndarray,
    t: np.ndarray,
    material: np.ndarray,
    top: np.ndarray,
) -> np.ndarray:
    """The static pore pressure at surface points ``top`` (free water), Pa.

    A table's is its hydrostatic pressure there; a seepage's is
    ``rho_w g max(h - z, 0)`` with the head ``h`` of the mesh node ``(x, t)``
    nearest to each point (the points are on or next to the mesh's top,
    where the head is continuous).
    """
    if water.seepage is None:
        return water.static_pressure(top, GRAVITY)
    head = water.seepage.solve(x, t, material).head
    nearest = cKDTree(x).query(top)[1]
    return water.rho_w * GRAVITY * np.maximum(head[nearest] - top[:, -1], 0.0)


def wet_particles(
    particles: Particles, water: Water | None, t: np.ndarray | None = None
) -> Particles:
    """The initial particles with the static pore pressure, no excess.

    Dry (``water`` None): the particles as they are.  A seepage is solved on
    the particles' mesh ``t`` (3, ne) with their material ids.
    """
    if water is None:
        return particles
    p0 = static_pressure(water, particles.x, t, particles.material)
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
