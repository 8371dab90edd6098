"""The ``slope`` scene with pore water.

References: a submerged slope (hydrostatic water above the crest) stands as
the dry slope of the buoyant unit weight ``gamma' = gamma_sat - gamma_w``
(the water's force on the skeleton is the buoyancy); so a cohesionless one has
the infinite-slope factor of safety ``tan(phi')/tan(beta)``, and the 2:1
slope of Griffiths & Lane (1999, example 1) with ``c'/(gamma' H) = 0.05``,
``phi' = 20`` deg has Bishop & Morgenstern's F = 1.38.  Undrained, the
strengths ``s_u = c' cos(phi') + s'_0 sin(phi')`` of ``K0`` stresses are
known in closed form.
"""

from __future__ import annotations

import json
import math

import pytest
from scenes.test_slope import BISHOP_MORGENSTERN_FOS, FOS_TOL, GRIFFITHS_LANE, SAND

import skfem_npfem as npfem
from skfem_npfem.errors import ParameterError

pytestmark = pytest.mark.filterwarnings("ignore:slope. the factor of safety")

#: gamma_w = 10 kN/m^3: gamma' = gamma_sat / 2 for gamma_sat = 20 kN/m^3.
RHO_W = 1.0e4 / 9.81


def test_submerged_cohesionless_slope_is_the_infinite_slope_value():
    """Water over the crest: tan(phi')/tan(beta) within the dry check's 5 %."""
    ref = math.tan(math.radians(35.0)) / math.tan(math.radians(30.0))
    wet = npfem.run_scene("slope", {**SAND, "water_level": 6.0})["metrics"]
    assert abs(wet["factor_of_safety"] / ref - 1) < 0.05


def test_submerged_griffiths_lane_slope_has_the_buoyant_chart_value():
    """c'/(gamma' H) = 0.05 submerged: Bishop & Morgenstern's 1.38 within 3 %."""
    gamma_sat = GRIFFITHS_LANE["rho"] * 9.81
    c = 0.05 * (gamma_sat - RHO_W * 9.81) * GRIFFITHS_LANE["height"]
    wet = {**GRIFFITHS_LANE, "c": c, "water_level": 12.0, "rho_w": RHO_W}
    m = npfem.run_scene("slope", wet)["metrics"]
    assert abs(m["factor_of_safety"] / BISHOP_MORGENSTERN_FOS - 1) < FOS_TOL


def test_undrained_strengths_of_k0_stresses():
    """s_u from c' cos(phi') at the surface to that plus sin(phi') (1 + K0)/2
    gamma' (D + H) at the base under the crest."""
    K0, c = 0.5, 2.0e3
    o = {**SAND, "c": c, "water_level": 6.0, "drainage": "undrained"}
    m = npfem.run_scene("slope", {**o, "initial_stress": "k0", "K0": K0})["metrics"]
    f = math.radians(35.0)
    gamma_b = (2000.0 - 1000.0) * 9.81  # the scene's rho and rho_w, g
    deepest = c * math.cos(f) + math.sin(f) * (1 + K0) / 2 * gamma_b * 5.0
    assert m["undrained_strength_min"] == pytest.approx(c * math.cos(f), rel=1e-9)
    assert m["undrained_strength_max"] == pytest.approx(deepest, rel=1e-9)
    assert m["factor_of_safety"] > 0


def test_dry_slope_reports_no_water():
    m = npfem.run_scene("slope", SAND)["metrics"]
    assert "undrained_strength_min" not in m


def test_drained_without_a_water_level_is_refused():
    with pytest.raises(ParameterError, match="drainage"):
        npfem.run_scene("slope", {**SAND, "drainage": "drained"})


@pytest.mark.slow
def test_submerged_griffiths_lane_slope_converges():
    """At H/20 the submerged slope is within 1 % of 1.38 (measured +0.65 %)."""
    gamma_sat = GRIFFITHS_LANE["rho"] * 9.81
    c = 0.05 * (gamma_sat - RHO_W * 9.81) * GRIFFITHS_LANE["height"]
    wet = {**GRIFFITHS_LANE, "c": c, "water_level": 12.0, "rho_w": RHO_W}
    m = npfem.run_scene("slope", {**wet, "spacing": 0.5})["metrics"]
    assert abs(m["factor_of_safety"] / BISHOP_MORGENSTERN_FOS - 1) < 0.01


def test_a_section_files_water_line_makes_the_slope_wet(tmp_path):
    """A phreatic line over the crest in the file: tan(phi')/tan(beta) within 5 %."""
    x_toe = 6.0 + 4.0 / math.tan(math.radians(30.0))
    W = x_toe + 10.0
    polygon = [[0, 0], [W, 0], [W, 1], [x_toe, 1], [6, 5], [0, 5], [0, 0]]
    section = {
        "materials": {"sand": {"c": 0.0, "phi": 35.0, "rho": 2000.0}},
        "regions": [{"material": "sand", "polygon": polygon}],
        "supports": {"base": "fixed", "sides": "rollers"},
        "water": [[0, 6], [W, 6]],
    }
    path = tmp_path / "submerged.json"
    path.write_text(json.dumps(section))
    s = npfem.run_scene(
        "slope",
        {"geometry": str(path), "analysis": "limit", "refine": "none", "spacing": 0.4},
    )
    assert s["parameters"]["drainage"] == "drained"
    assert s["metrics"]["pore_pressure_max"] == pytest.approx(1000.0 * 9.81 * 6.0)
    ref = math.tan(math.radians(35.0)) / math.tan(math.radians(30.0))
    assert abs(s["metrics"]["factor_of_safety"] / ref - 1) < 0.05
