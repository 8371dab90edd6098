"""Pseudo-static slopes: a horizontal body force ``k_h`` times the weight.

Reference: the dry cohesionless infinite slope.  A layer parallel to a slope
of angle ``beta`` slides when the resultant of its weight and ``k_h`` times
its weight (out of the face) leans ``phi`` from the normal of the slip plane:
``F(k_h) = tan(phi) (cos beta - k_h sin beta) / (sin beta + k_h cos beta)``
and ``F = 1`` at ``k_h = tan(phi - beta)`` (e.g. Kramer, Geotechnical
Earthquake Engineering, 1996, the infinite-slope pseudo-static analysis).
No cohesion: the depth of the layer does not matter, so the finite slope's
critical mechanism is that layer.

A c-phi slope with a published critical ``k_h``: Loukidis, Bandini & Salgado
(2003), example 1 (H = 25 m at 1V:3H, c' = 25 kPa, phi' = 30 deg, gamma = 20
kN/m^3, dry): 0.432 by their log-spiral analysis, between their finite-element
limit-analysis bounds 0.423 and 0.454.
"""

from __future__ import annotations

import math

import pytest
from slope_fos import SLOPE  # demos/studies (tests/conftest.py)
from slope_loads import LOUKIDIS, LOUKIDIS_BOUNDS, LOUKIDIS_KC

import skfem_npfem as npfem
from skfem_npfem import ParameterError

BETA, PHI = 20.0, 40.0
#: A cohesionless slope (beta = 20 deg, phi = 40 deg), 10 m high, at H/10.
SAND = {
    "analysis": "limit",
    "refine": "none",
    "c": 0.0,
    "phi": PHI,
    "angle": BETA,
    "spacing": 1.0,
}


def infinite_slope_F(kh: float) -> float:
    b = math.radians(BETA)
    return (
        math.tan(math.radians(PHI))
        * (math.cos(b) - kh * math.sin(b))
        / (math.sin(b) + kh * math.cos(b))
    )


@pytest.fixture(scope="module")
def sand() -> dict:
    return npfem.run_scene("slope", SAND)["metrics"]


def test_critical_kh_is_the_infinite_slope_value(sand):
    # tan(phi - beta) = 0.364: measured 0.377 (+3.6 %) at H/10 and 0.368
    # (+1.1 %) at H/20.
    assert sand["critical_kh"] == pytest.approx(
        math.tan(math.radians(PHI - BETA)), rel=0.05
    )


def test_factor_of_safety_under_kh_is_the_infinite_slope_value(sand):
    # k_h = 0.1: F = 1.743 (measured +1.8 % at H/10, +0.6 % at H/20); the
    # same run without k_h keeps the static F (+1.7 % over tan(phi)/tan(beta)).
    shaken = npfem.run_scene("slope", {**SAND, "kh": 0.1})["metrics"]
    assert shaken["factor_of_safety"] == pytest.approx(infinite_slope_F(0.1), rel=0.05)
    assert sand["factor_of_safety"] == pytest.approx(infinite_slope_F(0.0), rel=0.05)
    # The bias of the lattice is the same with and without shaking.
    bias = sand["factor_of_safety"] / infinite_slope_F(0.0)
    assert shaken["factor_of_safety"] / infinite_slope_F(0.1) == pytest.approx(
        bias, abs=0.01
    )


@pytest.mark.slow
def test_critical_kh_converges_with_the_spacing(sand):
    fine = npfem.run_scene("slope", {**SAND, "spacing": 0.5})["metrics"]
    exact = math.tan(math.radians(PHI - BETA))
    assert abs(fine["critical_kh"] / exact - 1) < abs(sand["critical_kh"] / exact - 1)
    assert fine["critical_kh"] == pytest.approx(exact, rel=0.02)


def test_kh_into_the_slope_raises_F(sand):
    # A negative k_h pushes the layer into the slope: F(-0.1) = 3.05.
    into = npfem.run_scene("slope", {**SAND, "kh": -0.1})["metrics"]
    assert into["factor_of_safety"] == pytest.approx(infinite_slope_F(-0.1), rel=0.05)


#: Griffiths & Lane's (1999) 2:1 slope, c' = 10 kPa, phi' = 20 deg (F = 1.4), H/10.
CPHI = {**SLOPE, "spacing": 1.0}


def test_factor_of_safety_is_one_at_the_critical_kh():
    # Two algorithms on one mesh: the collapse multiplier of k_h with gravity
    # dead, and the strength reduction under gravity plus that k_h.
    kc = npfem.run_scene("slope", CPHI)["metrics"]["critical_kh"]
    assert 0.05 < kc < 0.5
    at = npfem.run_scene("slope", {**CPHI, "kh": kc})["metrics"]
    assert at["factor_of_safety"] == pytest.approx(1.0, abs=2e-3)


