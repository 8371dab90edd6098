"""The ``slope`` scene and cross-sections from polygons.

References: Bishop & Morgenstern (1960) stability charts, FoS = 1.38 for a
2:1 homogeneous slope with phi' = 20 deg and c'/(gamma H) = 0.05 on a firm base
(Griffiths & Lane 1999, example 1, where finite elements give 1.4); the
infinite-slope factor of safety ``tan(phi)/tan(beta)`` of a dry cohesionless
slope; polygon areas (exact).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from adaptive_limit import CUT  # demos/studies (tests/conftest.py)
from helpers import check_cli_error, run_cli

import skfem_npfem as npfem
from skfem_npfem.mesh.regions import Region, check_regions, fill_regions

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "docs" / "examples" / "two_layer_slope.json"

#: Griffiths & Lane (1999), example 1: Bishop & Morgenstern's chart value.
BISHOP_MORGENSTERN_FOS = 1.38
#: Tolerance at spacing H/10 (measured +1.9 %; +1.0 % at H/15, +0.65 % at H/20).
FOS_TOL = 0.03

GRIFFITHS_LANE = {
    "analysis": "limit",
    "refine": "none",
    "height": 10.0,
    "angle": math.degrees(math.atan(0.5)),
    "foundation_depth": 0.0,
    "crest_length": 20.0,
    "toe_length": 15.0,
    "c": 1.0e4,
    "phi": 20.0,
    "rho": 2.0e4 / 9.81,
    "spacing": 1.0,
}

#: A cohesionless slope (beta = 30 deg, phi = 35 deg) at spacing H/10.
SAND = {
    "analysis": "limit",
    "refine": "none",
    "c": 0.0,
    "phi": 35.0,
    "angle": 30.0,
    "height": 4.0,
    "foundation_depth": 1.0,
    "spacing": 0.4,
}


def test_fill_regions_area_and_materials():
    """Two regions sharing an edge: mesh area exact, nodes by region."""
    a = np.array([[0, 0], [4, 0], [4, 1], [0, 1]], float)
    b = np.array([[0, 1], [4, 1], [2, 3], [0, 3]], float)
    pts, tri, region = fill_regions([Region("a", a), Region("b", b)], 0.25)
    v = pts[tri.T]
    area = 0.5 * np.abs(
        (v[:, 1, 0] - v[:, 0, 0]) * (v[:, 2, 1] - v[:, 0, 1])
        - (v[:, 1, 1] - v[:, 0, 1]) * (v[:, 2, 0] - v[:, 0, 0])
    )
    assert area.sum() == pytest.approx(4.0 + 6.0, rel=1e-12)
    assert np.all(region[pts[:, 1] < 1 - 1e-9] == 0)
    assert np.all(region[pts[:, 1] > 1 + 1e-9] == 1)
    assert np.all(region[np.isclose(pts[:, 1], 1.0)] == 0)  # shared: first region


@pytest.mark.parametrize(
    ("regions", "needle"),
    [
        ([[[0, 0], [1, 1], [1, 0], [0, 1]]], "self-intersecting"),
        (
            [[[0, 0], [2, 0], [2, 2], [0, 2]], [[1, 1], [3, 1], [3, 3], [1, 3]]],
            "overlap",
        ),
        ([[[0, 0], [0.1, 0], [0.1, 0.1], [0, 0.1]]], "smaller than the spacing"),
    ],
)
def test_check_regions_refuses(regions, needle):
    """Bad polygons: one ParameterError naming the region."""
    with pytest.raises(npfem.ParameterError, match=needle):
        check_regions([Region("m", np.array(r, float)) for r in regions], 0.5)


@pytest.mark.parametrize(
    ("edit", "needles"),
    [
        (lambda d: d["regions"][0]["polygon"].pop(), ("polygon", "open")),
        (
            lambda d: d["regions"][1].update(material="rock"),
            ("regions[1].material", "'rock'", "clay, fill"),
        ),
        (
            lambda d: d["regions"][1].update(
                polygon=[[0, 2], [10, 2], [22, 4], [14, 12], [0, 12], [0, 2]]
            ),
            ("regions[1]", "overlap"),
        ),
        (
            lambda d: d["regions"][1].update(
                polygon=[[0, 4], [14, 12], [10, 4], [0, 12], [0, 4]]
            ),
            ("self-intersecting",),
        ),
        (lambda d: d["materials"]["clay"].update(colour=1), ("colour",)),
    ],
)
def test_bad_geometry_file_one_error_line(tmp_path, edit, needles):
    """Each bad cross-section file: exit 2 and one `error:` line."""
    data = json.loads(EXAMPLE.read_text())
    edit(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    code, err = run_cli(
        ["run", "slope", "--set", f"geometry={path}", "--set", "analysis=limit"]
    )
    check_cli_error(code, err, *needles)


def test_classic_slope_factor_of_safety():
    """2:1 slope, phi 20, c/(gamma H) 0.05: FoS within 3 % of Bishop-Morgenstern."""
    m = npfem.run_scene("slope", GRIFFITHS_LANE)["metrics"]
    assert m["limit_status"] in ("Solved", "AlmostSolved")
    assert abs(m["factor_of_safety"] / BISHOP_MORGENSTERN_FOS - 1) < FOS_TOL
    assert abs(m["fos_iterates"][-1][1] - 1) < 1e-3  # lambda(F) = 1
    assert m["collapse_multiplier"] > 1.0  # F > 1: it carries more than its weight
    assert 2 <= m["cone_programs"] <= 10


#: Tresca vertical cut: 3.7752 <= gamma H_c / c <= 3.7776 (Kammoun et al. 2010).
VERTICAL_CUT = 3.7764


def test_vertical_cut_stability_number():
    """Tresca cut: gamma H F / c within 7 % of 3.776 at H/10 (+5.5 %, H/20 +2.2 %)."""
    m = npfem.run_scene("slope", {**CUT, "spacing": 1.0, "refine": "none"})["metrics"]
    number = m["factor_of_safety"] * 2.0e4 * 10.0 / 1.0e4
    assert abs(number / VERTICAL_CUT - 1) < 0.07
    assert m["cone_programs"] == 2  # cohesive: lambda(F) = lambda(1) / F
    assert m["collapse_multiplier"] == pytest.approx(m["factor_of_safety"], rel=1e-6)


def test_cohesionless_slope_infinite_slope_value():
    """Dry sand: tan(phi)/tan(beta) within 5 % at H/10 (+3.9 %; +1.5 % at H/20)."""
    m = npfem.run_scene("slope", SAND)["metrics"]
    ref = math.tan(math.radians(35.0)) / math.tan(math.radians(30.0))
    assert abs(m["factor_of_safety"] / ref - 1) < 0.05


def test_cross_section_file_runs():
    """The shipped example: two materials, a factor of safety, one line each."""
    s = npfem.run_scene(
        "slope",
        {
            "geometry": str(EXAMPLE),
            "analysis": "limit",
            "refine": "none",
            "spacing": 1.0,
        },
    )
    m = s["metrics"]
    assert m["factor_of_safety"] > 0.5
    assert 0 < m["plastic_fraction"] < 0.5


#: The column collapse's bound on the meshed volume change (test_column_collapse).
VOLUME_LIMIT = 0.18
#: Deposit surface slope above phi allowed, deg, over 3 spacings: the surface
#: is read from the highest particle per column (+-h/2 of noise).
SLOPE_TOL = 5.0


@pytest.fixture(scope="module")
def runout():
    """A small dry-sand cut (86 particles) that fails and runs out to rest."""
    return npfem.run_scene(
        "slope",
        {
            "runout": True,
            "c": 0.0,
            "phi": 30.0,
            "angle": 60.0,
            "height": 2.0,
            "foundation_depth": 0.4,
            "spacing": 0.4,
            "crest_length": 1.6,
            "toe_length": 4.0,
        },
    )


def test_runout_conserves_mass_and_comes_to_rest(runout):
    """Mass exact; meshed volume within the collapse's bound; at rest."""
    m = runout["metrics"]
    assert m["mass_change"] == 0.0
    assert abs(m["volume_change"]) < VOLUME_LIMIT
    assert m["at_rest"]
    assert m["initial_equilibrium_residual"] < 1e-10  # gravity switched on
    assert m["reduction"] == 1.0  # F < 1: it fails as it is
    assert m["factor_of_safety"] < 1.0
    assert m["runout"] > 0 and m["crest_settlement"] > 0
    above_toe = 2.0 * 1.6 + 0.5 * 2.0 * 2.0 / math.tan(math.radians(60.0))
    assert 0 < m["moved_volume"] < above_toe  # part of the slope slides


