"""The ``slope`` scene with the heads of a cross-section file (steady seepage).

References: equal heads ``H`` on every water boundary make the head ``H``
everywhere (a constant solves Darcy's problem), so the pore pressure is the
hydrostatic one of a horizontal table at ``H``: the factor of safety, the
pore pressure and the undrained strengths equal those of ``water_level = H``
(exactly, up to the round-off of the heads and the cone programs: 1e-9
relative at the interior-point tolerance ``tol = 1e-10``; measured 3e-11,
and 4e-8 at the default 1e-8).  The sand has a
small cohesion ``c'`` so that its factor of safety depends on the water (a
cohesionless submerged slope has the dry slope's F).  Vertical flow through
two layers of thickness ``d`` and conductivities ``k1``, ``k2`` (heads on
the base and the top, impermeable sides) is Darcy's flow in series: the head
at their interface is ``H_b + (H_t - H_b) (d / k1) / (d / k1 + d / k2)``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import skfem_npfem as npfem
from skfem_npfem.errors import ParameterError
from skfem_npfem.mesh.section_file import read_cross_section
from skfem_npfem.scenes import get_scene
from skfem_npfem.scenes.slope.body import slope_body
from skfem_npfem.scenes.slope.water import section_seepage, slope_water, static_pressure

pytestmark = [
    pytest.mark.filterwarnings("ignore:slope. the factor of safety"),
    pytest.mark.filterwarnings("ignore:.*AlmostSolved"),
]

PHI, LEVEL = 35.0, 6.0
X_TOE = 6.0 + 4.0 * 3**0.5  # a 30 degree slope 4 m high
W = X_TOE + 10.0
SECTION = {
    "materials": {"sand": {"c": 2.0e3, "phi": PHI, "rho": 2000.0}},
    "regions": [
        {
            "material": "sand",
            "polygon": [[0, 0], [W, 0], [W, 1], [X_TOE, 1], [6, 5], [0, 5], [0, 0]],
        }
    ],
    "supports": {"base": "fixed", "sides": "rollers"},
}
#: The free water at LEVEL seen by both sides: the same head everywhere.
HEADS = [{"boundary": "left", "head": LEVEL}, {"boundary": "right", "head": LEVEL}]
LIMIT = {"analysis": "limit", "refine": "none", "spacing": 0.4, "tol": 1e-10}


def write(tmp_path, name="section.json", **extra) -> str:
    path = tmp_path / name
    path.write_text(json.dumps({**SECTION, **extra}))
    return str(path)


def run(path: str, **values) -> dict:
    return npfem.run_scene("slope", {"geometry": path, **LIMIT, **values})


def test_equal_heads_are_a_horizontal_table(tmp_path):
    """F and p_max of equal heads H are those of water_level = H to 1e-9."""
    heads = run(write(tmp_path, heads=HEADS))
    table = run(write(tmp_path, "dry.json"), water_level=LEVEL)
    assert heads["parameters"]["drainage"] == "drained"
    m, ref = heads["metrics"], table["metrics"]
    assert m["pore_pressure_max"] == pytest.approx(1000.0 * 9.81 * LEVEL, rel=1e-9)
    assert m["factor_of_safety"] == pytest.approx(ref["factor_of_safety"], rel=1e-9)
    dry = run(write(tmp_path, "dry.json"))["metrics"]["factor_of_safety"]
    assert abs(m["factor_of_safety"] / dry - 1) > 0.05  # the water matters


def test_heads_win_over_the_phreatic_line(tmp_path):
    """A line at z = 2 with heads 6: the heads' pore pressure, rho_w g 6."""
    path = write(tmp_path, heads=HEADS, water=[[0, 2], [W, 2]])
    m = run(path)["metrics"]
    assert m["pore_pressure_max"] == pytest.approx(1000.0 * 9.81 * LEVEL, rel=1e-9)


def test_undrained_k0_strengths_of_equal_heads(tmp_path):
    """s_u of K0 stresses under equal heads H: those of water_level = H to 1e-9."""
    o = {"drainage": "undrained", "initial_stress": "k0", "K0": 0.5}
    m = run(write(tmp_path, heads=HEADS), **o)["metrics"]
    ref = run(write(tmp_path, "dry.json"), water_level=LEVEL, **o)["metrics"]
    for key in ("undrained_strength_min", "undrained_strength_max"):
        assert m[key] == pytest.approx(ref[key], rel=1e-9)


