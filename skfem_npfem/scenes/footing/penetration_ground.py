"""The ground of the footing pushed deep: its lattice, its soil, its weight.

By default the soil is a weightless layer (a Tresca clay, or the
effective-stress clay of :mod:`~.penetration_soil`).  ``rho`` gives a
Tresca clay its unit weight ``gamma = rho g``: the particles carry the masses
``rho V`` of their smoothing cells, start under the isotropic stress
``gamma z`` at depth ``z`` (in equilibrium with their weight) and gravity acts
in every step.  The footing then also lifts the soil it displaces: the net
resistance ``q - gamma w`` over the strength at the footing's depth
(``net_curve``) is what compares with a weightless clay's ``q / s_u``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from skfem import MeshTri

from ...constants import GRAVITY
from ...materials import Material, MohrCoulomb, Tresca
from ...mesh.smoothing import nodal_integration
from ...particles import Particles
from ..params import Param
from ..soil_profile import strength_profile
from .penetration_common import graded_axis, lattice_gap

__all__ = [
    "NET_METRICS",
    "WEIGHT",
    "footing_soil",
    "geometry",
    "net_curve",
    "penetration_curve",
    "soil",
]

WEIGHT = Param(
    "rho",
    0.0,
    "kg/m^3",
    "density of the soil (0: weightless); its unit weight gamma = rho g, with "
    "the geostatic stress gamma z (material=tresca, dry)",
    float,
    lo=0.0,
    hi=1.0e5,
)

NET_METRICS = {
    "net_curve": "list of [w/B, (q - gamma w) / s_u(w)] per step: the "
    "resistance less the weight of the soil the footing has displaced, over "
    "the strength at the footing's depth (q/s_u of curve in a weightless "
    "uniform soil)",
}


def geometry(values: Mapping[str, Any]) -> tuple[float, float, float, float]:
    """``(B, half width of the soil, depth of the soil, final penetration)``."""
    B, w = values["width"], values["penetration"]
    return (
        B,
        values["domain_width"] * B / 2,
        values["domain_depth"] * B,
        B if w is None else w,
    )


def soil(values: Mapping[str, Any]) -> tuple[Particles, np.ndarray, MeshTri]:
    """The graded lattice as particles, and each particle's spacing."""
    B, half, depth, w = geometry(values)
    h, ratio = values["spacing"], values["grading"]
    xs = graded_axis(B / 2 + B, h, half, ratio)
    ys = depth - graded_axis(w + B, h, depth, ratio)[::-1]
    mesh = MeshTri.init_tensor(xs, ys)
    x = mesh.p.T.copy()
    fixed = np.zeros_like(x, dtype=bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    fixed[np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], half), 0] = True
    volumes = nodal_integration(mesh).volumes
    rho = values.get("rho", 0.0)
    if rho > 0.0:
        stress = np.zeros((x.shape[0], 4))
        stress[:, :3] = -(rho * GRAVITY * (depth - x[:, 1]))[:, None]
        p = Particles.create(x, rho * volumes, fixed=fixed, stress=stress, n_walls=1)
    else:
        # Weightless soil: tiny masses (static steps do not use them).
        p = Particles.create(x, 1e-12 * volumes, fixed=fixed, n_walls=1)
    return p, lattice_gap(x, xs, ys), mesh


def footing_soil(values: Mapping[str, Any]) -> Material:
    """Tresca of strength ``su``, or the effective-stress Mohr-Coulomb clay."""
    E, nu = values["E"], values["nu"]
    if values["material"] == "tresca":
        return Tresca(E, nu, 0.0, c=values["su"])
    return MohrCoulomb(E, nu, 0.0, c=values["c"], phi=values["phi"], psi=values["psi"])


def penetration_curve(records, B: float, su: float) -> list[list[float]]:
    """``[w/B, q/s_u]`` of every step (half model: q = force / (B/2))."""
    return [
        [-r.extra["footing_y"] / B, r.extra["footing_force_y"] / (B / 2) / su]
        for r in records
        if "footing_force_y" in r.extra
    ]


def net_curve(curve: list[list[float]], values: Mapping[str, Any]) -> list[list[float]]:
    """``[w/B, (q - gamma w) / s_u(w)]`` from :func:`penetration_curve`'s."""
    B, su = values["width"], values["su"]
    gamma = values.get("rho", 0.0) * GRAVITY
    profile = strength_profile(values, su)
    return [[w, (n * su - gamma * w * B) / float(profile.at(w * B))] for w, n in curve]