def test_runout_deposit_statically_admissible(runout):
    """Cohesionless deposit: no steeper than phi + 5 deg; its own FoS >= 1."""
    m = runout["metrics"]
    assert m["deposit_max_slope"] <= 30.0 + SLOPE_TOL
    assert m["deposit_factor_of_safety"] >= 1.0


def test_finer_where_asked_and_t_junctions():
    """A region with its own spacing: more particles there, area still exact."""
    a = np.array([[0, 0], [4, 0], [4, 1], [0, 1]], float)  # top edge whole
    b = np.array([[0, 1], [2, 1], [2, 3], [0, 3]], float)  # T-junction at (2, 1)
    coarse = fill_regions([Region("a", a), Region("b", b)], 0.25)
    fine = fill_regions([Region("a", a), Region("b", b, spacing=0.1)], 0.25)
    for pts, tri, _ in (coarse, fine):
        v = pts[tri.T]
        area = 0.5 * np.abs(
            (v[:, 1, 0] - v[:, 0, 0]) * (v[:, 2, 1] - v[:, 0, 1])
            - (v[:, 1, 1] - v[:, 0, 1]) * (v[:, 2, 0] - v[:, 0, 0])
        )
        assert area.sum() == pytest.approx(4.0 + 4.0, rel=1e-12)
        assert area.min() > 0.02 * 0.1**2  # no slivers at the T-junction
    in_b = lambda r: int(np.sum(r[2] == 1))  # noqa: E731
    assert in_b(fine) > 4 * in_b(coarse)  # (0.25 / 0.1)^2 = 6.25 per area


def test_mechanism_is_saved_with_the_run_and_drawn_by_plot(tmp_path):
    """The scene writes the mechanism's data when it owns its folder; the
    drawing is the viz layer's (``skfem-npfem plot``), not the scene's."""
    pytest.importorskip("matplotlib")
    from skfem_npfem.viz.mechanism import plot_mechanism

    out = tmp_path / "slope"
    s = npfem.run_scene("slope", {**GRIFFITHS_LANE, "spacing": 2.0}, out=out)
    data = np.load(out / "mechanism.npz")
    # The saved mechanism is the one of the reported factor of safety.
    assert float(data["factor_of_safety"]) == s["metrics"]["factor_of_safety"]
    assert data["velocity"].shape == data["x"].shape
    png = plot_mechanism(out / "mechanism.npz", tmp_path / "plots")
    assert png.name == "mechanism.png" and png.stat().st_size > 10_000
