"""Pore water in the columns: a wet soil at rest under a water table.

References (Terzaghi's effective stress): below the table the skeleton carries
its buoyant weight, ``s'_v = -(rho_sat - rho_w) g depth`` (the full rho_sat g
above the table), and the pore pressure is hydrostatic, ``p = rho_w g (level -
z)``; free water above the ground loads total stress and pore pressure alike,
so it leaves the effective stress alone.  The elastic column (oedometric,
static) meets the tolerances of its dry tests (tests/scenes/test_scenes.py:
0.5 % in 2D at spacing 0.125; 3D at spacing 0.25: the dry 1.17 %, bounded by
1.5 %), and a column under water equals the dry column of density rho_sat -
rho_w to round-off.  The collapse scene's columns at rest (a cohesion they
never reach) keep their effective geostatic stress as well as the dry ones
keep theirs: the same error against the same closed form, within 5 %.
"""

from __future__ import annotations

import numpy as np
import pytest

from skfem_npfem import ParameterError, get_scene, run_scene
from skfem_npfem.scenes.wet_soil import effective_vertical_stress

RHO, RHO_W, G, H = 2000.0, 1000.0, 9.81, 4.0


def column(**o):
    return run_scene("elastic-column", o)["metrics"]


@pytest.mark.parametrize(
    ("dim", "spacing", "tol"), [(2, 0.125, 5e-3), (3, 0.25, 1.5e-2)]
)
@pytest.mark.parametrize("level", [H, H + 1.0, H / 2])
def test_elastic_column_under_a_water_table(dim, spacing, tol, level):
    m = column(dim=dim, spacing=spacing, rho=RHO, water_level=level)
    assert m["sigma_v_rel_l2"] <= tol
    assert m["sigma_h_rel_l2"] <= tol
    assert m["pore_pressure_rel_l2"] <= 1e-12
    assert m["settlement"] == pytest.approx(m["settlement_exact"], rel=tol)
    # The closed form of the settlement: buoyant below the table.
    M = 1e7 * (1 - 0.3) / ((1 + 0.3) * (1 - 2 * 0.3))
    d = min(level, H)
    dry_part = RHO * G * (H - d) ** 2 / 2
    wet_part = (RHO * G * (H - d) * d) + (RHO - RHO_W) * G * d**2 / 2
    assert m["settlement_exact"] == pytest.approx((dry_part + wet_part) / M, rel=1e-12)
    if level >= H:  # wholly submerged: the dry column of buoyant density
        dry = column(dim=dim, spacing=spacing, rho=RHO - RHO_W)
        for key in ("sigma_v_rel_l2", "sigma_h_rel_l2", "settlement", "base_sigma_v"):
            assert m[key] == pytest.approx(dry[key], rel=1e-9), key


def test_submerged_elastic_column_stays_at_rest():
    scene = get_scene("elastic-column")
    values = scene.resolve({"rho": RHO, "water_level": H + 2.0, "steps": 4})
    run = scene.build(values)
    run.simulation.run(**run.run_kwargs)
    top = [r.extra["settlement_top"] for r in run.simulation.records]
    # The second step sees the settled geometry (updated Lagrangian): the
    # buoyancy acts on the compressed volumes while the particles keep their
    # saturated mass, a change of the order of the strain rho' g H / M
    # (0.14 % beyond the dry column's 0.05 %); then the column is at rest.
    strain = (RHO - RHO_W) * G * H / (1e7 * 0.7 / (1.3 * 0.4))
    assert abs(top[1] / top[0] - 1) <= strain
    assert top[3] == pytest.approx(top[1], rel=1e-5)
    assert top[3] == pytest.approx(top[2], rel=1e-7)
    p = run.simulation.particles
    # Hydrostatic where the particles are (at rest: where the step began).
    depth = H + 2.0 - p.x[:, 1]
    assert np.allclose(p.pore_pressure, RHO_W * G * depth, rtol=1e-8, atol=0)
    assert np.all(p.excess_pore_pressure == 0.0)


def test_undrained_elastic_column_carries_its_weight_by_excess_pore_pressure():
    # Between smooth walls on a fixed base, a mixture that keeps its volume
    # cannot move: loaded by its weight from a stress-free skeleton, the
    # excess pore pressure takes all of the buoyant weight (rho - rho_w) g
    # times the depth, the skeleton nothing, and the top does not settle.
    # The pressure projection lets cells next to the boundary change their
    # volume a little (it acts on the pressure's gradient there).
    m = column(drainage="undrained", water_level=H, spacing=0.25, steps=3)
    assert m["excess_pore_pressure_rel_l2"] < 0.02
    assert m["sigma_v_rel_l2"] < 0.02
    assert abs(m["settlement"]) < 0.01 * (RHO - RHO_W) * G * H**2 / (2 * 1e7)


def test_elastic_column_warns_about_unused_rho_w():
    with pytest.warns(UserWarning, match="rho_w not used"):
        get_scene("elastic-column").resolve({"rho_w": 1025.0})


def collapse_at_rest(geometry: str, **o):
    """A collapse column at rest for 20 ms; its sigma'_v error and pore error."""
    scene = get_scene("column-collapse")
    values = scene.resolve(
        {"geometry": geometry, "c": 1e6, "rest_fraction": 0.0, "t_end": 0.02} | o
    )
    run = scene.build(values)
    sim = run.simulation
    sim.run(**run.run_kwargs)
    p = sim.particles
    z0 = p.x[:, -1] - p.u[:, -1]
    exact = effective_vertical_stress(
        z0, z0.max(), values["rho"], values["gravity"], sim.model.water
    )
    sv = p.stress[:, p.x.shape[1] - 1]
    err = np.linalg.norm(sv - exact) / np.linalg.norm(exact)
    if sim.model.water is None:
        return err, None
    pw = sim.model.water.static_pressure(p.x - p.u, values["gravity"])
    return err, np.linalg.norm(p.pore_pressure - pw) / np.linalg.norm(pw)


@pytest.mark.parametrize(
    ("geometry", "extra"),
    [
        ("plane-strain", {}),
        ("axisymmetric", {}),
        pytest.param("box", {"spacing": 0.02}, marks=pytest.mark.slow),
    ],
)
def test_collapse_column_at_rest_under_water(geometry, extra):
    dry, _ = collapse_at_rest(geometry, rho=RHO, **extra)
    wet, pore = collapse_at_rest(geometry, rho=RHO, water_level=10.0, **extra)
    # The step's static pressure is taken where the particles start the step:
    # they settle by ~1e-5 m, which the pore pressure follows.
    assert pore <= 1e-5
    assert wet <= 1.05 * dry


def test_collapse_water_parameters():
    scene = get_scene("column-collapse")
    values = scene.resolve({"geometry": "axisymmetric", "water_level": 1.0})
    assert values["drainage"] == "drained"
    with pytest.warns(UserWarning, match="rho_w not used"):
        scene.resolve({"rho_w": 1025.0})
    with pytest.raises(ParameterError, match="water_level"):
        scene.resolve({"drainage": "dry", "water_level": 1.0})