@pytest.mark.filterwarnings("ignore:.* limit program")
def test_critical_kh_of_loukidis_slope():
    # H/10 (measured 0.4344, +0.6 %; 0.4315 at H/20, 0.4299 at H/40, in
    # docs/validation/slope_loads.md): within 5 % of the log-spiral value and
    # inside the published bounds.
    slope = {**LOUKIDIS, "spacing": 2.5}
    kc = npfem.run_scene("slope", slope)["metrics"]["critical_kh"]
    assert kc == pytest.approx(LOUKIDIS_KC, rel=0.05)
    assert LOUKIDIS_BOUNDS[0] <= kc <= LOUKIDIS_BOUNDS[1]


def test_critical_kh_is_null_when_gravity_alone_fails():
    # A 10 m vertical cut in clay of s_u = 10 kPa: F = 3.8 c / (gamma H) < 1.
    cut = {k: v for k, v in CPHI.items() if k != "phi"}
    cut.update(material="tresca", angle=90.0, foundation_depth=10.0)
    cut.update(crest_length=15.0, toe_length=15.0)
    m = npfem.run_scene("slope", cut)["metrics"]
    assert m["factor_of_safety"] < 1.0
    assert m["critical_kh"] is None


#: A small slope of the sand above (H = 2 m at H/5) run out with its own
#: strength (reduction 1): it stands (F = 2.4) until shaken.
SHAKEN = {
    "runout": True,
    "c": 0.0,
    "phi": PHI,
    "angle": BETA,
    "height": 2.0,
    "foundation_depth": 0.4,
    "spacing": 0.4,
    "crest_length": 1.6,
    "toe_length": 4.0,
    "reduction": 1.0,
}


def pulse(path, peak: float) -> str:
    """A half-second pulse of k_h: 0, ramps to ``peak`` in 0.05 s, back at 0.55 s."""
    rows = [[0.0, 0.0], [0.05, peak], [0.5, peak], [0.55, 0.0]]
    path.write_text("# t (s), k_h\n" + "\n".join(f"{t}, {k}" for t, k in rows))
    return str(path)


def test_a_slope_slides_only_when_kh_passes_the_critical_one(tmp_path):
    # Newmark's threshold: a sliding mass moves only while k_h exceeds the
    # critical k_h (tan(phi - beta) = 0.364 for this sand).  A pulse of 0.2
    # leaves the slope where it is; one of 0.8 makes it slide, then rest.
    weak = npfem.run_scene("slope", {**SHAKEN, "kh": pulse(tmp_path / "w.csv", 0.2)})
    strong = npfem.run_scene("slope", {**SHAKEN, "kh": pulse(tmp_path / "s.csv", 0.8)})
    w, s = weak["metrics"], strong["metrics"]
    assert w["factor_of_safety"] > 1.0 and w["at_rest"] and s["at_rest"]
    assert w["moved_volume"] == 0.0 and abs(w["crest_settlement"]) < 0.01
    assert s["moved_volume"] > 1.0 and s["runout"] > 0.1
    assert s["crest_settlement"] > 0.1


def test_a_constant_kh_shakes_the_runout_too():
    # Above the critical k_h the whole run is shaken: it slides to t_end.
    m = npfem.run_scene("slope", {**SHAKEN, "kh": 0.8, "t_end": 0.5, "runout": True})[
        "metrics"
    ]
    assert m["factor_of_safety"] < 1.0  # F under k_h = 0.8
    assert m["moved_volume"] > 0.0


def test_bad_kh_files_are_refused(tmp_path):
    bad = {
        "missing.csv": None,
        "one.csv": "0, 0.1, 3\n1, 0.2, 4\n",
        "back.csv": "0, 0\n1, 0.1\n0.5, 0\n",
        "text.csv": "t, kh\n0, 0\n",
        "huge.csv": "0, 0\n1, 20\n",
    }
    for name, text in bad.items():
        path = tmp_path / name
        if text is not None:
            path.write_text(text)
        with pytest.raises(ParameterError) as err:
            npfem.run_scene("slope", {**SHAKEN, "kh": str(path)})
        assert err.value.name == "kh", name
    # A history shakes the run-out: without it a number is asked for.
    good = pulse(tmp_path / "good.csv", 0.2)
    with pytest.raises(ParameterError) as err:
        npfem.run_scene("slope", {**SAND, "kh": good})
    assert err.value.name == "kh"


def test_critical_kh_is_null_without_limit_analysis():
    m = npfem.run_scene("slope", {**SAND, "analysis": "incremental"})["metrics"]
    assert m["critical_kh"] is None
