"""A footing pushed with particles added where the soil stretches (refine=bodies)
and where it flows plastically (refine=strain)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from skfem_npfem.errors import ParameterError
from skfem_npfem.io import load_checkpoint, read_pvd, read_step
from skfem_npfem.scenes import run_scene
from skfem_npfem.scenes.refinement import insert_metrics

COARSE = {"spacing": 0.1, "refine": "bodies"}  # 957 particles, 40 steps
STRAIN = {**COARSE, "refine": "strain"}


@pytest.fixture(scope="module")
def coarse_runs(tmp_path_factory):
    """``runs(given)``: the coarse footing run with ``given``, run once a module."""
    done = {}

    def runs(given):
        key = given["refine"]
        if key not in done:
            out = tmp_path_factory.mktemp(key.replace("+", "_")) / "run"
            done[key] = out, run_scene("footing-penetration", given, out=out), given
        return done[key]

    return runs


@pytest.fixture(params=[COARSE, STRAIN], ids=["bodies", "strain"])
def refined(coarse_runs, request):
    return coarse_runs(request.param)


def test_refining_by_strain_rate_adds_particles_where_the_soil_yields(coarse_runs):
    out, strain, _ = coarse_runs(STRAIN)
    _, bodies, _ = coarse_runs(COARSE)
    n0 = strain["metrics"]["n_particles"]
    assert strain["metrics"]["inserted"] > 5 * bodies["metrics"]["inserted"]
    last = read_step(read_pvd(out / "result.pvd")[-1][1])
    eps, ids = last.point_data["plastic_strain_eq"], last.point_data["particle_id"]
    # The added particles are in the soil that flowed: each has a plastic
    # strain (the elastic soil's are round-off, < 1e-9), and most of them more
    # than 5 % where less than half of the initial particles have that much.
    added = ids >= n0
    assert np.all(eps[added] > 1e-3)
    assert np.mean(eps[added] > 0.05) > 0.8 > 0.5 > np.mean(eps[~added] > 0.05)
    # Each step records how many particles its target halved.
    records = summary_records(out)
    assert max(r["refined"] for r in records) > 0
    # The load at w = 0.1 B moves by less than the coarse lattice's own spread.
    assert strain["metrics"]["bearing_factor"] == pytest.approx(
        bodies["metrics"]["bearing_factor"], rel=0.1
    )


def test_particles_are_added_with_mass_kept_and_ids_stable(refined):
    out, summary, _ = refined
    m = summary["metrics"]
    assert m["inserted"] > 0
    assert m["n_particles_final"] == m["n_particles"] + m["inserted"]
    ids = mass_kept_and_ids(out, m["n_particles_final"])
    # A particle keeps its id and its row: the first rows are the initial ones.
    np.testing.assert_array_equal(ids[: m["n_particles"]], np.arange(m["n_particles"]))
    # Every step's insertion conserved momentum to round-off.
    arrays, meta = load_checkpoint(sorted(out.glob("checkpoint_*.npz"))[-1])
    errors = [r["insertion_momentum_error"] for r in meta["records"]]
    assert max(errors) < 1e-12
    assert arrays["ids"].size == m["n_particles_final"]


def test_a_run_resumed_across_insertions_repeats_the_uninterrupted_one(
    refined, tmp_path
):
    out, summary, given = refined
    cut = tmp_path / "cut"
    shutil.copytree(out, cut)  # the folder a kill -9 after step 25 leaves
    (cut / "checkpoint_000040.npz").unlink()
    _, meta20 = load_checkpoint(cut / "checkpoint_000020.npz")
    added_after = sum(r["inserted"] for r in summary_records(out)[20:])
    assert added_after > 0  # the resumed part inserts particles
    resumed = run_scene("footing-penetration", given, out=cut, resume=True)
    assert resumed["metrics"]["inserted"] == summary["metrics"]["inserted"]
    a, _ = load_checkpoint(out / "checkpoint_000040.npz")
    b, _ = load_checkpoint(cut / "checkpoint_000040.npz")
    assert sorted(a) == sorted(b)
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)
    assert meta20["step"] == 20


def mass_kept_and_ids(out, n_final: int) -> np.ndarray:
    """The last step's ids, after checking the total mass and the ids' count.

    Conservation: the total mass of the run's last step is the initial one
    (to round-off); every particle has its own id.
    """
    series = read_pvd(out / "result.pvd")
    a, b = read_step(series[0][1]), read_step(series[-1][1])
    assert b.point_data["mass"].sum() == pytest.approx(
        a.point_data["mass"].sum(), rel=1e-12
    )
    ids = b.point_data["particle_id"]
    assert np.unique(ids).size == ids.size == n_final
    return ids


def summary_records(out) -> list[dict]:
    """The step records of the last checkpoint of ``out``."""
    return load_checkpoint(sorted(out.glob("checkpoint_*.npz"))[-1])[1]["records"]


@pytest.mark.filterwarnings("ignore:footing-penetration")  # P1 FEM's locking note
def test_a_baseline_method_refuses_refinement():
    with pytest.raises(ParameterError, match="refine"):
        run_scene(
            "footing-penetration",
            {**COARSE, "method": "fem-remap", "penetration": 0.1},
        )


@pytest.mark.slow  # 20 s each; the dead loads' rebuild is unit-tested in tests/mesh
@pytest.mark.parametrize("merge", [0.0, 0.3])
def test_the_cone_with_its_surcharge_refines_and_keeps_its_dead_load(tmp_path, merge):
    from skfem_npfem.scenes import get_scene

    D = 0.0357
    scene = get_scene("cone-penetration")
    given = {"spacing": D / 6, "penetration": 2 * D, "dt": D / 6 / 0.02}
    values = scene.resolve({**given, "refine": "bodies", "refine_merge": merge})
    srun = scene.build(values)
    sim = srun.simulation
    total = sim.model.loads.sum(axis=0)
    n0, mass = sim.particles.n, sim.particles.mass.sum()
    sim.progress = False
    sim.run(**srun.run_kwargs)
    counts = insert_metrics(sim)
    assert counts["inserted"] > 0  # particles were added, and merged if asked
    assert (counts["merged"] > 0) == (merge > 0)
    assert sim.particles.n == n0 + counts["inserted"] - counts["merged"]
    # The surcharge's dead load stays on the particles it was put on.
    np.testing.assert_allclose(sim.model.loads.sum(axis=0), total, rtol=1e-12)
    assert sim.model.loads.shape[0] == sim.particles.n
    assert sim.particles.mass.sum() == pytest.approx(mass, rel=1e-12)


def test_merging_crowded_particles_keeps_the_mass_and_the_ids_unique(tmp_path):
    out = tmp_path / "merge"
    summary = run_scene("footing-penetration", {**COARSE, "refine_merge": 0.3}, out=out)
    m = summary["metrics"]
    assert m["merged"] > 0 and m["inserted"] > 0
    assert m["n_particles_final"] == m["n_particles"] + m["inserted"] - m["merged"]
    mass_kept_and_ids(out, m["n_particles_final"])
    records = summary_records(out)
    assert max(r["merging_momentum_error"] for r in records) < 1e-12


def test_a_footing_pushed_ten_times_faster_a_spacing_a_step_refines_stably(refined):
    # The extreme: ten times the default speed with the footing moving a whole
    # spacing a step (four times the default), particles added every few steps.
    _, slow, given = refined
    fast = run_scene("footing-penetration", {**given, "speed": 10.0, "dt": 0.1 / 10.0})[
        "metrics"
    ]
    assert fast["inserted"] > 0
    assert fast["bearing_factor"] == pytest.approx(
        slow["metrics"]["bearing_factor"], rel=0.05
    )
