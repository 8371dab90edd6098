"""A run into a used folder: the folder holds the earlier results or the new run's.

Each test first runs ``elastic-column`` into a folder (the *earlier* results),
then a second run into it that fails at one point -- a refused parameter, its
set-up, its first solve, a later step, a signal, SIGKILL -- and checks that the
folder holds exactly the earlier files (same names, same bytes) or only the new
run's, never a mix and never nothing.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import signal
import subprocess
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

import skfem_npfem as npfem
import skfem_npfem.io as npio
import skfem_npfem.io.run_folder as run_folder
import skfem_npfem.scenes.slope.stages as slope_stages
import skfem_npfem.step.stages as step_module
from skfem_npfem.cli import interrupted_message, main
from skfem_npfem.errors import RunInterrupted, SolverError

ROOT = Path(__file__).resolve().parents[2]
EARLIER = ["run", "elastic-column", "--set", "spacing=0.5", "--quiet"]
COLLAPSE = {"spacing": 0.05, "t_end": 0.03, "output_every": 1}
NEW = ["run", "column-collapse", "--quiet"]
NEW += [a for k, v in COLLAPSE.items() for a in ("--set", f"{k}={v}")]


def cli(argv: list[str]) -> tuple[int, str]:
    """Run the CLI in-process; return (exit code, stderr)."""
    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()):
        code = main(argv)
    return code, err.getvalue()


def files(folder: Path) -> dict[str, str]:
    """Every entry of ``folder`` but the lock (recursively), with its hash."""
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        if p.is_file()
        else "dir"
        for p in sorted(folder.rglob("*"))
        if p.name != npio.LOCK_NAME
    }


@pytest.fixture
def used(tmp_path: Path) -> tuple[Path, dict[str, str]]:
    """A folder with the earlier run's results, and their hashes."""
    d = tmp_path / "D"
    assert cli([*EARLIER, "--out", str(d)])[0] == 0
    before = files(d)
    assert {"checkpoint_000001.npz", "result_000001.vtu", "scene.json"} <= set(before)
    return d, before


def new_run_only(d: Path, steps: list[int], checkpoints: list[int]) -> None:
    """``d`` holds only the collapse's files: these steps and checkpoints."""
    expected = {f"result_{s:06d}.vtu" for s in steps}
    expected |= {f"checkpoint_{s:06d}.npz" for s in checkpoints}
    expected |= {"result.pvd"}
    expected |= {"result.vtu.series", "scene.json"}
    assert set(files(d)) == expected
    assert json.loads((d / "scene.json").read_text())["scene"] == "column-collapse"
    assert [p.name for _, p in npio.read_pvd(d / "result.pvd")] == sorted(
        f"result_{s:06d}.vtu" for s in steps
    )


def failing_from(monkeypatch, first: int) -> None:
    """Every cone solve of step ``first`` or later fails."""
    original = step_module.solve_step

    def broken(data, options=None, step=None):
        if step >= first:
            raise SolverError("NumericalError", step, 3, "injected")
        return original(data, options, step)

    monkeypatch.setattr(step_module, "solve_step", broken)


def test_a_refused_run_changes_nothing(used):
    d, before = used
    code, err = cli([*NEW, "--set", "psi=40", "--out", str(d)])
    assert code == 2 and "psi" in err
    assert files(d) == before


def test_a_run_whose_set_up_fails_keeps_the_earlier_results(used, monkeypatch):
    # The slope's strength reduction fails after the run started (a floating
    # region, which used to fail there, is now refused by the pre-run check).
    d, before = used

    def broken(*args, **kwargs):
        raise npfem.NpfemError("injected: strength reduction found no factor")

    monkeypatch.setattr(slope_stages, "strength_reduction", broken)
    argv = "run slope --set analysis=limit --set refine=none --set spacing=2".split()
    code, err = cli([*argv, "--out", str(d), "--quiet"])
    assert code == 2 and err.startswith("error:") and "injected" in err, err
    assert files(d) == before


def test_a_run_whose_first_solve_fails_keeps_the_earlier_results(used, monkeypatch):
    d, before = used
    failing_from(monkeypatch, 1)
    code, err = cli([*NEW, "--out", str(d)])
    assert code == 2 and "injected" in err and "on disk" not in err, err
    assert files(d) == before


def test_a_run_failing_later_leaves_its_own_steps_and_resumes(used, monkeypatch):
    d, before = used
    failing_from(monkeypatch, 3)
    code, err = cli([*NEW, "--out", str(d)])
    assert code == 2 and "results up to step 2 are on disk" in err, err
    new_run_only(d, [0, 1, 2], [2])
    assert files(d)["result_000001.vtu"] != before["result_000001.vtu"]
    monkeypatch.undo()
    assert cli([*NEW, "--out", str(d), "--resume"])[0] == 0
    new_run_only(d, list(range(7)), [2, 6])


