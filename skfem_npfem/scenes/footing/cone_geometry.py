"""Where the cone-penetration scene's cone and particles start.

The geometry of :mod:`~skfem_npfem.scenes.footing.cone`: its lengths, the
graded lattice round the tip's path, the cone with its shaft and the checks
made before anything is built.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...boundary import RigidBody
from ...errors import ParameterError
from ..limits import check_size
from ..params import Param
from .penetration_common import (
    axis_count,
    graded_axis,
    interface_adhesion,
    lattice_gap,
    step_dt,
)

__all__ = [
    "APEX",
    "SHOULDER_PARAM",
    "check",
    "cone_body",
    "cone_height",
    "cone_outline",
    "fine_window",
    "heights",
    "shoulder_arc",
    "sizes",
    "soil_points",
]

#: Apex angle of the standard cone, degrees.
APEX = 60.0

#: Straight pieces of a rounded shoulder's arc (7.5 degrees each).
ARC_PIECES = 4

SHOULDER_PARAM = Param(
    "shoulder_round",
    0.0,
    "-",
    "radius of the cone's shoulder (where the face meets the shaft), in "
    "spacings: 0 keeps the standard cone's sharp corner; r > 0 rounds it to an "
    "arc tangent to the face and the shaft (a regularisation of the corner that "
    "vanishes with the spacing: the soil flowing round a sharp corner gives way "
    "in single steps)",
    float,
    lo=0.0,
    hi=4.0,
)


def sizes(values: Mapping[str, Any]) -> dict[str, float]:
    """Lengths of the set-up, m: D, spacing, push, tip depth, soil, radius, round."""
    D = values["diameter"]
    h = values["spacing"] if values["spacing"] is not None else D / 12
    w = values["penetration"] if values["penetration"] is not None else 6 * D
    depth = values["depth"] if values["depth"] is not None else 10 * D
    z_tip = values["domain_below"] * D + w  # the tip's height at time 0
    return {
        "D": D,
        "h": h,
        "w": w,
        "depth": depth,
        "z_tip": z_tip,
        "top": z_tip + depth,
        "radius": values["domain_radius"] * D,
        "round": values["shoulder_round"] * h,
    }


def cone_height(g: dict[str, float]) -> float:
    """Height of the cone from its tip to its (sharp) shoulder, m: R / tan 30°."""
    return g["D"] / 2 / math.tan(math.radians(APEX / 2))


def shoulder_arc(g: dict[str, float]) -> np.ndarray:
    """The cone's shoulder at time 0: its corner (1, 2), or its rounded arc.

    With a radius ``r = g["round"] > 0`` the corner is replaced by
    :data:`ARC_PIECES` + 1 points on the circle of radius ``r`` tangent to
    the face and to the shaft, from the face's tangent point, ``r tan(15°)``
    below the corner along the face, to the shaft's, as far above it.

    Examples
    --------
    >>> g = {"D": 2.0, "z_tip": 0.0, "round": 0.0}
    >>> shoulder_arc(g).round(4).tolist()
    [[1.0, 1.7321]]
    >>> arc = shoulder_arc(g | {"round": 0.5})
    >>> arc.shape, arc[-1].round(4).tolist()
    ((5, 2), [1.0, 1.866])
    """
    R, half = g["D"] / 2, math.radians(APEX / 2)
    corner = np.array([R, g["z_tip"] + cone_height(g)])
    r = g["round"]
    if r <= 0:
        return corner[None]
    along = np.array([math.sin(half), math.cos(half)])  # the face, tip to corner
    outward = np.array([math.cos(half), -math.sin(half)])  # the face's normal
    centre = corner - r * math.tan(half / 2) * along - r * outward
    theta = np.linspace(-half, 0.0, ARC_PIECES + 1)
    return centre + r * np.stack([np.cos(theta), np.sin(theta)], axis=1)


def fine_window(g: dict[str, float]) -> tuple[float, float]:
    """Heights between which the lattice has the fine spacing."""
    return max(g["z_tip"] - g["w"] - 2 * g["D"], 0.0), min(
        g["z_tip"] + 2 * g["D"], g["top"]
    )


def heights(g: dict[str, float], ratio: float) -> np.ndarray:
    """Lattice heights: fine around the tip's path, growing below and above."""
    lo, hi = fine_window(g)
    h = g["h"]
    fine = np.linspace(lo, hi, max(1, math.ceil((hi - lo) / h - 1e-9)) + 1)
    below = lo - graded_axis(h, h, lo, ratio)[::-1] if lo > 0 else np.zeros(0)
    above = hi + graded_axis(h, h, g["top"] - hi, ratio) if g["top"] > hi else fine
    return np.unique(np.concatenate([below, fine, above]).round(12))


