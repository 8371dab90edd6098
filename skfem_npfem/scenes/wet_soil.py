"""Initial state of a soil with pore water: effective geostatic stress, pore pressure.

Below the water table the skeleton carries the buoyant unit weight
``(rho_sat - rho_w) g``, above it the full ``rho_sat g``; free water above the
ground adds its pressure to the total stress and the pore pressure alike, so
the effective stress does not feel it.  The vertical effective stress at
elevation ``z`` under a ground surface at ``top`` is therefore

    s'_v(z) = -rho g (top - z) + rho_w g [max(level - z, 0) - max(level - top, 0)]

(tension positive) and ``s'_h = K0 s'_v``.  A dry scene (no water) keeps its
particles untouched, bit for bit.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..particles import Particles
from ..step.model import Model
from ..water import Water
from .common import warn_unused
from .soil_profile import UNIFORM_VALUES
from .water import is_wet

__all__ = [
    "DRY_VALUES",
    "effective_vertical_stress",
    "recorded_parameters",
    "warn_dry_water",
    "wet_column",
    "wet_geostatic",
]


def effective_vertical_stress(
    z: np.ndarray, top: float, rho: float, gravity: float, water: Water | None
) -> np.ndarray:
    """Geostatic vertical effective stress at elevations ``z`` (tension +), Pa.

    Parameters
    ----------
    z : ndarray (N,)
        Elevations, m (the last coordinate).
    top : float
        Elevation of the (horizontal) ground surface, m.
    rho : float
        Saturated density of the soil (its density when dry), kg/m^3.
    gravity : float
        Gravitational acceleration, m/s^2.
    water : Water or None
        The model's water; None or no water table: ``-rho g (top - z)``.

    Examples
    --------
    >>> from skfem_npfem.water import WaterTable
    >>> w = Water("drained", WaterTable(level=3.0))
    >>> effective_vertical_stress(np.array([0.0]), 2.0, 2000.0, 10.0, w)
    array([-20000.])
    """
    z = np.asarray(z, float)
    sv = -rho * gravity * (top - z)
    if water is None or water.table is None:
        return sv
    points = np.zeros((z.size + 1, 2))
    points[:, 1] = np.append(z, top)
    pw = water.static_pressure(points, gravity)
    return sv + pw[:-1] - pw[-1]


def wet_geostatic(
    particles: Particles,
    water: Water | None,
    *,
    rho: float,
    gravity: float,
    top: float,
    K0: float,
    vertical: int,
    horizontal: Sequence[int],
    floor: int | None = None,
) -> Particles:
    """The particles of a wet soil at rest: effective stress and pore pressure.

    Replaces the vertical (``vertical``) and horizontal (``horizontal``)
    stress components by the effective geostatic stress
    (:func:`effective_vertical_stress`, ``K0`` times it horizontally), sets
    ``pore_pressure`` to the hydrostatic field of the water table and
    ``excess_pore_pressure`` to zeros; ``floor`` (a wall-force column) is
    scaled from the total to the effective weight on the base.  Without water
    the particles are returned unchanged.
    """
    if water is None:
        return particles
    x = particles.x
    sv = effective_vertical_stress(x[:, -1], top, rho, gravity, water)
    stress = np.array(particles.stress, float, copy=True)
    stress[:, vertical] = sv
    stress[:, list(horizontal)] = K0 * sv[:, None]
    extra = {}
    if floor is not None:
        base = effective_vertical_stress(np.zeros(1), top, rho, gravity, water)[0]
        total = -rho * gravity * top
        wall = np.array(particles.wall_force, float, copy=True)
        wall[:, floor] *= base / total if total != 0 else 1.0
        extra["wall_force"] = wall
    return particles.replace(
        stress=stress,
        pore_pressure=water.static_pressure(x, gravity),
        excess_pore_pressure=np.zeros(particles.n),
        **extra,
    )


#: Parameters a dry run leaves out of its recorded parameters (at these values).
DRY_VALUES = {"drainage": "dry", "water_level": None, "rho_w": 1000.0, "p0": 0.0}


def recorded_parameters(values: Mapping[str, Any]) -> dict[str, Any]:
    """The parameters a run records: a dry run's without the water parameters.

    A dry run writes the records it wrote before the scene had pore water (its
    checkpoints, bit for bit; a checkpoint of then resumes now), so the water
    parameters at their dry values are left out; so are the soil profile's
    at a uniform soil's values
    (:data:`~skfem_npfem.scenes.soil_profile.UNIFORM_VALUES`).
    """
    return {
        k: v
        for k, v in values.items()
        if DRY_VALUES.get(k, k) != v and UNIFORM_VALUES.get(k, k) != v
    }


def wet_column(
    particles: Particles, model: Model, values: Mapping[str, Any], height: float
) -> Particles:
    """A column of soil at rest on the floor (wall 0) with the model's water.

    :func:`wet_geostatic` with the soil's ``rho``, ``gravity`` and ``K0``; the
    vertical stress slot is the last axis (1 in plane strain and axisymmetry,
    2 in 3D).  Dry: the particles unchanged.
    """
    vertical = particles.x.shape[1] - 1
    return wet_geostatic(
        particles,
        model.water,
        rho=values["rho"],
        gravity=values["gravity"],
        top=height,
        K0=values["K0"],
        vertical=vertical,
        horizontal=[i for i in (0, 1, 2) if i != vertical],
        floor=0,
    )


def warn_dry_water(values: Mapping[str, Any], given: frozenset[str]) -> None:
    """Warn that ``rho_w`` is not used by a dry soil (``drainage=dry``)."""
    if not is_wet(values) and values.get("water_level") is None:
        warn_unused(given, ("rho_w",), "a dry soil (drainage=dry) has no pore water")
