"""Particle counts of the column geometries, estimated before anything is built.

The up-front size check (:func:`~skfem_npfem.scenes.limits.check_size`, the
memory model of every scene) needs the particle count of a run before its
lattice exists -- a spacing of 1e-5 m would otherwise allocate the lattice
first.  :func:`lattice_particles` counts the lattices of
:mod:`.cylinder` and :mod:`.box_column` from their sizes alone.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["lattice_particles"]


def lattice_particles(
    geometry: str, values: Mapping[str, Any], spacing: float
) -> float:
    """Particles of a column's lattice (estimated without building it).

    ``values`` holds ``radius`` and ``height`` (cylindrical geometries) or
    ``half_width``, ``aspect``, ``depth`` and ``symmetric`` (box).  The quarter
    cylinder's count per layer is the quarter disc's area in lattice cells plus
    one edge and the centre, ``pi n^2 / 4 + n + 1`` (Gauss's circle problem:
    273.5 for ``n = 18`` spacings over the radius, 271 counted).

    Examples
    --------
    >>> lattice_particles("axisymmetric", {"radius": 0.039, "height": 0.078}, 0.0039)
    231.0
    """
    h = float(spacing)
    if geometry in ("axisymmetric", "quarter-cylinder"):
        nr = max(1.0, round(values["radius"] / h))
        layers = max(1.0, round(values["height"] / h)) + 1.0
        if geometry == "axisymmetric":
            return (nr + 1.0) * layers
        return (math.pi / 4.0 * nr * nr + nr + 1.0) * layers
    width = values["half_width"] * (1.0 if values["symmetric"] else 2.0)
    height = values["aspect"] * values["half_width"]
    per = [max(1.0, round(v / h)) + 1.0 for v in (width, values["depth"], height)]
    return per[0] * per[1] * per[2]