def check(values: Mapping[str, Any]) -> float:
    """Refuse bad combinations before anything is built; return ``dt``."""
    g = sizes(values)
    D, h = g["D"], g["h"]
    if h > D / 4:
        raise ParameterError("spacing", h, f"at most D/4 = {D / 4:g} m")
    if g["depth"] < 2 * D:
        raise ParameterError(
            "depth",
            g["depth"],
            f"at least 2 D = {2 * D:g} m: the cone starts embedded, its tip "
            "this deep below the surface",
        )
    dt = step_dt(values, h, 0.5, "cone")
    lo, hi = fine_window(g)
    nr = axis_count(1.5 * D, h, g["radius"], values["grading"])
    nz = (hi - lo) / h + axis_count(h, h, lo, values["grading"])
    nz += axis_count(h, h, g["top"] - hi, values["grading"])
    check_size(nr * nz, 2, values, advice="use a larger spacing or grading")
    return dt


def cone_outline(g: dict[str, float]) -> np.ndarray:
    """The cone with its shaft at time 0 (m, 2): tip, shoulder, shaft's top, axis.

    The shaft reaches a diameter above the soil's top at the end of the push.
    """
    top = g["top"] + g["w"] + g["D"]
    R = g["D"] / 2
    return np.array([[0.0, g["z_tip"]], *shoulder_arc(g), [R, top], [0.0, top]])


def cone_body(values: Mapping[str, Any]) -> RigidBody:
    """The cone with its shaft at time 0, wished in place, moving down."""
    g = sizes(values)
    outline = cone_outline(g)
    adhesion = interface_adhesion(values)
    if adhesion > 0:  # on the face and its rounded end only; the shaft is smooth
        adhesion = [adhesion] * (outline.shape[0] - 3) + [0.0, 0.0, 0.0]
    return RigidBody(
        outline,
        velocity=[0.0, -values["speed"]],
        adhesion=adhesion,
        name="cone",
        reference=[0.0, g["z_tip"]],
    )


def soil_points(values: Mapping[str, Any], body: RigidBody) -> tuple[np.ndarray, ...]:
    """Particle positions round the cone and each one's lattice spacing.

    A graded lattice without the points inside the cone or closer to it
    than half their spacing, plus points on the cone's face and shaft (the
    soil starts in contact with the cone: an unsupported cavity would close
    plastically under sigma_0; on a rounded shoulder the face's points
    inside the arc are moved onto it).
    """
    g = sizes(values)
    rs = graded_axis(1.5 * g["D"], g["h"], g["radius"], values["grading"])
    zs = heights(g, values["grading"])
    R, z_tip, h = g["D"] / 2, g["z_tip"], g["h"]
    shoulder = z_tip + cone_height(g)
    n_face = max(2, math.ceil(math.hypot(R, shoulder - z_tip) / h - 1e-9))
    s = np.linspace(0.0, 1.0, n_face + 1)
    face = np.stack([s * R, z_tip + s * (shoulder - z_tip)], axis=1)
    shaft_z = zs[zs > shoulder + 0.5 * h]
    shaft = np.stack([np.full(shaft_z.size, R), shaft_z], axis=1)
    rr, zz = np.meshgrid(rs, zs, indexing="ij")
    lattice = np.stack([rr.ravel(), zz.ravel()], axis=1)
    gap = lattice_gap(lattice, rs, zs)
    dist, _, _ = body.signed_distance(lattice, 0.0)
    keep = dist > 0.5 * gap
    if g["round"] > 0:  # the face's points in the rounded corner onto the arc
        d, _, on = body.signed_distance(face, 0.0)
        face[d < 0] = on[d < 0]
    x = np.concatenate([face, shaft, lattice[keep]])
    return x, lattice_gap(x, rs, zs)
