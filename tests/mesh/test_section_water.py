"""The water of a cross-section file: the phreatic line and the heads.

References: linear interpolation of the phreatic line (z = 2 at x = 0 to
z = 0.5 at x = 12 is z = 1.25 at x = 6) and hydrostatics below it
(p = rho_w g (z_w - z)).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from skfem_npfem.errors import ParameterError
from skfem_npfem.mesh.section_file import read_cross_section
from skfem_npfem.mesh.section_water import section_water

SECTION = {
    "materials": {
        "clay": {"c": 30000, "phi": 0, "rho": 1940},
        "sand": {"c": 0, "phi": 35, "rho": 1835},
    },
    "regions": [
        {"material": "clay", "polygon": [[0, 0], [12, 0], [12, 1], [0, 1], [0, 0]]},
        {"material": "sand", "polygon": [[0, 1], [7.5, 1], [3, 4], [0, 4], [0, 1]]},
    ],
}


def read(tmp_path, **extra):
    path = tmp_path / "section.json"
    path.write_text(json.dumps({**SECTION, **extra}))
    return read_cross_section(path)


def error(tmp_path, **extra) -> ParameterError:
    with pytest.raises(ParameterError) as err:
        read(tmp_path, **extra)
    return err.value


def test_dry_section(tmp_path):
    sec = read(tmp_path)
    assert sec.water is None and sec.heads == []
    assert section_water(sec, 1000.0) is None


def test_water_line_read_and_interpolated(tmp_path):
    sec = read(tmp_path, water=[[0, 2], [12, 0.5]])
    assert np.array_equal(sec.water, [[0, 2], [12, 0.5]])
    table = section_water(sec, rho_w=1000.0)
    x = np.array([[6.0, 0.0], [6.0, 3.0]])
    assert table.elevation(x) == pytest.approx([1.25, 1.25], abs=1e-15)
    # Hydrostatic below the line, zero above it.
    p = table.pressure(x, rho_w=1000.0, gravity=9.81)
    assert p == pytest.approx([1000.0 * 9.81 * 1.25, 0.0], rel=1e-15)


def test_water_line_beyond_the_section_is_accepted(tmp_path):
    sec = read(tmp_path, water=[[-5, 2], [20, 0.5]])
    assert len(sec.water) == 2


def test_water_line_must_span_the_section(tmp_path):
    err = error(tmp_path, water=[[0, 2], [10, 0.5]])
    assert err.name == "water" and "[0, 12]" in str(err)
    assert "[0, 10]" in str(err)


@pytest.mark.parametrize(
    "water", [[[0, 2], [0, 3], [12, 1]], [[0, 2]], "nowhere", [[0, "a"], [12, 1]]]
)
def test_bad_water_line(tmp_path, water):
    assert error(tmp_path, water=water).name == "water"


def test_water_from_a_named_boundary(tmp_path):
    boundaries = {"phreatic": [[12, 0.5], [6, 1.5], [0, 2]]}
    sec = read(tmp_path, boundaries=boundaries, water="phreatic")
    # Given right to left: read along increasing x.
    assert np.array_equal(sec.water, [[0, 2], [6, 1.5], [12, 0.5]])


def test_heads_on_boundaries_and_lines(tmp_path):
    heads = [
        {"boundary": "left", "head": 4.0},
        {"boundary": "upstream", "head": 3.5},
        {"line": [[10, 1], [12, 1]], "head": 1},
    ]
    sec = read(tmp_path, boundaries={"upstream": [[0, 1], [0, 4]]}, heads=heads)
    names = [n for n, _, _ in sec.heads]
    assert names == ["left", "upstream", "heads[2]"]
    assert [h for _, _, h in sec.heads] == [4.0, 3.5, 1.0]
    # The left side: the polygons' vertices at x = 0, bottom to top.
    assert np.array_equal(sec.heads[0][1], [[0, 0], [0, 1], [0, 4]])
    assert all(isinstance(h, float) for _, _, h in sec.heads)


def test_base_and_right_boundaries(tmp_path):
    heads = [{"boundary": "base", "head": 1.0}, {"boundary": "right", "head": 1.0}]
    sec = read(tmp_path, heads=heads)
    assert np.array_equal(sec.heads[0][1], [[0, 0], [12, 0]])
    assert np.array_equal(sec.heads[1][1], [[12, 0], [12, 1]])


def test_head_on_a_missing_boundary(tmp_path):
    err = error(
        tmp_path,
        boundaries={"upstream": [[0, 1], [0, 4]]},
        heads=[{"boundary": "downstream", "head": 1.0}],
    )
    assert err.name == "heads[0].boundary" and err.value == "downstream"
    assert "base, left, right, upstream" in str(err)


@pytest.mark.parametrize(
    ("heads", "name"),
    [
        ([{"boundary": "left", "head": "high"}], "heads[0].head"),
        ([{"boundary": "left", "head": float("nan")}], "heads[0].head"),
        ([{"boundary": "left", "line": [[0, 0], [1, 0]], "head": 1}], "heads[0]"),
        ([{"head": 1}], "heads[0]"),
        ([{"boundary": "left", "head": 1, "flux": 0}], "heads[0].flux"),
        ([{"line": [[0, 0]], "head": 1}], "heads[0].line"),
        ({"left": 1}, "heads"),
    ],
)
def test_bad_heads(tmp_path, heads, name):
    assert error(tmp_path, heads=heads).name == name


def test_bad_rho_w(tmp_path):
    sec = read(tmp_path, water=[[0, 2], [12, 0.5]])
    with pytest.raises(ParameterError) as err:
        section_water(sec, rho_w=-1.0)
    assert err.value.name == "rho_w"


def test_conductivity_of_every_material(tmp_path):
    clay, sand = SECTION["materials"]["clay"], SECTION["materials"]["sand"]
    mats = {"clay": {**clay, "k": 1e-9}, "sand": {**sand, "k": 1e-5}}
    sec = read(tmp_path, materials=mats)
    assert [p["k"] for p in sec.materials.values()] == [1e-9, 1e-5]


def test_conductivity_of_some_materials_only_is_refused(tmp_path):
    mats = {**SECTION["materials"], "sand": {**SECTION["materials"]["sand"], "k": 1e-5}}
    err = error(tmp_path, materials=mats)
    assert err.name == "materials.clay.k" and "every material" in str(err)


@pytest.mark.parametrize("k", [0, -1e-5, "fast"])
def test_bad_conductivity(tmp_path, k):
    mats = {**SECTION["materials"], "sand": {**SECTION["materials"]["sand"], "k": k}}
    assert error(tmp_path, materials=mats).name == "materials.sand.k"
