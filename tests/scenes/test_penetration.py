"""Scene ``footing-penetration``: a rigid strip footing pushed into Tresca clay.

Reference: Prandtl's ``q/s_u = 2 + pi`` (weightless Tresca soil, smooth or
rough).  The checks use a stiff soil, E_u/s_u = 1000: at the default 100 the
soil still settles elastically at w/B = 0.1 (the small-strain curve of the
same block, scene ``strip-footing``, is at 4.82 there and reaches 2 + pi at
w/B = 0.16), so no discretisation would give Prandtl at w/B = 0.1.  Soil
nodes passing the footing's edge make the curve a saw-tooth of about a
spacing over B; ``bearing_factor`` is its mean over one spacing of
penetration around w/B = 0.1.  Measured against 2 + pi (E_u/s_u = 1000,
w = 0.15 B): -7.3 % at h = B/10, +3.1 % at B/20, +3.3 % at B/40; the
footing is then 0.1 B deep, and Skempton's (1951) depth factor puts the
embedded reference 2 % above 2 + pi.
"""

from __future__ import annotations

import itertools
import math
import statistics

import numpy as np
import pytest

from skfem_npfem import ParameterError, run_scene

SCENE = "footing-penetration"


def test_footing_penetration_coarse_reaches_prandtl_and_keeps_out():
    res = run_scene(SCENE, {"spacing": 0.1, "penetration": 0.15, "E": 1e6})
    m = res["metrics"]
    assert set(res["solver"]["statuses"]) <= {"Solved", "AlmostSolved"}
    # measured -7.3 % at h = B/10 (five spacings under the half footing)
    assert m["relative_error"] == pytest.approx(0.0, abs=0.12)
    lo, hi = m["bearing_factor_range"]
    assert lo <= m["bearing_factor"] <= hi
    assert m["max_body_penetration"] <= 0.5 * 0.1  # measured 1e-15
    assert m["max_heave"] > 0.0


def test_footing_penetration_rough_interface_runs():
    res = run_scene(SCENE, {"spacing": 0.1, "penetration": 0.1, "interface": "rough"})
    m = res["metrics"]
    assert set(res["solver"]["statuses"]) <= {"Solved", "AlmostSolved"}
    assert m["bearing_factor"] == pytest.approx(2 + 3.141592653589793, rel=0.3)


@pytest.mark.parametrize(
    ("over", "name"),
    [
        ({"spacing": 0.5}, "spacing"),
        ({"penetration": 5.0}, "penetration"),
        ({"speed": 10.0, "dt": 0.05}, "speed"),
        ({"width": 0.0}, "width"),
        ({"width": -1.0}, "width"),
        ({"nu": 0.5}, "nu"),
        ({"interface": "glued"}, "interface"),
        ({"method": "spfem"}, "method"),
        ({"method": "npfem", "element": "p2"}, "element"),
    ],
)
def test_footing_penetration_bad_input(over, name):
    with pytest.raises(ParameterError) as info:
        run_scene(SCENE, over)
    assert info.value.name == name and "\n" not in str(info.value)


def test_footing_penetration_refuses_spfem_saying_why():
    with pytest.raises(ParameterError, match="quasi-static"):
        run_scene(SCENE, {"method": "spfem"})


def test_footing_penetration_near_incompressible_runs():
    res = run_scene(SCENE, {"spacing": 0.1, "penetration": 0.05, "nu": 0.4999})
    assert set(res["solver"]["statuses"]) <= {"Solved", "AlmostSolved"}
    assert res["metrics"]["final_bearing_factor"] > 0


@pytest.mark.slow
def test_footing_penetration_fine_prandtl():
    res = run_scene(
        SCENE, {"spacing": 0.025, "penetration": 0.15, "dt": 0.00625, "E": 1e6}
    )
    m = res["metrics"]
    # The footing is 0.1 B deep at w/B = 0.1: Skempton's (1951) depth factor
    # 1 + 0.2 d/B puts the reference 2 % above 2 + pi.  Measured 5.313 at
    # h = B/40 (+1.3 % on that, +3.3 % on 2 + pi; B/20: 5.301), about two
    # and a half minutes on one core.
    embedded = (2 + math.pi) * (1 + 0.2 * 0.1)
    assert m["bearing_factor"] == pytest.approx(embedded, rel=0.03)
    assert m["max_body_penetration"] <= 0.5 * 0.025


def test_footing_penetration_fem_remap_p2_near_prandtl_and_p1_locks():
    # Same case as the N-PFEM coarse test (E_u/s_u = 1000, h = B/10, w = 0.15 B).
    # Measured: P2 +5.0 % off 2 + pi (tolerance 10 %); P1 locks (one
    # incompressibility constraint per constant-strain triangle under
    # isochoric Tresca flow): +129 %, asserted above +50 %.
    case = {"spacing": 0.1, "penetration": 0.15, "E": 1e6, "method": "fem-remap"}
    p2 = run_scene(SCENE, {**case, "element": "p2"})
    m2 = p2["metrics"]
    assert set(p2["solver"]["statuses"]) <= {"Solved", "AlmostSolved"}
    assert m2["relative_error"] == pytest.approx(0.0, abs=0.10)
    assert m2["max_body_penetration"] <= 0.5 * 0.1  # measured 6e-15
    assert not m2["warnings"]
    with pytest.warns(UserWarning, match="P1 elements locks"):
        p1 = run_scene(SCENE, {**case, "element": "p1"})["metrics"]
    assert p1["relative_error"] > 0.5
    assert any("use element=p2" in w for w in p1["warnings"])


