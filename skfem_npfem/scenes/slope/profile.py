"""A parametric slope's strength that grows with depth below its ground surface.

``su_gradient`` (or ``layers``) gives each particle the strength of its depth
below the slope's surface right above it: the crest, the face or the toe
(:func:`ground_height`), the profile of a normally consolidated clay whose
surface is the slope's.  The factors go on the particles, so the factor of
safety, the critical ``k_h``, a crest surcharge's collapse and the run-out
all read them (:mod:`~skfem_npfem.scenes.soil_profile`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...errors import ParameterError
from ..soil_profile import has_profile
from ..soil_profile import profile_factors as soil_profile_factors

__all__ = ["check_profile", "ground_height", "profile_factors"]


def ground_height(values: Mapping[str, Any], x: np.ndarray) -> np.ndarray:
    """The parametric slope's surface above each ``x``: crest, face or toe, m."""
    H, D = values["height"], values["foundation_depth"]
    crest = values["crest_length"]
    if values["angle"] >= 90.0:
        return np.where(np.asarray(x) <= crest, D + H, D)
    run = H / math.tan(math.radians(values["angle"]))
    return D + H - H * np.clip((np.asarray(x) - crest) / run, 0.0, 1.0)


def check_profile(values: Mapping[str, Any]) -> None:
    """Refuse a profile on a cross-section file (its regions carry strengths)."""
    if has_profile(values) and values["geometry"]:
        name = "layers" if values.get("layers") is not None else "su_gradient"
        raise ParameterError(
            name,
            values[name],
            "left out with geometry (a cross-section's regions carry their own "
            "strengths: draw the layers as regions)",
        )


def profile_factors(
    values: Mapping[str, Any], pts: np.ndarray
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The strength and stiffness factors of particles at ``pts`` (None: uniform)."""
    if not has_profile(values):  # (a cross-section file has no ground_height)
        return None, None
    check_profile(values)
    depth = ground_height(values, pts[:, 0]) - pts[:, 1]
    return soil_profile_factors(values, depth, values["c"])
