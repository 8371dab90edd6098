"""The water table, the model's water and the scenes' water parameters."""

from __future__ import annotations

import numpy as np
import pytest

import skfem_npfem as npfem
from skfem_npfem.errors import ParameterError
from skfem_npfem.scenes.water import derive_drainage, scene_water


def test_level_gives_hydrostatic_pressure_below_and_none_above():
    t = npfem.WaterTable(level=2.0)
    x = np.array([[0.0, -1.0], [5.0, 2.0], [1.0, 3.5]])
    np.testing.assert_array_equal(t.pressure(x, 1000.0, 9.81), [3 * 9810.0, 0, 0])


def test_line_is_interpolated_between_its_vertices():
    t = npfem.WaterTable(line=[[0.0, 1.0], [10.0, 3.0]])
    x = np.array([[5.0, 0.0], [10.0, 3.0]])
    np.testing.assert_allclose(t.pressure(x, 1000.0, 10.0), [2e4, 0.0])


@pytest.mark.parametrize(
    ("kwargs", "says"),
    [
        ({}, "exactly one of"),
        ({"level": 1.0, "line": [[0, 0], [1, 0]]}, "exactly one of"),
        ({"level": float("nan")}, "finite elevation"),
        ({"line": [[0, 0]]}, "at least two points"),
        ({"line": [[1, 0], [0, 0]]}, "strictly increasing"),
    ],
)
def test_bad_tables_are_refused(kwargs, says):
    with pytest.raises(ParameterError, match=says):
        npfem.WaterTable(**kwargs)


def test_a_line_that_does_not_span_the_soil_is_refused():
    t = npfem.WaterTable(line=[[0.0, 1.0], [10.0, 3.0]])
    with pytest.raises(ParameterError, match="outside it"):
        t.pressure(np.array([[11.0, 0.0]]), 1000.0, 10.0)


def test_water_refuses_bad_modes_and_a_drained_soil_without_a_table():
    with pytest.raises(ParameterError, match="drainage"):
        npfem.Water("wet", npfem.WaterTable(level=0.0))
    with pytest.raises(ParameterError, match="water table"):
        npfem.Water("drained")
    with pytest.raises(ParameterError, match="rho_w"):
        npfem.Water("undrained", rho_w=0.0)
    with pytest.raises(ParameterError, match="water"):
        npfem.Model(dim=2, materials=[npfem.LinearElastic(1e6, 0.3)], water="wet")


@pytest.mark.parametrize(
    ("given", "drainage", "error"),
    [
        ({}, "dry", None),
        ({"water_level": 1.0}, "drained", None),
        ({"drainage": "undrained"}, "undrained", None),
        ({"drainage": "drained"}, None, "drained with a water_level"),
        ({"drainage": "dry", "water_level": 1.0}, None, "no water_level"),
    ],
)
def test_scene_drainage_follows_the_water_level(given, drainage, error):
    values = {"drainage": None, "water_level": None, "rho_w": 1000.0, **given}
    if error:
        with pytest.raises(ParameterError, match=error):
            derive_drainage(values)
        return
    derive_drainage(values)
    assert values["drainage"] == drainage
    water = scene_water(values)
    assert (water is None) == (drainage == "dry")


def test_baselines_refuse_water():
    soil = npfem.LinearElastic(1e6, 0.3)
    model = npfem.Model(dim=2, materials=[soil], water=npfem.Water("undrained", None))
    with pytest.raises(ParameterError, match="N-PFEM only"):
        model.refuse_loads("FEM-remap")
