"""The cone's ground: weight, a strength growing with depth, the net resistance.

By default the cone-penetration soil is weightless and uniform (a deep test
idealised: ``sigma0`` everywhere, one ``s_u``).  Site investigation reads a
cone in a heavy clay whose strength grows with depth: ``rho`` gives the soil
its unit weight ``gamma = rho g`` (the initial stress is then ``sigma0 +
gamma z`` at depth ``z`` below the surface, isotropic as ``sigma0`` is, and
gravity acts in every step), and ``su_gradient`` makes ``s_u(z) = su + k z``
(``layers``: a strength by layers)
(:mod:`~skfem_npfem.scenes.soil_profile`; with ``stiffness_profile =
strength`` the rigidity index stays ``rigidity_index`` at every depth).  The
resistance is then read as site investigation reads it: the net cone
resistance ``q_net = q_c - sigma_v0(z)`` and ``N_kt = q_net / s_u(z)`` at the
tip's depth ``z``; in a weightless uniform soil both reduce to the cone
factor ``N_c = (q_c - sigma0) / s_u`` exactly.

The weight and the profile are those of a total-stress Tresca clay
(``material=tresca``, dry): an effective-stress clay's strength already
follows its effective stress.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...constants import GRAVITY
from ...errors import ParameterError
from ...loads import surface_load
from ...mesh.axisymmetric import AxisymmetricMohrCoulomb
from ...particles import Particles
from ..params import Param
from ..soil_profile import (
    CLAY_PARAMS,
    has_profile,
    profile_params,
    strength_profile,
    with_profile,
)
from .cone_geometry import cone_height, shoulder_arc, sizes
from .penetration_soil import with_pore_pressure

__all__ = [
    "GROUND_METRICS",
    "GROUND_PARAMS",
    "check_ground",
    "cone_soil",
    "has_ground",
    "net_curve",
    "start_state",
]

GROUND_PARAMS = [
    Param(
        "rho",
        0.0,
        "kg/m^3",
        "density of the soil (0: weightless); its unit weight gamma = rho g "
        "adds gamma z to sigma0 at depth z (material=tresca, dry)",
        float,
        lo=0.0,
        hi=1.0e5,
    ),
    *profile_params("su"),
    *CLAY_PARAMS,
]

GROUND_METRICS = {
    "cone_factor_nkt": "N_kt = q_net / s_u(z) at steady state (the median over "
    "the last steady_window x D, as cone_factor): q_net = q_c - sigma_v0(z) "
    "at the tip's depth z; equal to cone_factor (which is read the same way)",
    "q_net": "list of [z (m), q_net (Pa), s_u(z) (Pa)] per step: the tip's "
    "depth below the surface, the net cone resistance q_c - sigma0 - gamma z "
    "and the strength there",
}


def has_ground(values: Mapping[str, Any]) -> bool:
    """Whether the soil has weight or a strength profile."""
    return values.get("rho", 0.0) > 0.0 or has_profile(values)


def check_ground(values: Mapping[str, Any]) -> None:
    """Refuse weight or a profile where the scene cannot give them.

    Raises
    ------
    ParameterError
        ``rho`` or ``su_gradient`` with an effective-stress clay or pore
        water, or ``su_gradient`` with an adhesive interface (its adhesion is
        one number).
    """
    if not has_ground(values):
        return
    name = "rho" if values.get("rho", 0.0) > 0.0 else "su_gradient"
    if name == "su_gradient" and values.get("layers") is not None:
        name = "layers"
    if values["material"] != "tresca" or values["drainage"] != "dry":
        raise ParameterError(
            name,
            values[name],
            "0 unless material=tresca and drainage=dry (the weight and the "
            "strength profile are a total-stress clay's)",
        )
    if has_profile(values) and values["interface"] != "smooth":
        raise ParameterError(
            "interface",
            values["interface"],
            "smooth with su_gradient or layers (an adhesion is one number, not "
            "a profile)",
        )


def cone_soil(values: Mapping[str, Any], E: float) -> AxisymmetricMohrCoulomb:
    """The soil: Tresca of strength ``su``, or the effective-stress clay."""
    if values["material"] == "tresca":
        return AxisymmetricMohrCoulomb(E, values["nu"], 1.0, c=values["su"], phi=0.0)
    return AxisymmetricMohrCoulomb(
        E, values["nu"], 1.0, c=values["c"], phi=values["phi"], psi=values["psi"]
    )


def soil_volume(g: dict[str, float]) -> float:
    """Volume of the soil round the embedded cone at the start, m^3.

    A rounded shoulder leaves the ring between its arc and the sharp
    corner to the soil (Pappus: the polygon's first moment about the axis).
    """
    R = g["D"] / 2
    tall = cone_height(g)
    cylinder = math.pi * g["radius"] ** 2 * g["top"]
    shaft = math.pi * R**2 * (g["top"] - g["z_tip"] - tall)
    ring = np.vstack([shoulder_arc(g), shoulder_arc(g | {"round": 0.0})])
    r, z = ring.T
    r1, z1 = np.roll(r, -1), np.roll(z, -1)
    rounded = abs(math.pi / 3 * float(np.sum((r + r1) * (r * z1 - r1 * z))))
    return cylinder - shaft - math.pi * R**2 * tall / 3.0 + rounded


def start_state(
    values: Mapping[str, Any], x: np.ndarray
) -> tuple[Particles, np.ndarray | None]:
    """The particles under ``sigma0`` (and their weight) at ``x``; the surcharge.

    The base is fixed, the far side on rollers; the top carries ``sigma0``
    as a dead load or (``surface=rollers``) is held vertically.  A heavy
    soil's particles share its mass ``rho V`` equally (a step's nodal masses
    are the density times the cell volumes, :attr:`~skfem_npfem.Model.nodal_mass`)
    and start under ``sigma0 + rho g z``.
    """
    g = sizes(values)
    s0, rho = values["sigma0"], values.get("rho", 0.0)
    fixed = np.zeros_like(x, dtype=bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    fixed[np.isclose(x[:, 0], g["radius"]), 0] = True
    top = np.isclose(x[:, 1], g["top"])
    if values["surface"] == "rollers":
        fixed[top, 1] = True  # rollers hold sigma_0 on top
        loads = None
    else:  # sigma_0 on the top as a dead load: the soil is free to heave
        loads = surface_load(x, top, s0, axisymmetric=True)
    stress = np.zeros((x.shape[0], 4))
    if rho > 0.0:
        depth = np.maximum(g["top"] - x[:, 1], 0.0)
        stress[:, :3] = -(s0 + rho * GRAVITY * depth)[:, None]
        mass = np.full(x.shape[0], rho * soil_volume(g) / x.shape[0])
    else:
        stress[:, :3] = -s0
        # Weightless soil: tiny masses (static steps do not use them).
        mass = np.full(x.shape[0], 1e-12)
    particles = Particles.create(x, mass, fixed=fixed, stress=stress, n_walls=2)
    particles = with_profile(
        values, particles, g["top"] - x[:, 1], values["su"], name="su"
    )
    return with_pore_pressure(particles, values), loads


def net_curve(
    records: list, values: Mapping[str, Any]
) -> tuple[list[list[float]], list[list[float]]]:
    """``[w/D, N]`` and ``[z, q_net, s_u(z)]`` of the push's recorded steps.

    ``N = (q_c - sigma0) / s_u`` in a weightless uniform soil, else ``N_kt =
    (q_c - sigma0 - gamma z) / s_u(z)`` at the tip's depth ``z`` below the
    surface (its start ``depth`` plus the push; ``s_u(z)`` of ``su_gradient``
    or ``layers``).
    """
    g = sizes(values)
    D, s0 = g["D"], values["sigma0"]
    area = math.pi * D**2 / 4
    gamma = values.get("rho", 0.0) * GRAVITY
    # A uniform weightless soil: s_u(z) = su and gamma = 0 exactly, so N is
    # (q_c - sigma0) / su to the last bit.
    profile = strength_profile(values, values["su"])
    curve, net = [], []
    for r in records:
        if "cone_force_y" not in r.extra:
            continue
        q_c, w = r.extra["cone_force_y"] / area, -r.extra["cone_y"]
        z = g["depth"] + w
        s_z, q_net = float(profile.at(z)), q_c - s0 - gamma * z
        curve.append([w / D, q_net / s_z])
        net.append([z, q_net, s_z])
    return curve, net
