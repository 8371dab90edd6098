"""Buried slivers in the 3D column: meshed, the second step's stresses stay smooth.

One step after the release the quarter cylinder's cubic lattice is nearly, not
exactly, co-spherical cube by cube, and its Delaunay triangulation puts flat
slivers between cubes split along different face diagonals (docs/theory.md,
"Other guards").  Meshed (``buried_slivers=keep``, the 3D default), the mesh
stays conforming and the second step's vertical stress is as smooth as the
first's; dropped, the kept tetrahedra are non-conforming and every cube face
next to a sliver is a surface to the stress-roughness measure, which then finds
no interior particle at all.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skfem_npfem.scenes import get_scene

R0 = 0.039


def _two_steps(buried_slivers: str) -> list[float]:
    s = get_scene("column-collapse").run(
        {
            "geometry": "quarter-cylinder",
            "spacing": R0 / 8,
            "accuracy": "fast",
            "dt": 4e-3,
            "t_end": 8e-3,
            "rest_fraction": 0.0,
            "threads": 1,
            "buried_slivers": buried_slivers,
        },
        progress=False,
    )
    return [h["stress_roughness"] for h in s["history"]]


@pytest.mark.filterwarnings("ignore:column-collapse")
def test_second_step_is_smooth_with_buried_slivers_meshed() -> None:
    kept = _two_steps("keep")
    dropped = _two_steps("drop")
    # The first step's mesh is the exact lattice's: no slivers, same R.
    assert kept[0] == pytest.approx(dropped[0], rel=1e-9)
    # The reference measure's scale: a smooth field remeshed gives ~0.06;
    # measured 0.021 and 0.044 for the two steps.
    assert np.all(np.isfinite(kept)) and max(kept) <= 0.10
    # Dropped, the second step's mesh leaves the measure no interior particle.
    assert math.isnan(dropped[1])


def test_buried_slivers_is_refused_in_axisymmetry() -> None:
    from skfem_npfem.errors import ParameterError

    with pytest.raises(ParameterError, match="buried_slivers"):
        get_scene("column-collapse").run(
            {"geometry": "axisymmetric", "buried_slivers": "keep"}, progress=False
        )