@pytest.fixture
def sigint_raises():
    """SIGINT raises KeyboardInterrupt during the test; put back after."""
    found = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, found)


@pytest.mark.parametrize("abandon", [True, False])
def test_an_interrupted_run(used, monkeypatch, sigint_raises, abandon):
    # Two signals in step 1 abandon it: nothing to keep, the earlier results
    # stay.  One signal in step 2: the run stops after it with its checkpoint,
    # which replaces the earlier results and can be resumed.
    d, before = used
    original = step_module.solve_step

    def signalling(data, options=None, step=None):
        if step == (1 if abandon else 2):
            for _ in range(2 if abandon else 1):
                os.kill(os.getpid(), signal.SIGINT)
        return original(data, options, step)

    monkeypatch.setattr(step_module, "solve_step", signalling)
    scene = npfem.get_scene("column-collapse")
    with pytest.raises(RunInterrupted) as info:
        scene.run(COLLAPSE, out=d, summary=d / "summary.json", progress=False)
    err = info.value
    if abandon:
        assert files(d) == before
        assert err.checkpoint is None and err.summary_path is None
        said = interrupted_message(err)
        assert said.endswith("nothing written (no step finished: --out is as it was)")
    else:
        assert err.checkpoint == d / "checkpoint_000002.npz"
        assert err.summary_path == d / "summary.json"
        names = set(files(d)) - {"summary.json"}
        assert names == {f"result_00000{s}.vtu" for s in range(3)} | {
            "checkpoint_000002.npz",
            "result.pvd",
            "result.vtu.series",
            "scene.json",
        }


KILLER = """
import os, signal, sys
import skfem_npfem.step.stages as stages
from skfem_npfem.cli import interrupted_message, main
original = stages.solve_step
def dying(data, options=None, step=None):
    if step == int(sys.argv[1]):
        os.kill(os.getpid(), signal.SIGKILL)
    return original(data, options, step)
stages.solve_step = dying
main(sys.argv[2:])
"""


@pytest.mark.parametrize("step", [1, 3])
def test_a_run_killed_with_sigkill_then_a_fresh_run(used, step):
    # Killed in step 1: the earlier results; in step 3: the new run's steps
    # 1-2.  The next fresh run starts clean either way.
    d, before = used
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    argv = [sys.executable, "-c", KILLER, str(step), *NEW, "--out", str(d)]
    assert subprocess.run(argv, env=env, check=False).returncode == -signal.SIGKILL
    staged = [p.name for p in d.iterdir() if p.name.startswith(".staging-")]
    if step == 1:
        assert len(staged) == 1  # removed by the next run
        assert {k: v for k, v in files(d).items() if staged[0] not in k} == before
    else:
        assert not staged
        new_run_only(d, [0, 1, 2], [])
    assert cli([*NEW, "--out", str(d)])[0] == 0
    new_run_only(d, list(range(7)), [6])


def test_a_commit_cut_short_is_finished_by_the_next_run(tmp_path, monkeypatch):
    # Killed while it moves its files in (here: a rename that fails): the next
    # run into the folder finishes the move, the earlier files are all gone.
    d = tmp_path / "D"
    d.mkdir()
    for name in ("result_000001.vtu", "result_000002.vtu", "scene.json"):
        (d / name).write_text("earlier")
    run = npio.RunFolder(d, fresh=True)
    real, calls = os.replace, []

    def dying(src, dst):
        calls.append(dst)
        if len(calls) == 3:  # the staging rename, the stage rename, one move
            raise OSError("killed")
        real(src, dst)

    with pytest.raises(OSError), run.hold():
        for name in ("result_000001.vtu", "scene.json"):
            (run.path / name).write_text("new")
        monkeypatch.setattr(run_folder.os, "replace", dying)
        run.commit()
    monkeypatch.undo()
    assert any(p.name.startswith(".moving-") for p in d.iterdir())
    with npio.RunFolder(d, fresh=False).hold():
        pass
    assert {k: (d / k).read_text() for k in files(d)} == {
        "result_000001.vtu": "new",
        "scene.json": "new",
    }


@pytest.mark.parametrize("summary", ["summary.json", "s.json"])
def test_a_fresh_run_replaces_the_mechanism_and_summary(tmp_path, summary):
    m = tmp_path / "M"
    argv = "run slope --set analysis=limit --set refine=none --set spacing=2".split()
    assert cli([*argv, "--out", str(m), "--summary", str(m / summary)])[0] == 0
    assert {"mechanism.npz", summary} <= set(files(m))
    assert cli([*EARLIER, "--out", str(m)])[0] == 0
    assert set(files(m)) == {
        "checkpoint_000001.npz",
        "result_000000.vtu",
        "result_000001.vtu",
        "result.pvd",
        "result.vtu.series",
        "scene.json",
    }
