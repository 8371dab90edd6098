"""A rigid footing pushed down at the crest's edge of a (next to) weightless slope.

References: the same footing's collapse pressure by limit analysis on the
initial lattice (``surcharge_collapse``), which an elastic-plastic push must
reach once the soil under it has yielded; and the exact collapse pressure of
a weightless Tresca soil under a smooth strip at the edge of a slope of angle
``beta``, ``(2 + pi - 2 beta) s_u`` (Prandtl's field with its fan narrowed by
the face), which the rigid footing's limit analysis approaches from above as
the spacing shrinks (docs/validation/slope_loads.md).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from crest_push import EDGE as SLOPE  # demos/studies (tests/conftest.py)

import skfem_npfem as npfem
from skfem_npfem import ParameterError

#: A 2 m slope at 45 deg on the rigid base, gamma H / s_u = 2e-3, a 0.5 m
#: footing at the crest's edge, spacing B/8, pushed 0.2 B (the study's slope).
EDGE = {**SLOPE, "rho": 1.0, "spacing": 0.0625}


def edge_factor(beta: float) -> float:
    """``(2 + pi - 2 beta)``: the smooth strip at the edge, over s_u."""
    return 2.0 + math.pi - 2.0 * math.radians(beta)


KINDS = ("smooth", "rough")


@pytest.fixture(scope="module")
def pushed() -> dict[str, dict]:
    return {
        kind: npfem.run_scene("slope", {**EDGE, "surcharge_footing": kind})["metrics"]
        for kind in KINDS
    }


@pytest.mark.parametrize("kind", KINDS)
def test_the_pushed_footing_reaches_its_limit_analysis_load(pushed, kind):
    # Measured push / limit analysis at B/8: 1.021 smooth, 0.984 rough (at
    # B/16: 1.008, 1.029).
    m = pushed[kind]
    assert m["push_capacity_ratio"] == pytest.approx(1.0, abs=0.05)
    assert m["push_capacity"] == pytest.approx(
        m["push_capacity_ratio"] * m["surcharge_collapse"], rel=1e-12
    )


@pytest.mark.parametrize("kind", KINDS)
def test_the_footing_moves_a_quarter_spacing_per_step(pushed, kind):
    # Kinematics: the footing's settlement is prescribed (a step the solver
    # fails is halved and retried, so a step may be shorter, never longer).
    w = np.array(pushed[kind]["push_curve"])[:, 0]
    assert w[-1] == pytest.approx(EDGE["push_depth"], rel=1e-9)
    assert w[0] == pytest.approx(0.25 * EDGE["spacing"], rel=1e-9)
    assert np.all(np.diff(w) > 0)
    assert np.all(np.diff(w) <= 0.25 * EDGE["spacing"] * (1 + 1e-9))


def test_the_smooth_push_against_the_exact_edge_load(pushed):
    # Measured +8.9 % at B/8 and +4.0 % at B/16: the rigid footing's edges
    # concentrate the shear, so it converges from above.
    factor = pushed["smooth"]["push_capacity"] / EDGE["c"]
    assert edge_factor(45.0) < factor < 1.12 * edge_factor(45.0)


def test_a_rough_footing_carries_more_than_a_smooth_one(pushed):
    # Held sideways, the rough footing cannot slide toward the face: 4.20
    # against 3.89 s_u at B/8.
    assert pushed["rough"]["push_capacity"] > 1.03 * pushed["smooth"]["push_capacity"]


@pytest.mark.parametrize(
    ("over", "name"),
    [
        ({"surcharge_footing": "flexible"}, "surcharge_footing"),
        ({"surcharge": 1.0e4}, "surcharge"),
        ({"runout": True}, "runout"),
        ({"analysis": "limit"}, "analysis"),
        ({"kh": 0.1}, "kh"),
        ({"surcharge_width": None}, "surcharge_width"),
        ({"push_depth": 3.0}, "push_depth"),
        ({"water_level": 1.0}, "push_depth"),  # the push runs dry
    ],
)
def test_a_push_the_scene_cannot_model_is_refused(over, name):
    values = {**EDGE, "surcharge_footing": "smooth", **over}
    with pytest.raises(ParameterError) as err:
        npfem.run_scene("slope", values)
    assert err.value.name == name


def test_a_push_speed_without_a_push_is_warned_about():
    values = {
        **EDGE,
        "push_depth": 0.0,
        "push_speed": 0.1,
        "analysis": "limit",
        "refine": "none",
    }
    with pytest.warns(UserWarning, match="push_speed"):
        npfem.run_scene("slope", values)


def test_a_push_on_a_section_with_water_is_refused(tmp_path):
    # The push runs dry: a cross-section file's water line (no water_level
    # parameter to refuse up front) is refused when the run is built.
    section = {
        "materials": {"clay": {"c": 1.0e4, "phi": 0.0, "rho": 2000.0}},
        "regions": [
            {
                "material": "clay",
                "polygon": [[0, 0], [5, 0], [5, 1], [3, 3], [0, 3], [0, 0]],
            }
        ],
        "supports": {"base": "fixed", "sides": "rollers"},
        "water": [[0, 1], [5, 1]],
    }
    path = tmp_path / "wet.json"
    path.write_text(json.dumps(section))
    values = {
        "geometry": str(path),
        "spacing": 0.25,
        "surcharge_width": 1.0,
        "surcharge_footing": "smooth",
        "push_depth": 0.1,
    }
    with pytest.raises(ParameterError) as err:
        npfem.run_scene("slope", values)
    assert err.value.name == "push_depth"
    assert "dry" in str(err.value)