def test_dry_drainage_ignores_the_heads(tmp_path):
    m = run(write(tmp_path, heads=HEADS), drainage="dry")["metrics"]
    assert "pore_pressure_max" not in m


def test_conductivity_per_material_in_material_order(tmp_path):
    two = {
        "materials": {
            "clay": {"c": 2e4, "phi": 0.0, "rho": 1900.0, "k": 1e-9},
            "sand": {"c": 0.0, "phi": PHI, "rho": 2000.0, "k": 1e-5},
        },
        "regions": [
            {"material": "clay", "polygon": [[0, 0], [W, 0], [W, 1], [0, 1], [0, 0]]},
            {
                "material": "sand",
                "polygon": [[0, 1], [X_TOE, 1], [6, 5], [0, 5], [0, 1]],
            },
        ],
    }
    path = tmp_path / "two.json"
    path.write_text(json.dumps({**two, "heads": HEADS}))
    assert section_seepage(read_cross_section(path)).k == (1e-9, 1e-5)
    dry = read_cross_section(write(tmp_path, "dry.json"))
    assert section_seepage(dry) is None


def test_head_on_a_missing_boundary_is_refused(tmp_path):
    path = write(tmp_path, heads=[{"boundary": "upstream", "head": 6.0}])
    with pytest.raises(ParameterError, match="upstream"):
        run(path)


@pytest.mark.parametrize("k", [0.0, -1e-5])
def test_conductivity_must_be_positive(tmp_path, k):
    mats = {"sand": {**SECTION["materials"]["sand"], "k": k}}
    path = write(tmp_path, materials=mats, heads=HEADS)
    with pytest.raises(ParameterError, match=r"materials\.sand\.k"):
        run(path)


@pytest.mark.parametrize("k_clay, k_sand", [(1e-6, 1e-5), (1e-5, 1e-6)])
def test_layers_in_series_take_the_materials_conductivities(tmp_path, k_clay, k_sand):
    """Interface head within 2 % of the head drop of the series value at spacing
    0.5 (measured 0.9 % and 1.2 %: the elements across the interface take the
    mean k of their vertices, an O(h) error; 0.4 % and 0.6 % at 0.25)."""
    layers = {
        "materials": {
            "clay": {"c": 2e4, "phi": 0.0, "rho": 1900.0, "k": k_clay},
            "sand": {"c": 0.0, "phi": PHI, "rho": 2000.0, "k": k_sand},
        },
        "regions": [
            {"material": "clay", "polygon": [[0, 0], [4, 0], [4, 2], [0, 2], [0, 0]]},
            {"material": "sand", "polygon": [[0, 2], [4, 2], [4, 4], [0, 4], [0, 2]]},
        ],
        "boundaries": {"top": [[0, 4], [4, 4]]},
        "heads": [{"boundary": "base", "head": 10.0}, {"boundary": "top", "head": 6.0}],
    }
    path = tmp_path / "layers.json"
    path.write_text(json.dumps(layers))
    values = get_scene("slope").resolve(
        {"geometry": str(path), "spacing": 0.5, "analysis": "limit"}
    )
    body = slope_body(values)
    water = slope_water(values, body.sec)
    p = static_pressure(water, body.pts, body.mesh.t, body.material)
    z = body.pts[:, 1]
    head = z + p / (1000.0 * 9.81)
    r_clay, r_sand = 2.0 / k_clay, 2.0 / k_sand
    interface = 10.0 - 4.0 * r_clay / (r_clay + r_sand)
    at = np.isclose(z, 2.0)
    assert np.abs(head[at] - interface).max() < 0.02 * 4.0


def test_runout_under_unequal_heads(tmp_path):
    """Heads 5.5 (left) and 1 (right) through a short run-out: the largest pore
    pressure is rho_w g 5.5 (maximum principle: h <= 5.5 everywhere, z >= 0,
    and the fixed corner (0, 0) of the left boundary keeps h = 5.5)."""
    heads = [{"boundary": "left", "head": 5.5}, {"boundary": "right", "head": 1.0}]
    path = write(tmp_path, heads=heads)
    o = {"spacing": 0.5, "runout": True, "t_end": 0.3, "reduction": 1.5}
    m = npfem.run_scene("slope", {"geometry": path, **o})["metrics"]
    assert m["pore_pressure_max"] == pytest.approx(1000.0 * 9.81 * 5.5, rel=1e-9)
    assert m["deposit_factor_of_safety"] > 0
