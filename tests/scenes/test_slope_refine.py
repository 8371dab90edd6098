"""A slope run-out with particles added where the sliding soil thins."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from slope_fos import RUNOUT

from skfem_npfem.io import load_checkpoint, read_pvd, read_step
from skfem_npfem.scenes import get_scene, run_scene
from skfem_npfem.scenes.slope.body import run_out_mesher, slope_body

#: The dry sand cut of the slope study's run-out (86 particles, about 200 steps).
CUT = RUNOUT
#: Deposit surface slope above phi allowed, deg (as the uniform run's test).
SLOPE_TOL = 5.0


@pytest.fixture(scope="module")
def refined(tmp_path_factory):
    out = tmp_path_factory.mktemp("slope") / "run"
    return out, run_scene("slope", {**CUT, "refine": "surface"}, out=out)


def test_the_thinning_soil_gains_particles_with_mass_and_momentum_kept(refined):
    out, summary = refined
    m = summary["metrics"]
    assert m["inserted"] > 0
    assert m["n_particles"] == 86
    assert m["n_particles_final"] == m["n_particles"] + m["inserted"]
    assert abs(m["mass_change"]) < 1e-14
    arrays, meta = load_checkpoint(sorted(out.glob("checkpoint_*.npz"))[-1])
    assert max(r["insertion_momentum_error"] for r in meta["records"]) < 1e-12
    # ParaView follows each particle: the initial ones keep ids 0..85, in order.
    series = read_pvd(out / "result.pvd")
    first, last = read_step(series[0][1]), read_step(series[-1][1])
    total = first.point_data["mass"].sum()
    assert last.point_data["mass"].sum() == pytest.approx(total, rel=1e-12)
    ids = np.asarray(last.point_data["particle_id"])
    assert ids.size == m["n_particles_final"]
    np.testing.assert_array_equal(ids[:86], np.arange(86))
    assert np.unique(ids).size == ids.size
    # The added particles carry the spacing of the particles they came from.
    np.testing.assert_allclose(arrays["spacing"], CUT["spacing"])


def test_the_refined_deposit_is_at_rest_and_statically_admissible(refined):
    """A cohesionless deposit at rest stands (its own F >= 1), no steeper than phi."""
    m = refined[1]["metrics"]
    assert m["at_rest"]
    assert m["deposit_factor_of_safety"] >= 1.0
    assert m["deposit_max_slope"] <= 30.0 + SLOPE_TOL
    # The slide moves part of the soil above the toe, not more.
    above_toe = 2.0 * 1.6 + 0.5 * 2.0 * 2.0 / math.tan(math.radians(60.0))
    assert 0 < m["moved_volume"] < above_toe


def test_an_adaptive_factor_of_safety_before_the_run_out():
    """refine=strain+surface: F from refined lattices, the run-out on the uniform."""
    uniform = run_scene("slope", {**CUT, "runout": False})["metrics"]
    both = run_scene("slope", {**CUT, "refine": "strain+surface", "t_end": 0.05})
    m = both["metrics"]
    history = m["refine_history"]
    assert history is not None and len(history) >= 2
    assert history[0][0] == 86 and history[-1][0] > 86  # the lattices grow
    assert history[0][1] == pytest.approx(uniform["factor_of_safety"], rel=1e-9)
    assert m["factor_of_safety"] == pytest.approx(history[-1][1], rel=1e-12)
    assert m["n_particles"] == 86  # the run-out starts on the uniform lattice


@pytest.mark.filterwarnings("ignore:slope. regions.0.")  # the thin foundation
def test_a_regions_own_spacing_is_what_its_particles_keep(tmp_path):
    """A finer region of a cross-section stays fine in the run-out.

    The sand cut drawn as a file, its slope region at half the section's
    spacing: the particles of that region carry its spacing into the run-out
    (the alpha test's and the insertion's target), the foundation's keep the
    section's; a section without region spacings is meshed as before.
    """
    toe = 1.6 + 2.0 / math.tan(math.radians(60.0))
    section = {
        "materials": {"sand": {"c": 0, "phi": 30, "rho": 2000}},
        "regions": [
            {"material": "sand", "polygon": [[0, 0], [6.8, 0], [6.8, 0.4], [0, 0.4]]},
            {
                "material": "sand",
                "spacing": 0.2,
                "polygon": [[0, 0.4], [toe, 0.4], [1.6, 2.4], [0, 2.4]],
            },
        ],
        "supports": {"base": "fixed", "sides": "rollers"},
    }
    for r in section["regions"]:
        r["polygon"].append(r["polygon"][0])
    path = tmp_path / "cut.json"
    path.write_text(json.dumps(section))
    out = tmp_path / "run"
    over = {"geometry": str(path), "runout": True, "spacing": 0.4, "t_end": 0.05}
    m = run_scene("slope", {**over, "refine": "surface"}, out=out)["metrics"]
    arrays, _ = load_checkpoint(sorted(out.glob("checkpoint_*.npz"))[-1])
    first = read_step(read_pvd(out / "result.pvd")[0][1])
    y0 = np.asarray(first.points)[:, 1]
    spacing = arrays["spacing"][: m["n_particles"]]
    assert np.all(spacing[y0 > 0.4 + 1e-9] == 0.2)
    assert np.all(spacing[y0 < 0.4 - 1e-9] == 0.4)
    assert np.all(spacing[np.abs(y0 - 0.4) < 1e-9] <= 0.4)
    assert abs(m["mass_change"]) < 1e-14
    # Without region spacings the remesher is the section's, as before.
    body = slope_body(get_scene("slope").resolve(CUT))
    mesher = run_out_mesher(body, 1.3)
    assert mesher.spacing is None and mesher.h == CUT["spacing"]
