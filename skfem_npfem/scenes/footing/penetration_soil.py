"""The soil of the penetration scenes: Tresca, or an effective-stress clay.

A total-stress Tresca clay of strength ``su``, or a Mohr-Coulomb clay (``c``,
``phi``, ``psi``) whose undrained strength follows from its initial mean
effective stress (:func:`undrained_strength`), with the pore water of
:mod:`~skfem_npfem.scenes.water` on its particles and in its metrics.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...errors import ParameterError
from ...particles import Particles
from ..params import ANGLE, Param
from ..water import is_wet, scene_water
from ..wet_soil import recorded_parameters

__all__ = [
    "SHEARING",
    "SOIL_MATERIALS",
    "TRESCA_VALUES",
    "WATER_METRICS",
    "derive_soil",
    "penetration_parameters",
    "pore_metrics",
    "refuse_soil",
    "soil_params",
    "undrained_strength",
    "with_pore_pressure",
]

#: Soils of the penetration scenes: a total-stress Tresca clay (``su``) or an
#: effective-stress Mohr-Coulomb clay (``c``, ``phi``, ``psi``).
SOIL_MATERIALS = ("tresca", "mohr-coulomb")

#: Modes of shearing of :func:`undrained_strength`.
SHEARING = ("plane-strain", "triaxial-compression", "triaxial-extension")


def soil_params(su: float, derived: str) -> list[Param]:
    """``material``, ``su`` (Tresca's, default ``su``), ``c``, ``phi``, ``psi``.

    ``derived`` says how the scene derives a Mohr-Coulomb clay's ``su``.
    """
    return [
        Param(
            "material",
            "tresca",
            "-",
            "soil: tresca (total-stress clay of strength su) or mohr-coulomb "
            "(effective-stress clay c, phi, psi; with drainage=undrained its "
            "undrained strength follows from them and the initial effective stress)",
            str,
            SOIL_MATERIALS,
        ),
        Param(
            "su",
            None,
            "Pa",
            f"undrained shear strength s_u (default {su:g} with material=tresca; "
            f"with mohr-coulomb its undrained strength {derived}, the only value "
            "accepted)",
            float,
            lo=0,
            lo_open=True,
        ),
        Param(
            "c",
            0.0,
            "Pa",
            "effective cohesion c' (material=mohr-coulomb)",
            float,
            lo=0,
        ),
        Param(
            "phi",
            25.0,
            "deg",
            "effective friction angle phi' (material=mohr-coulomb)",
            float,
            **ANGLE,
        ),
        Param(
            "psi",
            0.0,
            "deg",
            "dilation angle (material=mohr-coulomb; 0: isochoric plastic flow, "
            "which an undrained soil needs to reach a limit load)",
            float,
            **ANGLE,
        ),
    ]


def undrained_strength(c: float, phi: float, p0: float, mode: str) -> float:
    """The undrained strength of a Mohr-Coulomb clay that keeps its mean stress.

    Undrained shearing with an isochoric plastic flow (``psi = 0``) keeps the
    volume, hence the elastic volume change is nil and the mean effective
    stress stays ``p0`` (compression positive).  Mohr-Coulomb,
    ``sigma'_1 - sigma'_3 = (sigma'_1 + sigma'_3) sin(phi) + 2 c cos(phi)``,
    then gives ``s_u = (sigma'_1 - sigma'_3)/2``:

    * ``plane-strain``: ``sigma'_2 = (sigma'_1 + sigma'_3)/2`` (no plastic
      strain out of plane), so the circle's centre is ``p0`` and
      ``s_u = c cos(phi) + p0 sin(phi)``;
    * ``triaxial-compression`` (``sigma'_2 = sigma'_3``, ``p0 = (sigma'_1 +
      2 sigma'_3)/3``): ``s_u = 3 (c cos(phi) + p0 sin(phi)) / (3 - sin(phi))``;
    * ``triaxial-extension`` (``sigma'_2 = sigma'_1``): the same over
      ``3 + sin(phi)``.

    Examples
    --------
    >>> round(undrained_strength(0.0, 30.0, 100.0, "plane-strain"), 9)
    50.0
    >>> round(undrained_strength(0.0, 30.0, 100.0, "triaxial-compression"), 9)
    60.0
    >>> round(undrained_strength(0.0, 30.0, 100.0, "triaxial-extension"), 9)
    42.857142857
    """
    if mode not in SHEARING:
        raise ParameterError("mode", mode, f"one of {', '.join(SHEARING)}")
    s = math.sin(math.radians(phi))
    plane = c * math.cos(math.radians(phi)) + p0 * s
    if mode == "plane-strain":
        return plane
    return 3.0 * plane / (3.0 - s if mode == "triaxial-compression" else 3.0 + s)


def refuse_soil(values: Mapping[str, Any], given: frozenset[str]) -> None:
    """Refuse Mohr-Coulomb parameters given to a Tresca soil.

    Raises
    ------
    ParameterError
        Naming the parameter that the chosen ``material`` does not use.
    """
    if values["material"] == "tresca":
        for name in ("c", "phi", "psi"):
            if name in given:
                raise ParameterError(
                    name,
                    values[name],
                    "left out with material=tresca (its strength is su); choose "
                    "material=mohr-coulomb for an effective-stress clay",
                )


def derive_soil(values: dict[str, Any], su: float, p0: float, mode: str) -> None:
    """Fill ``su``: ``su`` for Tresca, the derived undrained strength otherwise.

    ``p0`` is the initial mean effective stress, ``mode`` the shearing of
    :func:`undrained_strength`.

    Raises
    ------
    ParameterError
        A Mohr-Coulomb clay without strength (``c = 0`` and ``p0 sin(phi) =
        0``), or with an ``su`` other than its derived one.
    """
    if values["material"] == "tresca":
        if values["su"] is None:
            values["su"] = su
        return
    derived = undrained_strength(values["c"], values["phi"], p0, mode)
    if derived <= 0.0:
        raise ParameterError(
            "c",
            values["c"],
            "c > 0, or phi > 0 with an initial effective stress > 0: the clay "
            "has no strength",
        )
    if values["su"] is not None and not math.isclose(
        values["su"], derived, rel_tol=1e-9
    ):
        raise ParameterError(
            "su",
            values["su"],
            f"left out with material=mohr-coulomb (its undrained strength is "
            f"derived from c, phi and the initial stress: {derived:g} Pa)",
        )
    values["su"] = derived


def with_pore_pressure(particles: Particles, values: Mapping[str, Any]) -> Particles:
    """The initial particles with the static pore pressure and no excess.

    The scenes are weightless (``gravity = 0``), so a water table's
    hydrostatic pressure, and the static pore pressure, is nil; the stress
    the particles carry is then both total and effective.  Dry soil: the
    particles unchanged.
    """
    water = scene_water(values)
    if water is None:
        return particles
    static = water.static_pressure(particles.x, 0.0)
    return particles.replace(
        pore_pressure=static, excess_pore_pressure=np.zeros(particles.n)
    )


#: The metrics :func:`pore_metrics` adds.
WATER_METRICS = {
    "undrained_strength": "material=mohr-coulomb only: the s_u the factors are "
    "divided by (its derivation: the parameter su), Pa",
    "max_excess_pore_pressure": "with water only: the largest excess pore "
    "pressure of the particles at the end / s_u",
}


def pore_metrics(
    p: Particles,
    values: Mapping[str, Any],
    near: np.ndarray | None = None,
    name: str = "",
) -> dict[str, Any]:
    """s_u of a Mohr-Coulomb clay; the excess pore pressure of a wet soil / s_u.

    ``near`` (bool, N) picks particles whose mean excess pore pressure is
    reported as ``name``.  Empty for a dry Tresca soil (its metrics stay as
    they were).
    """
    out: dict[str, Any] = {}
    su = values["su"]
    if values["material"] != "tresca":
        out["undrained_strength"] = su
    u = p.excess_pore_pressure
    if not is_wet(values) or u is None:
        return out
    out["max_excess_pore_pressure"] = float(u.max()) / su
    if near is not None:
        out[name] = float(u[near].mean()) / su if near.any() else None
    return out


#: The cone's dissipation-test parameters, recorded only with ``dissipation``.
DISSIPATION_NAMES = ("dissipation", "dT", "dt_growth", "dT_max", "T_end")

#: The soil parameters of a Tresca clay as the scenes had them before
#: effective-stress clays: a run with these records none of them.
TRESCA_VALUES = {"material": "tresca", "c": 0.0, "phi": 25.0, "psi": 0.0}


def penetration_parameters(values: Mapping[str, Any]) -> dict[str, Any]:
    """The parameters a penetration run records.

    A dry Tresca run records what it recorded before the scenes had pore
    water and effective-stress clays (its checkpoints, bit for bit): the
    water parameters at their dry values
    (:func:`~skfem_npfem.scenes.wet_soil.recorded_parameters`) and, with
    ``material=tresca``, the Mohr-Coulomb parameters at their defaults are
    left out; so are a cone's ``k`` when not coupled, its dissipation
    stepping without a dissipation test, its ``rho`` when weightless and its
    ``shoulder_round`` when sharp.
    """
    out = recorded_parameters(values)
    if out.get("k", 0.0) is None:  # not coupled: no conductivity
        del out["k"]
    if not out.get("dissipation", True):  # no dissipation test: no stepping
        out = {k: v for k, v in out.items() if k not in DISSIPATION_NAMES}
    if values.get("material") == "tresca":
        out = {k: v for k, v in out.items() if TRESCA_VALUES.get(k, k) != v}
    for name in ("rho", "shoulder_round"):  # a weightless or sharp cone as before
        if out.get(name) == 0.0:
            del out[name]
    return out
