"""The water parameters every scene with soil shares, and the model's water.

``drainage`` (dry, drained or undrained), ``water_level`` (the elevation of a
horizontal water table, m) and ``rho_w`` (the water's density).  Without a
water level the default is ``dry``: today's soil, bit-identical to a scene
without these parameters; with one it is ``drained``.  A scene adds
:data:`WATER_PARAMS` to its parameters, calls :func:`derive_drainage` in its
``derive`` and hands :func:`scene_water` to its :class:`~skfem_npfem.Model`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..errors import ParameterError
from ..water import Water, WaterTable
from .params import POSITIVE, Param

__all__ = [
    "DRAINAGE",
    "WATER_PARAMS",
    "derive_drainage",
    "is_wet",
    "scene_water",
    "water_params",
]

#: Values of the ``drainage`` parameter (``coupled`` where a scene offers it).
DRAINAGE = ("dry", "drained", "undrained", "coupled")


def water_params(coupled: bool = False) -> list[Param]:
    """The water parameters of a scene with soil.

    ``coupled=True`` offers ``drainage=coupled`` (consolidation: the water
    flows by Darcy's law while the soil deforms) and its hydraulic
    conductivity ``k``.
    """
    choices = DRAINAGE if coupled else DRAINAGE[:3]
    help_ = (
        "pore water: dry (no water), drained (pore pressure from the water "
        "table, effective stress in the cones) or undrained (no drainage within "
        "a step: the mixture keeps its volume; excess pore pressure)"
    )
    if coupled:
        help_ += " or coupled (Darcy flow within each step, k; the soil consolidates)"
    drainage = Param(
        "drainage",
        None,
        "-",
        help_ + " (default: dry without water_level, drained with it)",
        str,
        choices,
    )
    out = [drainage, *_LEVEL_AND_DENSITY]
    if coupled:
        out.append(
            Param(
                "k",
                None,
                "m/s",
                "hydraulic conductivity of the soil (drainage=coupled)",
                float,
                lo=0,
                lo_open=True,
            )
        )
    return out


_LEVEL_AND_DENSITY = [
    Param(
        "water_level",
        None,
        "m",
        "elevation of a horizontal water table (hydrostatic pore pressure "
        "below it; above the ground it is free water loading the surface); "
        "default: none",
        float,
    ),
    Param("rho_w", 1000.0, "kg/m^3", "density of the pore water", float, **POSITIVE),
]

#: The water parameters of a scene with soil (no ``coupled`` drainage).
WATER_PARAMS = water_params()


def derive_drainage(values: dict[str, Any]) -> None:
    """Fill ``drainage`` from ``water_level``; refuse a drained soil without water.

    Raises
    ------
    ParameterError
        ``drainage=drained`` without a ``water_level``, or ``drainage=dry``
        with one.
    """
    level = values.get("water_level")
    if values.get("drainage") is None:
        values["drainage"] = "dry" if level is None else "drained"
    if values["drainage"] == "drained" and level is None:
        raise ParameterError(
            "drainage",
            "drained",
            "drained with a water_level (m) that sets the pore pressure, or dry",
        )
    if values["drainage"] == "coupled" and values.get("k") is None:
        raise ParameterError(
            "k",
            None,
            "a hydraulic conductivity k > 0 (m/s) with drainage=coupled",
        )
    if values["drainage"] == "dry" and level is not None:
        raise ParameterError(
            "water_level",
            level,
            "no water_level with drainage=dry (give drainage=drained or undrained)",
        )


def is_wet(values: Mapping[str, Any]) -> bool:
    """The scene has pore water (``drainage`` other than ``dry``)."""
    return values.get("drainage", "dry") not in (None, "dry")


def scene_water(values: Mapping[str, Any]) -> Water | None:
    """The :class:`~skfem_npfem.Water` of a scene's resolved values (None: dry)."""
    if not is_wet(values):
        return None
    level = values.get("water_level")
    table = None if level is None else WaterTable(level=float(level))
    if values["drainage"] == "coupled":
        return Water(
            "coupled",
            table,
            rho_w=float(values["rho_w"]),
            permeability=float(values["k"]),
        )
    return Water(values["drainage"], table, rho_w=float(values["rho_w"]))
