"""Faults: solver failures mid-run and runs killed mid-write never lose a step."""

import numpy as np
import pytest

import skfem_npfem as npfem
import skfem_npfem.io as npio
import skfem_npfem.step.stages as step_module
from skfem_npfem.cli import main
from skfem_npfem.errors import SolverError

# A coarse collapse (6 particles across L0): qdldl, deterministic, ~0.03 s/step.
COARSE = {
    "spacing": 0.2 / 6,
    "t_end": 0.1,
    "rest_fraction": 0.0,
    "linear_solver": "qdldl",
}


def _build(out=None, **over):
    scene = npfem.get_scene("column-collapse")
    values = scene.resolve({**COARSE, **over})
    return scene.build(values, out=out, progress=False)


def test_solver_failure_is_retried_with_half_the_step(monkeypatch):
    # A NumericalError at step 3 with the full dt: the loop halves dt, retries,
    # and the run continues (adaptive stepping).
    original = step_module.solve_step
    calls = []

    def flaky(data, options=None, step=None):
        calls.append((step, data.dt))
        if step == 3 and data.dt > 0.004:
            raise SolverError("NumericalError", step, 7, "injected")
        return original(data, options, step)

    monkeypatch.setattr(step_module, "solve_step", flaky)
    srun = _build()
    sim = srun.simulation
    sim.run(steps=5)
    rec = sim.records[2]
    assert rec.step == 3 and rec.retries == 1
    assert rec.dt == pytest.approx(0.005 / 2, rel=1e-12)
    assert [c[1] for c in calls if c[0] == 3] == [0.005, 0.0025]
    assert all(r.status in ("Solved", "AlmostSolved") for r in sim.records)


def test_failure_past_the_floor_keeps_every_finished_step(tmp_path, monkeypatch):
    # From step 4 on every solve fails: the loop halves dt down to its floor,
    # then stops with a SolverError that says where the results are; steps 1-3
    # are on disk and a checkpoint lets the run continue.
    original = step_module.solve_step

    def broken(data, options=None, step=None):
        if step >= 4:
            raise SolverError("NumericalError", step, 3, "injected")
        return original(data, options, step)

    monkeypatch.setattr(step_module, "solve_step", broken)
    out = tmp_path / "run"
    srun = _build(out=out, output_every=1, checkpoint_every=100)
    with pytest.raises(SolverError) as info:
        srun.simulation.run(**srun.run_kwargs)
    msg = str(info.value)
    assert info.value.status == "NumericalError" and info.value.step == 4
    assert "results up to step 3 are on disk" in msg and "floor" in msg
    entries = npio.read_pvd(out / "result.pvd")
    assert [round(t, 6) for t, _ in entries] == [0.0, 0.005, 0.01, 0.015]
    for _, path in entries:  # every listed step is readable and finite
        mesh = npio.read_step(path)
        assert np.all(np.isfinite(mesh.point_data["stress"]))
    ckpt = npio.latest_checkpoint(out)
    _, meta = npio.load_checkpoint(ckpt)
    assert meta["step"] == 3

    # Continue from the checkpoint with a working solver: identical to a run
    # that never failed.
    monkeypatch.setattr(step_module, "solve_step", original)
    resumed = _build()
    resumed.simulation.restore(ckpt)
    resumed.simulation.run(steps=3)
    clean = _build()
    clean.simulation.run(steps=6)
    for name, arr in clean.simulation.particles.arrays().items():
        np.testing.assert_array_equal(
            resumed.simulation.particles.arrays()[name], arr, err_msg=name
        )


def test_a_failed_run_writes_its_last_finished_step(tmp_path, monkeypatch):
    # Output every 5 steps and a failure at step 4: the last finished step (3,
    # t = 0.015 s) is written as well, so ParaView shows where the run stopped,
    # and it matches the checkpoint of that step particle for particle.
    original = step_module.solve_step

    def broken(data, options=None, step=None):
        if step >= 4:
            raise SolverError("NumericalError", step, 3, "injected")
        return original(data, options, step)

    monkeypatch.setattr(step_module, "solve_step", broken)
    out = tmp_path / "run"
    srun = _build(out=out, output_every=5, checkpoint_every=100)
    with pytest.raises(SolverError, match="results up to step 3 are on disk"):
        srun.simulation.run(**srun.run_kwargs)
    entries = npio.read_pvd(out / "result.pvd")
    assert [round(t, 6) for t, _ in entries] == [0.0, 0.015]
    last = npio.read_step(entries[-1][1])
    state, _ = npio.load_checkpoint(npio.latest_checkpoint(out))
    np.testing.assert_array_equal(last.points[:, :2], state["x"])
    assert last.cells_dict["triangle"].shape[0] > 0


def test_killed_mid_write_then_resume_reproduces_the_run(tmp_path, monkeypatch):
    # The process dies while step 7's VTU is being written (simulated by an
    # interrupt inside the atomic rename). The folder stays readable (no partial
    # file is listed) and --resume reproduces the uninterrupted result exactly.
    sets = [
        "--set",
        "spacing=0.03333333333333333",
        "--set",
        "t_end=0.06",
        "--set",
        "rest_fraction=0",
        "--set",
        "linear_solver=qdldl",
        "--set",
        "output_every=1",
        "--set",
        "checkpoint_every=5",
    ]
    ref = tmp_path / "ref"
    assert main(["run", "column-collapse", *sets, "--out", str(ref), "--quiet"]) == 0

    run = tmp_path / "run"
    real_replace = npio.files.os.replace

    def dying_replace(src, dst):
        if str(dst).endswith("result_000007.vtu"):
            raise KeyboardInterrupt  # the process is killed mid-write
        return real_replace(src, dst)

    monkeypatch.setattr(npio.files.os, "replace", dying_replace)
    assert main(["run", "column-collapse", *sets, "--out", str(run), "--quiet"]) == 130
    monkeypatch.setattr(npio.files.os, "replace", real_replace)
    listed = npio.read_pvd(run / "result.pvd")
    assert len(listed) == 7  # steps 0..6
    for _, path in listed:
        npio.read_step(path)
    assert not (run / "result_000007.vtu").exists()

    assert (
        main(
            ["run", "column-collapse", *sets, "--out", str(run), "--quiet", "--resume"]
        )
        == 0
    )
    a = npio.read_pvd(ref / "result.pvd")
    b = npio.read_pvd(run / "result.pvd")
    assert [t for t, _ in a] == [t for t, _ in b]
    last_a, last_b = npio.read_step(a[-1][1]), npio.read_step(b[-1][1])
    np.testing.assert_array_equal(last_a.points, last_b.points)
    for key in ("stress", "velocity", "displacement", "plastic_strain_eq"):
        np.testing.assert_array_equal(last_a.point_data[key], last_b.point_data[key])