@pytest.fixture(scope="module")
def to_b():
    """B/10, the footing moving a quarter spacing a step to w/B = 1: open, sealed."""
    over = {"spacing": 0.1, "penetration": 1.0}
    return {
        seal: run_scene(SCENE, {**over, "seal_cavities": seal})["metrics"]
        for seal in (False, True)
    }


def test_footing_penetration_keeps_particles_out_to_w_equal_b(to_b):
    # At B/10 with the footing moving a quarter spacing a step to w/B = 1:
    # measured 0 (0.89 spacings when the elements that clip the footing's
    # corner were dropped: two particles met under the footing on the
    # symmetry line, the pressure fell to 2.4 s_u at the end).
    m = to_b[False]
    assert m["max_body_penetration"] <= 0.05 * 0.1
    assert not m["warnings"]
    assert m["final_bearing_factor"] > 2 + 3.141592653589793  # heave: it rises
    # one step falls to 2.7 at w/B = 0.775 (see docs/theory.md, "The edge of
    # a footing"): counted
    assert m["load_drops"] == _drops_by_hand(m["curve"]) >= 1


def test_sealing_the_hole_under_the_footing_removes_its_load_drop(to_b):
    # The drop above: the alpha test opens a hole on the symmetry axis under
    # the footing (docs/theory.md, "Holes the alpha test opens inside the
    # soil") and the load falls to 2.74 s_u, a third below the median.
    # Sealed, the curve is the same step for step up to that step and has no
    # load drop after it.
    open_, sealed = (np.asarray(to_b[s]["curve"]) for s in (False, True))
    first = np.flatnonzero(open_[:, 1] != sealed[:, 1])[0]
    assert open_[first, 0] == pytest.approx(0.775, abs=0.03)
    assert to_b[False]["load_drops"] >= 1 and to_b[True]["load_drops"] == 0
    beyond = sealed[:, 0] > 0.2
    falls = -np.diff(sealed[:, 1])[beyond[1:]] / np.median(sealed[beyond, 1])
    assert falls.max() < 0.15  # measured 0.116 (open: 0.325)
    assert to_b[True]["max_body_penetration"] <= 0.05 * 0.1
    assert to_b[True]["final_bearing_factor"] > 2 + math.pi


def test_penetration_warning_past_half_a_spacing():
    from skfem_npfem.scenes.footing.penetration_common import penetration_warnings

    assert penetration_warnings(SCENE, 0.049, 0.1, 0.025) == []
    with pytest.warns(UserWarning, match="0.51 spacings inside the body"):
        (msg,) = penetration_warnings(SCENE, 0.051, 0.1, 0.025)
    assert "lower dt (now 0.025 s)" in msg


def test_footing_penetration_soft_soil_is_not_compared_with_prandtl():
    # At the default E_u/s_u = 100 the soil still settles elastically at
    # w/B = 0.1 (it reaches 2 + pi near w/B = 0.15), so the relative error
    # against 2 + pi is not given there; at 1000 it is.
    soft = run_scene(SCENE, {"spacing": 0.1, "penetration": 0.15})["metrics"]
    assert soft["bearing_factor"] is not None
    assert soft["relative_error"] is None
    assert soft["bearing_factor"] < 2 + math.pi  # still on the elastic rise
    stiff = run_scene(SCENE, {"spacing": 0.1, "penetration": 0.15, "E": 3e5})
    m = stiff["metrics"]
    assert m["relative_error"] == pytest.approx(m["bearing_factor"] / (2 + math.pi) - 1)


def _drops_by_hand(curve, window=0.5):
    # a step under 0.8 x the median of the steps over the last B/2 up to it
    return sum(
        q < 0.8 * statistics.median(p for v, p in curve if w - window <= v <= w)
        for w, q in curve
    )


def test_footing_load_drops_count_the_committed_curves():
    # The footing at B/20 with the holes inside the soil left open
    # (docs/validation/footing_drops.json, seal_cavities=false): q/s_u falls
    # from 5.8 to 3.6 at w/B = 0.69 and from 6.0 to 3.8 at 0.89.  Sealed (the
    # default; docs/validation/penetration_methods.json at B/10 and B/20) the
    # counter finds none.
    import json
    from pathlib import Path

    from skfem_npfem.scenes.footing.penetration_common import running_drops

    validation = Path(__file__).parents[2] / "docs/validation"
    steps = json.loads((validation / "footing_drops.json").read_text())
    curve = [[s["w"], s["q"]] for s in steps["stepwise"]["steps"]]
    drops = running_drops(curve)
    assert drops == _drops_by_hand(curve)
    fallen = [w for (_, a), (w, b) in itertools.pairwise(curve) if b < 0.7 * a]
    assert [round(w, 2) for w in fallen] == [0.69, 0.89]
    assert drops >= len(fallen)
    runs = json.loads((validation / "penetration_methods.json").read_text())["runs"]
    sealed = [r["curve"] for r in runs if r["method"] == "npfem"]
    assert len(sealed) == 4
    assert [running_drops(c) for c in sealed] == [_drops_by_hand(c) for c in sealed]
    assert [running_drops(c) for c in sealed] == [0, 0, 0, 0]
    # a rising curve (the elastic start) has no drops
    assert running_drops([[w, 1 - (1 - w) ** 2] for w in (0.1, 0.2, 0.3)]) == 0
