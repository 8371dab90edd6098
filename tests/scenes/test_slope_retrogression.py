"""A sensitive-clay slope on a rigid base: the floor, the retrogression and its blocks.

``foundation_depth = 0`` stands the parametric slope on its fixed base, and the
run-out spreads beyond the toe on that base as a rigid floor
(``floor_friction``).  The ``blocks`` metric counts the intact groups of the
failed mass (:func:`~skfem_npfem.scenes.slope.runout.intact_blocks`).
"""

from __future__ import annotations

import meshio
import numpy as np
import pytest

import skfem_npfem as npfem
from skfem_npfem import ParameterError
from skfem_npfem.scenes import get_scene
from skfem_npfem.scenes.slope.runout import intact_blocks


def square(x0: float, n: int, h: float) -> np.ndarray:
    g = np.arange(n) * h
    X, Y = np.meshgrid(x0 + g, g)
    return np.column_stack([X.ravel(), Y.ravel()])


def test_intact_blocks_counts_separate_groups_by_area():
    h = 0.1
    x = np.vstack([square(0.0, 4, h), square(1.0, 4, h), square(2.0, 2, h)])
    area = np.full(len(x), h * h)
    every = np.ones(len(x), bool)
    # Two 4 x 4 groups (0.16 m^2) and one 2 x 2 (0.04 m^2), 0.7 m apart.
    assert intact_blocks(x, area, every, h, 0.1) == 2
    assert intact_blocks(x, area, every, h, 0.01) == 3
    # Not candidates: not counted; a bridge of particles joins two groups.
    assert intact_blocks(x, area, np.zeros(len(x), bool), h, 0.01) == 0
    bridge = np.column_stack([np.arange(0.4, 1.0, h), np.zeros(6)])
    xb = np.vstack([x, bridge])
    ab = np.full(len(xb), h * h)
    assert intact_blocks(xb, ab, np.ones(len(xb), bool), h, 0.01) == 2


@pytest.fixture(scope="module")
def slide(tmp_path_factory) -> dict:
    # A 2 m, 45 deg sensitive clay slope (F = 0.96 at H/8: it fails as it is)
    # on the rigid base, for its first 1.5 s.
    over = {
        "material": "tresca", "c": 6.0e3, "rho": 2000.0, "E": 1.0e7,
        "height": 2.0, "angle": 45.0, "foundation_depth": 0.0,
        "crest_length": 6.0, "toe_length": 8.0, "spacing": 0.25,
        "runout": True, "reduction": 1.0, "sensitivity": 10.0, "ductility": 1.0,
        "t_end": 1.5,
    }  # fmt: skip
    out = tmp_path_factory.mktemp("slide")
    res = npfem.run_scene("slope", over, out=out)
    last = meshio.read(sorted(out.glob("result_*.vtu"))[-1])
    return {
        **res,
        "lowest": float(last.points[:, 1].min()),
        "factor": last.point_data["strength_law_factor"],
    }


def test_the_run_out_spreads_on_the_rigid_floor(slide):
    m = slide["metrics"]
    # The toe advances on the floor and no particle goes below it (the floor
    # is the base y = 0); mass is conserved exactly.
    assert m["runout"] > 0.5
    assert slide["lowest"] >= 0.0
    assert m["mass_change"] == 0.0
    assert m["retrogression"] > 0.0
    assert isinstance(m["blocks"], int)


def test_the_softened_strength_is_written(slide):
    # The clay law's factor per particle (softening, no rate law here): between
    # the remoulded 1 / S_t and the intact 1, and softened where it slid.
    f = slide["factor"]
    assert f.min() >= 0.1 - 1e-12 and f.max() <= 1.0
    assert f.min() < 0.5


def test_blocks_is_null_without_softening():
    m = npfem.run_scene(
        "slope", {"analysis": "limit", "refine": "none", "spacing": 2.0}
    )["metrics"]
    assert m["blocks"] is None


def test_bad_floor_friction_is_refused():
    sc = get_scene("slope")
    with pytest.raises(ParameterError, match="floor_friction"):
        sc.resolve({"floor_friction": 95.0})
