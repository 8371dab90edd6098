"""Slopes that do not mislead: floating regions, unit mistakes, thin layers.

Each test is built from a new user's reproducer, scaled down to seconds: a
cross-section whose upper region floats 1 m above the lower one, material
values in the wrong units, a layer one or two spacings thick.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from helpers import check_cli_error, run_cli

import skfem_npfem as npfem
from skfem_npfem.errors import ParameterError
from skfem_npfem.mesh.regions import (
    CrossSection,
    Region,
    check_regions,
    region_thickness,
)
from skfem_npfem.mesh.section_file import implausible_values, read_cross_section
from skfem_npfem.scenes.slope.section import MIN_SPACINGS, section_warnings

EXAMPLE = Path(__file__).parents[2] / "docs" / "examples" / "two_layer_slope.json"


def _example(tmp_path: Path, edit) -> Path:
    data = json.loads(EXAMPLE.read_text())
    edit(data)
    path = tmp_path / "section.json"
    path.write_text(json.dumps(data))
    return path


def _lift_fill(data: dict) -> None:
    for p in data["regions"][1]["polygon"]:
        p[1] += 1.0


# -- floating regions ------------------------------------------------------------
def test_floating_region_is_refused_before_solving_and_named(tmp_path):
    """The example with its upper region lifted 1 m is refused by the pre-run check.

    It used to fail after a 6.9 s strength reduction with ``invalid
    max_programs=30``, a parameter that ``--set`` rejects.
    """
    path = _example(tmp_path, _lift_fill)
    code, err = run_cli(
        ["run", "slope", "--set", f"geometry={path}", "--set", "analysis=limit"]
    )
    line = check_cli_error(code, err, "regions[1]", "'fill'", "floats", "1 m")
    assert "max_programs" not in line


def test_regions_that_share_an_edge_or_rest_on_the_base_pass():
    lower = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [0.0, 1.0]])
    upper = np.array([[0.0, 1.0], [2.0, 1.0], [2.0, 2.0], [0.0, 2.0]])
    beside = np.array([[5.0, 0.0], [6.0, 0.0], [6.0, 1.0], [5.0, 1.0]])
    check_regions([Region("a", lower), Region("b", upper), Region("c", beside)], 0.25)


@pytest.mark.parametrize(
    "upper, needle",
    [
        # Lifted off: a gap of 0.5 m.
        ([[0.0, 1.5], [2.0, 1.5], [2.0, 2.5], [0.0, 2.5]], "0.5 m"),
        # Touching at one corner only: a hinge, no support.
        ([[4.0, 1.0], [5.0, 1.0], [5.0, 2.0], [4.0, 2.0]], "point only"),
    ],
)
def test_unsupported_regions_are_named(upper, needle):
    lower = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [0.0, 1.0]])
    regions = [Region("a", lower), Region("b", np.array(upper))]
    with pytest.raises(ParameterError, match=r"regions\[1\]") as err:
        check_regions(regions, 0.25)
    assert "floats" in str(err.value) and needle in str(err.value)


# -- unit mistakes -----------------------------------------------------------------
@pytest.mark.parametrize(
    "key, value, needle",
    [
        ("rho", 20, "kN/m^3"),  # a unit weight in kN/m^3
        ("c", 5, "kPa"),  # with phi below 5 degrees: kPa meant
        ("phi", 0.5, "radians"),  # radians meant
        ("E", 30, "MPa"),  # MPa meant
    ],
)
def test_unit_mistakes_are_warned_of_with_their_place(tmp_path, key, value, needle):
    def edit(data):
        data["materials"]["fill"][key] = value
        if key == "c":
            data["materials"]["fill"]["phi"] = 0

    sec = read_cross_section(_example(tmp_path, edit))
    msgs = implausible_values(sec.materials)
    assert len(msgs) == 1, msgs
    assert msgs[0].startswith(f"materials.fill.{key} = ") and needle in msgs[0]


def test_the_example_file_has_no_implausible_value():
    assert implausible_values(read_cross_section(EXAMPLE).materials) == []


def test_a_scene_run_warns_of_a_unit_mistake(tmp_path):
    """``"rho": 20`` gave F = 21.6 without a word; the run now warns."""

    def edit(data):
        data["materials"]["fill"]["rho"] = 20

    path = _example(tmp_path, edit)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        npfem.get_scene("slope").resolve({"geometry": str(path), "spacing": 1.0})
    assert any("materials.fill.rho = 20" in str(w.message) for w in caught)


@pytest.mark.parametrize(
    "given, needle",
    [({"rho": 20.0}, "rho = 20: "), ({"material": "tresca", "c": 5.0}, "c = 5: ")],
)
def test_a_parametric_slope_warns_of_a_unit_mistake_by_its_parameter(given, needle):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        npfem.get_scene("slope").resolve({**given, "spacing": 2.0})
    assert any(str(w.message).startswith(needle) for w in caught)


def test_a_plausible_parametric_slope_has_no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        npfem.get_scene("slope").resolve({"spacing": 1.0})


@pytest.mark.parametrize(
    "key, value, where",
    [
        ("phi", 95, "materials.fill.phi"),
        ("phi", -1, "materials.fill.phi"),
        ("c", -5, "materials.fill.c"),
        ("rho", 0, "materials.fill.rho"),
        ("nu", 0.5, "materials.fill.nu"),
        ("E", "30 MPa", "materials.fill.E"),
        ("gamma", 20, "materials.fill.gamma"),
    ],
)
def test_file_errors_name_the_key(tmp_path, key, value, where):
    def edit(data):
        data["materials"]["fill"][key] = value

    with pytest.raises(ParameterError) as err:
        read_cross_section(_example(tmp_path, edit))
    assert err.value.name == where


def test_support_errors_name_the_key(tmp_path):
    def edit(data):
        data["supports"]["top"] = "fixed"

    with pytest.raises(ParameterError) as err:
        read_cross_section(_example(tmp_path, edit))
    assert err.value.name == "supports.top"


# -- thin layers and the convergence hint -----------------------------------------
def test_region_thickness_is_the_layer_thickness():
    for t in (0.8, 2.0, 3.2):
        layer = Region("a", np.array([[0.0, 0.0], [40.0, 0.0], [40.0, t], [0.0, t]]))
        assert t - 0.4 / 8 <= region_thickness(layer, 0.4) <= t


def test_a_layer_thinner_than_the_threshold_is_warned_of():
    layer = np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 0.8], [0.0, 0.8]])
    base = np.array([[0.0, -4.0], [40.0, -4.0], [40.0, 0.0], [0.0, 0.0]])
    sec = CrossSection(
        [Region("rock", base), Region("weak", layer)],
        {"rock": {"c": 5e4, "phi": 30.0}, "weak": {"c": 4e3, "phi": 15.0}},
    )
    thin = section_warnings(sec, 0.4, {"geometry": "file"})
    assert len(thin) == 1 and "regions[1] ('weak')" in thin[0]
    assert "2.0 spacings" in thin[0]
    assert section_warnings(sec, 0.8 / MIN_SPACINGS, {"geometry": "file"}) == []


def test_factor_of_safety_reports_the_value_at_twice_the_spacing():
    """The hint is the factor of safety of the same slope at twice the spacing."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fine = npfem.run_scene(
            "slope", {"analysis": "limit", "refine": "none", "spacing": 2.0}
        )
        coarse = npfem.run_scene(
            "slope", {"analysis": "limit", "refine": "none", "spacing": 4.0}
        )
    m = fine["metrics"]
    F, F2 = m["factor_of_safety"], coarse["metrics"]["factor_of_safety"]
    assert m["factor_of_safety_coarse"] == F2
    assert m["fos_spacing_change"] == pytest.approx((F - F2) / F, rel=1e-12)


def test_an_unconverged_factor_of_safety_is_warned_of():
    """A warning exactly when F moves by more than 5 % at twice the spacing."""
    for phi in (10.0, 30.0):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = npfem.run_scene(
                "slope",
                {"analysis": "limit", "refine": "none", "spacing": 2.0, "phi": phi},
            )
        m = res["metrics"]
        loud = abs(m["fos_spacing_change"]) > 0.05
        assert any("not converged" in w for w in m["warnings"]) == loud
        assert any("not converged" in str(w.message) for w in caught) == loud
