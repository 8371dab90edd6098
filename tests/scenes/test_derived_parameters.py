"""The summary's ``parameters`` records the values used for derived defaults.

A parameter left at its default ``None`` ("derived") is filled once, before
the run is built, by the documented rule of its help text; the summary (and
``scene.json``) must then show that value, not null.
"""

from __future__ import annotations

import math
import warnings

import pytest

from skfem_npfem.constants import GRAVITY
from skfem_npfem.scenes import get_scene, run_scene


def _values(scene: str, overrides: dict) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return dict(get_scene(scene).resolve(overrides))


def test_slope_sizes_are_recorded():
    v = _values("slope", {"height": 8.0})
    assert v["crest_length"] == 1.5 * 8.0 and v["toe_length"] == 2.5 * 8.0


def test_strip_footing_stepping_and_soil_are_recorded():
    v = _values("strip-footing", {"material": "mohr-coulomb", "phi": 30.0})
    assert v["K0"] == pytest.approx(0.5) and v["psi"] == 30.0
    b = v["width"] / 2  # settlement: 100 (c + gamma b) b / E, weightless soil
    assert v["settlement"] == pytest.approx(100 * v["c"] * b / v["E"])
    assert v["plateau_tol"] == 1e-3
    assert v["max_settlement"] == pytest.approx(100 * v["settlement"])
    assert _values("strip-footing", {"large_deformation": True})["plateau_tol"] == 0


@pytest.mark.parametrize("geometry", ["plane-strain", "axisymmetric", "box"])
def test_column_defaults_are_recorded(geometry):
    v = _values("column-collapse", {"geometry": geometry, "phi": 25.0})
    assert v["K0"] == pytest.approx(1 - math.sin(math.radians(25.0)))
    assert v["floor_friction"] == 25.0
    H0 = v["height"] if geometry == "axisymmetric" else v["aspect"] * v["half_width"]
    assert v["min_time"] == pytest.approx(2 * math.sqrt(H0 / GRAVITY))


def test_penetration_defaults_are_recorded():
    v = _values("footing-penetration", {})
    assert v["penetration"] == v["width"]
    assert v["dt"] == pytest.approx(v["spacing"] / 4 / v["speed"])
    v = _values("cone-penetration", {})
    D = v["diameter"]
    assert v["spacing"] == pytest.approx(D / 12)
    assert v["penetration"] == pytest.approx(6 * D)
    assert v["depth"] == pytest.approx(10 * D)
    assert v["dt"] == pytest.approx(v["spacing"] / 2 / v["speed"])


def test_the_summary_records_the_runouts_reduction():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = run_scene(
            "slope",
            {"spacing": 2.0, "runout": True, "t_end": 0.05, "phi": 10.0},
        )
    p, m = s["parameters"], s["metrics"]
    assert p["reduction"] is not None
    assert p["reduction"] == m["reduction"]
    F = m["factor_of_safety"]  # default: margin x F (1 when F < 1)
    assert p["reduction"] == pytest.approx(p["margin"] * F if F >= 1 else 1.0)
    for name in ("crest_length", "toe_length", "spacing", "dt", "t_end"):
        assert p[name] is not None, name


def test_the_slopes_k0_is_recorded_when_used():
    s = run_scene(
        "slope", {"spacing": 2.0, "initial_stress": "k0", "material": "tresca"}
    )
    assert s["parameters"]["K0"] == pytest.approx(1.0)  # 1 - sin 0
    s = run_scene("slope", {"spacing": 2.0, "initial_stress": "k0"})
    assert s["parameters"]["K0"] == pytest.approx(1 - math.sin(math.radians(20.0)))
    assert run_scene("slope", {"spacing": 2.0})["parameters"]["K0"] is None  # unused
