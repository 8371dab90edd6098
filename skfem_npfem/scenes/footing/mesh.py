"""The strip footing's soil block: a graded mesh and its particles.

The block is ``domain_width * b`` wide and deep, with elements of ``spacing`` under
the footing growing by ``grading`` away from it; the particles carry the
geostatic stress with the at-rest coefficient K0, and those under the footing
move down at unit pseudo-speed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from skfem import MeshTri

from ...errors import ParameterError
from ...mesh.smoothing import nodal_integration
from ...particles import Particles
from ..limits import check_size
from ..soil_profile import with_profile
from .penetration_common import grow_axis, grown_count
from .strip_water import initial_state

#: Default element size under the footing and block size / b (incremental).
DEFAULT_SPACING, DEFAULT_DOMAIN = 0.125, 5.0
#: The same with ``analysis=limit``: one program is cheap, so the default is
#: finer and the block wider (the Prandtl mechanism reaches 16 b at phi = 40).
LIMIT_SPACING, LIMIT_DOMAIN = 0.04, 10.0

__all__ = [
    "DEFAULT_DOMAIN",
    "DEFAULT_SPACING",
    "LIMIT_DOMAIN",
    "LIMIT_SPACING",
    "graded_coordinates",
    "graded_count",
    "resolve_defaults",
    "soil_mesh",
    "soil_particles",
    "unit_weight",
]


def graded_coordinates(b: float, h: float, length: float, ratio: float) -> np.ndarray:
    """Coordinates 0..length: uniform ``h`` up to ``1.5 b``, then growing by ratio."""
    n_fine = max(2, round(1.5 * b / h))
    xs = list(np.linspace(0.0, n_fine * h, n_fine + 1))
    return grow_axis(xs, h, length, ratio)


def graded_count(b: float, h: float, length: float, ratio: float) -> float:
    """Number of :func:`graded_coordinates` (estimated without building them)."""
    n_fine = max(2, round(1.5 * b / h))
    return n_fine + 1 + grown_count(max(length - n_fine * h, 0.0), h, ratio)


def soil_mesh(values: Mapping[str, Any]) -> MeshTri:
    """The graded ``domain_width*b`` square block, surface at its top."""
    b, h = values["width"] / 2, values["spacing"]
    if h > b / 2:
        raise ParameterError("spacing", h, f"at most width/4 = {b / 2:g} m")
    L = values["domain_width"] * b
    n = graded_count(b, h, L, values["grading"])
    check_size(n * n, 2, values, advice="use a larger spacing, grading or domain_width")
    xs = graded_coordinates(b, h, L, values["grading"])
    ys = L - graded_coordinates(b, h, L, values["grading"])[::-1]
    return MeshTri.init_tensor(xs, ys)


def soil_particles(
    values: Mapping[str, Any], mesh: MeshTri, phi: float
) -> tuple[Particles, np.ndarray]:
    """Particles at the mesh nodes with the geostatic stress; the footing mask.

    The footing particles move down at unit pseudo-speed (1 m per unit of
    pseudo-time), so a step's ``dt`` is its settlement increment.
    """
    b, rho = values["width"] / 2, values["rho"]
    L, gamma = values["domain_width"] * b, unit_weight(values)
    ni = nodal_integration(mesh)
    x = mesh.p.T.copy()
    fixed = np.zeros_like(x, dtype=bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    fixed[np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], L), 0] = True
    foot = np.isclose(x[:, 1], L) & (x[:, 0] <= b * (1 + 1e-9))
    fixed[foot, 1] = True
    if values["interface"] == "rough":
        fixed[foot, 0] = True
    K0 = values["K0"] if values["K0"] is not None else 1.0 - math.sin(math.radians(phi))
    stress = np.zeros((x.shape[0], 4))
    sv = -gamma * (L - x[:, 1])
    stress[:, 1] = sv
    stress[:, 0] = stress[:, 2] = K0 * sv
    vp = np.zeros_like(x)
    vp[foot, 1] = -1.0
    particles = Particles.create(
        x, np.maximum(rho, 1e-12) * ni.volumes, stress=stress, fixed=fixed
    )
    particles = initial_state(values, particles.replace(v_prescribed=vp), L, K0)
    particles = with_profile(values, particles, L - x[:, 1], values["c"])
    return particles, foot


def unit_weight(values: Mapping[str, Any]) -> float:
    """Unit weight ``gamma = rho g`` of the soil, N/m^3 (0: weightless)."""
    return values["rho"] * values["gravity"]


def resolve_defaults(values: dict[str, Any]) -> dict[str, Any]:
    """Fill ``spacing`` and ``domain_width`` left at None (they follow ``analysis``)."""
    limit = values.get("analysis") == "limit"
    if values.get("spacing") is None:
        values["spacing"] = LIMIT_SPACING if limit else DEFAULT_SPACING
    if values.get("domain_width") is None:
        values["domain_width"] = LIMIT_DOMAIN if limit else DEFAULT_DOMAIN
    return values
