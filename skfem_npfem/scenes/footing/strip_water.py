"""Pore water in the strip footing: parameters, initial state, references.

The soil's ``rho`` is its saturated density; ``c`` and ``phi`` are effective.
A weightless soil can start from a uniform isotropic effective stress ``p0``
(K0 = 1).  Undrained, with ``psi = 0``, the plane-strain in-plane mean
effective stress cannot change (no volume change, no plastic dilation), so a
weightless Mohr-Coulomb soil behaves as Tresca with the undrained strength

    s_u = c cos(phi) + p0 sin(phi)

and its collapse load is Prandtl's ``(2 + pi) s_u``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...limit.undrained import undrained_materials
from ...materials import Material, Tresca
from ...particles import Particles
from ...water import water_force
from ..params import Param
from ..water import scene_water, water_params
from ..wet_soil import wet_geostatic

__all__ = [
    "FOOTING_WATER_PARAMS",
    "footing_gamma",
    "initial_state",
    "limit_soil",
    "undrained_strength",
    "water_dead_load",
]

#: The water parameters of the strip footing and the weightless soil's ``p0``.
FOOTING_WATER_PARAMS = [
    *water_params(coupled=True),
    Param(
        "p0",
        0.0,
        "Pa",
        "initial isotropic effective stress of a weightless soil (rho = 0; "
        "K0 = 1); with drainage=undrained and psi = 0 it sets the undrained "
        "strength s_u = c cos(phi) + p0 sin(phi)",
        float,
        lo=0,
    ),
]


def footing_gamma(values: Mapping[str, Any]) -> float:
    """The unit weight of ``N_gamma = q / (gamma b)``, N/m^3.

    ``rho g``; the buoyant ``(rho - rho_w) g`` when drained under a water
    table at or above the ground (the top of the ``domain_width * b`` block).
    """
    gamma = values["rho"] * values["gravity"]
    level = values.get("water_level")
    top = values["domain_width"] * values["width"] / 2
    if values.get("drainage") == "drained" and level is not None and level >= top:
        gamma = (values["rho"] - values["rho_w"]) * values["gravity"]
    return gamma


def soil_gravity(values: Mapping[str, Any]) -> float:
    """The model's gravity: that of the values for a soil with weight, else 0."""
    return values["gravity"] if values["rho"] > 0 else 0.0


def initial_state(
    values: Mapping[str, Any], particles: Particles, top: float, K0: float
) -> Particles:
    """The footing's soil at rest with its water and ``p0`` (dry, p0 = 0: as given).

    Wet: the effective geostatic stress (buoyant weight below the water table)
    and the hydrostatic pore pressure (:func:`~..wet_soil.wet_geostatic`).
    ``p0``: a uniform isotropic effective stress ``-p0`` on the normal
    components.
    """
    particles = wet_geostatic(
        particles,
        scene_water(values),
        rho=values["rho"],
        gravity=soil_gravity(values),
        top=top,
        K0=K0,
        vertical=1,
        horizontal=(0, 2),
    )
    p0 = values.get("p0", 0.0) if values["rho"] == 0 else 0.0
    if p0:
        stress = np.array(particles.stress, float, copy=True)
        stress[:, :3] -= p0
        particles = particles.replace(stress=stress)
    return particles


def undrained_strength(values: Mapping[str, Any], phi: float) -> float | None:
    """``s_u = c cos(phi) + p0 sin(phi)`` of an undrained weightless soil, Pa.

    None unless ``drainage=undrained``, ``rho = 0`` and ``psi = 0`` (the
    conditions under which the soil is a Tresca soil of that strength; the
    limit analysis flows at constant volume whatever ``psi``).
    """
    psi = phi if values["psi"] is None else values["psi"]
    if values["drainage"] != "undrained" or values["rho"] > 0:
        return None
    if psi != 0.0 and values.get("analysis") != "limit":
        return None
    f = math.radians(phi)
    return values["c"] * math.cos(f) + values.get("p0", 0.0) * math.sin(f)


def water_dead_load(values: Mapping[str, Any], ni, x: np.ndarray) -> np.ndarray:
    """The water force on the skeleton in the limit analysis's dead load, N.

    :func:`~skfem_npfem.water.water_force` of the hydrostatic pore pressure
    (buoyancy; zeros when dry or without a water table).
    """
    water = scene_water(values)
    if water is None:
        return np.zeros_like(x)
    return water_force(ni, x, water.static_pressure(x, soil_gravity(values)))


def limit_soil(
    values: Mapping[str, Any], mat: Material, stress: np.ndarray
) -> tuple[Material, float]:
    """The limit analysis's soil and cohesion: ``mat`` and ``c``, or undrained.

    An undrained soil collapses at constant volume with the undrained strength
    of its initial effective stress.  A weightless soil with ``psi = 0`` has a
    uniform one, ``c cos(phi) + p0 sin(phi)`` (the limit analysis flows at
    constant volume whatever ``psi``); a soil with weight has one per particle,
    from its initial effective stress ``stress``
    (:func:`~skfem_npfem.limit.undrained.undrained_materials`), and its
    reference strength is the surface's, ``c cos(phi)``.
    """
    if values["drainage"] != "undrained":
        return mat, values["c"]
    phi = 0.0 if values["material"] == "tresca" else math.radians(values["phi"])
    if values["rho"] > 0:
        soil = undrained_materials([mat], np.zeros(len(stress), int), stress)[0]
        return soil, values["c"] * math.cos(phi)
    s_u = values["c"] * math.cos(phi) + values["p0"] * math.sin(phi)
    return Tresca(mat.E, mat.nu, mat.rho, c=s_u), s_u
