"""A column on a graded lattice (refine=surface): fewer particles, same column."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from skfem_npfem.errors import ParameterError
from skfem_npfem.io import read_pvd, read_step
from skfem_npfem.scenes import get_scene, run_scene
from skfem_npfem.scenes.collapse.plane_strain import graded_lattice, lattice


def test_graded_lattice_keeps_the_fine_band_and_every_other_core_point():
    h, band = 0.01, 0.04
    x, spacing = graded_lattice(0.0, 0.2, 0.4, h, band, symmetric=True)
    full = lattice(0.0, 0.2, 0.4, h)
    fine = spacing == h
    # The band along the top, the free side and the floor is the full lattice.
    in_band = (
        (full[:, 1] > 0.4 - band) | (full[:, 1] < band) | (full[:, 0] > 0.2 - band)
    )
    assert fine.sum() == in_band.sum()
    # The core has a quarter of the points: every other one in each direction.
    core = (~in_band).sum()
    assert (~fine).sum() == pytest.approx(core / 4, rel=0.1)
    assert np.all(spacing[~fine] == 2 * h)
    # The symmetry wall x = 0 is not a free surface: no fine band there.
    assert not np.any(
        fine & (x[:, 0] < band) & (x[:, 1] > band) & (x[:, 1] < 0.4 - band)
    )
    free_standing, _ = graded_lattice(-0.2, 0.2, 0.4, h, band, symmetric=False)
    assert np.sum(free_standing[:, 0] < -0.2 + band) > 0


def test_the_graded_column_has_the_mass_and_weight_of_the_uniform_one():
    scene = get_scene("column-collapse")
    runs = {}
    for refine in ("none", "surface"):
        values = scene.resolve({"spacing": 0.01, "refine": refine})
        runs[refine] = scene.build(values).simulation.particles
    uniform, graded = runs["none"], runs["surface"]
    assert graded.n < 0.6 * uniform.n
    # Masses from the graded lattice's own cells: the same total, rho L0 H0.
    assert graded.mass.sum() == pytest.approx(1800.0 * 0.2 * 0.4, rel=1e-12)
    assert uniform.mass.sum() == pytest.approx(graded.mass.sum(), rel=1e-12)
    # The floor carries the column's weight in both.
    assert graded.wall_force[:, 0].sum() == pytest.approx(
        uniform.wall_force[:, 0].sum(), rel=1e-9
    )


def test_a_graded_column_runs_and_the_box_refuses_it(tmp_path):
    summary = run_scene(
        "column-collapse",
        {"spacing": 0.02, "refine": "surface", "t_end": 0.1, "rest_fraction": 0.0},
        out=tmp_path / "g",
    )
    m = summary["metrics"]
    assert m["mass_change"] == pytest.approx(0.0, abs=1e-12)
    assert m["inserted"] == 0 and m["merged"] == 0  # the graded lattice only
    with pytest.raises(ParameterError, match="refine"):
        run_scene("column-collapse", {"geometry": "box", "refine": "surface"})
    with pytest.raises(ParameterError, match="refine_ratio"):
        run_scene("column-collapse", {"refine": "surface", "refine_ratio": 1.2})


def test_a_graded_column_with_insertion_adds_particles_and_keeps_its_mass():
    m = run_scene(
        "column-collapse",
        {
            "spacing": 0.02,
            "refine": "surface",
            "refine_ratio": 1.6,
            "t_end": 0.15,
            "rest_fraction": 0.0,
        },
    )["metrics"]
    assert m["inserted"] > 0
    assert m["mass_change"] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.filterwarnings("ignore:column-collapse")  # detached grains, not at rest
def test_a_deposit_merging_its_crowded_particles_keeps_its_mass():
    # The extreme: a coarse graded column whose deposit compacts under its own
    # weight, pairs closer than 0.3 spacings merged as it settles.
    m = run_scene(
        "column-collapse",
        {"spacing": 0.0167, "dt": 0.01, "refine": "surface", "refine_merge": 0.3},
    )["metrics"]
    assert m["merged"] > 0 and m["inserted"] == 0
    assert m["mass_change"] == pytest.approx(0.0, abs=1e-12)
    assert np.isfinite(m["runout"]) and m["runout"] > 0.2  # it spread


@pytest.mark.parametrize("geometry", ["quarter-cylinder", "axisymmetric"])
def test_a_graded_cylinder_has_the_mass_and_weight_of_the_uniform_one(geometry):
    """The seed column at r0/18: fewer particles, the same column."""
    scene = get_scene("column-collapse")
    runs = {}
    for refine in ("none", "surface"):
        values = scene.resolve({"geometry": geometry, "refine": refine})
        runs[refine] = scene.build(values).simulation
    uniform, graded = runs["none"].particles, runs["surface"].particles
    assert graded.n < 0.6 * uniform.n  # measured 5 830 of 10 027; 388 of 703
    assert graded.mass.sum() == pytest.approx(uniform.mass.sum(), rel=1e-12)
    assert graded.wall_force[:, 0].sum() == pytest.approx(
        uniform.wall_force[:, 0].sum(), rel=1e-9
    )
    spacing = runs["surface"].mesh_source.spacing
    h, r0, h0 = 0.039 / 18, 0.039, 0.078
    r = np.linalg.norm(graded.x[:, :-1], axis=1)
    z = graded.x[:, -1]
    coarse = spacing == 2 * h
    assert np.all((spacing == h) | coarse)
    # The fine band: four spacings along the top, the floor and the free side.
    near = (z > h0 - 4.5 * h) | (z < 4.5 * h) | (r > r0 - 4.5 * h)
    assert np.all(near[~coarse])
    assert not np.any(coarse & ((z > h0 - 3.5 * h) | (z < 3.5 * h)))
    assert not np.any(coarse & (r > r0 - 3.5 * h))
    # The symmetry planes (and the axis) are no free surface: the core reaches them.
    assert np.any(coarse & (graded.x[:, 0] == 0.0))


def test_the_quarter_cylinders_speed_defaults_reach_its_run():
    """Unset, the graded lattice, the fast preset and the step control run."""
    base = {"geometry": "quarter-cylinder", "spacing": 0.039 / 6, "t_end": 0.06}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # not at rest at t_end: expected
        s = run_scene("column-collapse", base)
    p, m, hist = s["parameters"], s["metrics"], s["history"]
    assert (p["refine"], p["accuracy"], p["dt"], p["max_displacement"]) == (
        "surface",
        "fast",
        6e-3,
        1.0,
    )
    scene = get_scene("column-collapse")
    uniform = scene.build(scene.resolve({**base, "refine": "none"})).simulation
    assert m["n_particles"] < uniform.particles.n  # graded: fewer particles
    assert m["mass_change"] == 0.0
    # Displacement-controlled steps: each measured against the mesh's spacing,
    # none longer than 6 ms, together exactly the run's time.
    assert all(h["status"] == "Solved" for h in hist)
    assert all(0 < h["dt"] <= 6e-3 for h in hist)
    assert sum(h["dt"] for h in hist) == pytest.approx(0.06, rel=1e-12)
    ratios = [h["max_displacement_ratio"] for h in hist]
    assert all(np.isfinite(ratios)) and max(ratios) < 1.0


def test_a_column_refined_where_it_flows_adds_particles_in_the_sliding_soil(tmp_path):
    over = {"spacing": 0.02, "refine": "strain", "refine_ratio": 1.6, "t_end": 0.15}
    out = tmp_path / "s"
    m = run_scene("column-collapse", {**over, "rest_fraction": 0.0}, out=out)
    m = m["metrics"]
    assert m["inserted"] > 0 and m["merged"] == 0
    assert m["mass_change"] == pytest.approx(0.0, abs=1e-12)
    last = read_step(read_pvd(out / "result.pvd")[-1][1])
    eps, ids = last.point_data["plastic_strain_eq"], last.point_data["particle_id"]
    n0 = ids.size - m["inserted"]  # the initial particles keep ids 0 .. n0 - 1
    added = ids >= n0
    assert added.sum() == m["inserted"] and n0 == 11 * 21
    # The added particles are in soil that has flowed (each over 1 % of
    # plastic strain; measured at least 2 %), where the core behind the
    # failure wedge has barely yielded (13 % of the initial particles under 1 %).
    assert np.all(eps[added] > 0.01)
    assert np.mean(eps[~added] < 0.01) > 0.05
    with pytest.raises(ParameterError, match="refine_ratio"):
        run_scene("column-collapse", {"refine": "strain", "t_end": 0.01})
    with pytest.raises(ParameterError, match="plane strain only"):
        run_scene("column-collapse", {"geometry": "axisymmetric", "refine": "strain"})
