"""A Tresca slope whose strength grows with depth below its surface.

The strength reduction of a purely cohesive soil is linear in the strength
field: doubling ``c`` and ``su_gradient`` together doubles the factor of
safety (to the iteration's tolerance), which checks that the reduction reads
every particle's factor.
"""

import json

import pytest

from skfem_npfem import ParameterError
from skfem_npfem.scenes import get_scene, run_scene

SCENE = "slope"
CLAY = {
    "analysis": "limit",
    "refine": "none",
    "material": "tresca",
    "c": 2.0e4,
    "angle": 30.0,
}


def fos(over: dict) -> dict:
    return run_scene(SCENE, {**CLAY, **over})["metrics"]


def test_factor_of_safety_is_linear_in_the_strength_profile():
    one = fos({"su_gradient": 2.0e3})
    two = fos({"c": 4.0e4, "su_gradient": 4.0e3})
    assert two["factor_of_safety"] == pytest.approx(
        2 * one["factor_of_safety"], rel=2e-4
    )
    uniform = fos({})
    # Stronger soil below: a higher F (measured 1.019 against 0.616) and a
    # critical k_h, which the uniform slope, that gravity alone brings down
    # (F < 1), does not have.
    assert one["factor_of_safety"] > 1.5 * uniform["factor_of_safety"]
    assert one["critical_kh"] > 0.0
    assert uniform["critical_kh"] is None
    assert uniform["retrogression"] is None


def test_one_layer_is_the_uniform_slope():
    uniform = fos({})
    layered = fos({"layers": "[[0, 20000]]"})
    assert layered["factor_of_safety"] == uniform["factor_of_safety"]


def test_a_cross_section_file_refuses_a_profile(tmp_path):
    section = {
        "materials": {"clay": {"c": 2e4, "phi": 0, "rho": 1900}},
        "regions": [
            {
                "material": "clay",
                "polygon": [[0, 0], [20, 0], [20, 5], [10, 10], [0, 10], [0, 0]],
            }
        ],
        "supports": {"base": "fixed", "sides": "rollers"},
    }
    path = tmp_path / "s.json"
    path.write_text(json.dumps(section))
    sc = get_scene(SCENE)
    over = {
        "analysis": "limit",
        "refine": "none",
        "geometry": str(path),
        "su_gradient": 1e3,
    }
    with pytest.raises(ParameterError, match="su_gradient"):
        sc.build(sc.resolve(over))


@pytest.mark.slow
def test_a_sensitive_clay_slide_travels_farther():
    # H/10, the run-out of the Tresca slope with s_u growing with depth (F =
    # 1.02, strengths divided by 1.5 F); about 2.5 minutes.  Remoulded to a
    # fifth (S_t = 5, xi_95 = 2) the slide travels far (measured 90 m against
    # 5.3 m) and moves more soil (422 against 350 m^3/m); mass is conserved
    # exactly in both; the failure reaches behind the crest.
    over = {**CLAY, "analysis": "incremental", "su_gradient": 2.0e3, "runout": True}
    intact = run_scene(SCENE, over)["metrics"]
    soft = run_scene(SCENE, {**over, "sensitivity": 5.0, "ductility": 2.0})["metrics"]
    assert soft["runout"] > 3 * intact["runout"]
    assert soft["moved_volume"] > intact["moved_volume"]
    for m in (intact, soft):
        assert m["mass_change"] == 0.0
        assert 0.0 < m["retrogression"] <= 15.0
