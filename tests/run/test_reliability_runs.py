"""A run's folder, its interruption and its messages, as a new user meets them.

Each test starts from the command that went wrong (scaled down to the coarse
collapse of ``COARSE``: 72 particles, qdldl, a few hundredths of a second per
step) and checks what the user must see instead.
"""

from __future__ import annotations

import io
import json
import os
import re
import signal
import subprocess
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

import skfem_npfem as npfem
import skfem_npfem.io as npio
from skfem_npfem import ParameterError
from skfem_npfem.cli import main
from skfem_npfem.run.control import Progress

COARSE = [
    "spacing=0.03333333333333333",
    "rest_fraction=0",
    "linear_solver=qdldl",
]
ROOT = Path(__file__).resolve().parents[2]


def cli(argv: list[str]) -> tuple[int, str, str]:
    """Run the CLI in-process; return (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(out):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def sets(*items: str) -> list[str]:
    return [arg for item in items for arg in ("--set", item)]


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file of a folder (recursively) with its bytes."""
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


# --------------------------------------------- a refused run touches nothing --
@pytest.mark.parametrize(
    ("item", "says"),
    [
        ("psi=40", "invalid psi=40.0: at most phi = 30 degrees"),
        ("spacing=1.0", "invalid spacing=1.0"),
        ("dt=1e-8", "invalid dt=1e-08"),  # the step-count check, after the build
    ],
)
def test_a_refused_run_leaves_the_previous_results_intact(tmp_path, item, says):
    # Reproducer: a run with --summary into out/k, then a run into out/k that
    # a scene check refuses: exit 2 with the right error, but every VTU, the
    # .pvd and the checkpoints were gone and scene.json said psi = 40.
    d = tmp_path / "k"
    base = ["run", "column-collapse", "--out", str(d), "--quiet"]
    argv = [*base, *sets(*COARSE, "t_end=0.02"), "--summary", str(d / "s.json")]
    assert cli(argv)[0] == 0
    before = snapshot(d)
    assert {"result.pvd", "checkpoint_000004.npz", "scene.json"} <= set(before)
    code, _, err = cli([*base, *sets(item)])
    assert code == 2 and err.startswith(f"error: {says}"), err
    assert snapshot(d) == before


def test_a_refused_run_into_a_new_folder_creates_nothing(tmp_path):
    d, s = tmp_path / "new" / "k", tmp_path / "other" / "s.json"
    argv = ["run", "column-collapse", *sets("psi=40"), "--out", str(d)]
    code, _, err = cli([*argv, "--summary", str(s)])
    assert code == 2 and "psi" in err
    assert sorted(tmp_path.iterdir()) == []


def test_a_refused_resume_leaves_the_results_intact(tmp_path):
    d = tmp_path / "k"
    base = ["run", "column-collapse", "--out", str(d), "--quiet"]
    assert cli([*base, *sets(*COARSE, "t_end=0.02")])[0] == 0
    before = snapshot(d)
    code, _, err = cli([*base, *sets(*COARSE, "t_end=0.01"), "--resume"])
    assert code == 2 and "invalid t_end=0.01" in err
    assert snapshot(d) == before


# ------------------------------------------ two runs into one folder at once --
HOLDER = """
import sys, time
from skfem_npfem.io import folder_lock
with folder_lock(sys.argv[1]):
    print("locked", flush=True)
    time.sleep(120)
"""


def test_a_second_run_into_a_busy_folder_is_refused_and_kill_9_frees_it(tmp_path):
    # Reproducer: two runs into one --out at the same time both succeeded and
    # left a mixture of their steps and checkpoints.  Here the first run is a
    # process holding the folder the way a run does; then it is killed with
    # SIGKILL, which must not leave the folder locked.
    d = tmp_path / "k"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(d)],
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert holder.stdout.readline().strip() == "locked"
        argv = ["run", "column-collapse", *sets(*COARSE, "t_end=0.01")]
        code, _, err = cli([*argv, "--out", str(d), "--quiet"])
        lines = err.strip().splitlines()
        assert code == 2 and len(lines) == 1, err
        assert lines[0].startswith(f"error: invalid out='{d}': a folder no other run")
        assert f"process {holder.pid}" in lines[0]
        assert not list(d.glob("result*")) and not (d / "scene.json").exists()
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    assert cli([*argv, "--out", str(d), "--quiet"])[0] == 0
    assert (d / "result.pvd").is_file()


def test_a_resume_into_a_busy_folder_names_the_lock_not_a_missing_checkpoint(
    tmp_path,
):
    # Reproducer: --resume into a folder a fresh run was writing to said "no
    # checkpoint_*.npz to resume from" (the running run stages its files),
    # which sends the user looking for a file instead of at the other run.
    d = tmp_path / "k"
    argv = ["run", "column-collapse", *sets(*COARSE, "t_end=0.01"), "--resume"]
    with npio.folder_lock(d):
        code, _, err = cli([*argv, "--out", str(d), "--quiet"])
    assert code == 2, err
    assert err.startswith(f"error: invalid out='{d}': a folder no other run"), err
    assert f"process {os.getpid()}" in err and "no checkpoint" not in err
    # Once the folder is free, the missing checkpoint is what is said.
    code, _, err = cli([*argv, "--out", str(d), "--quiet"])
    assert code == 2 and "no checkpoint_*.npz to resume from" in err, err


def test_the_lock_refuses_a_second_holder_in_the_same_process(tmp_path):
    with npio.folder_lock(tmp_path), pytest.raises(ParameterError):
        with npio.folder_lock(tmp_path):
            pass
    with npio.folder_lock(tmp_path):  # released after the block
        pass
    assert [p.name for p in tmp_path.iterdir()] == [npio.LOCK_NAME]


# ------------------------------------------------------------ CLI messages --
@pytest.mark.parametrize("argv", [["scenes"], ["scenes", "--json"]])
def test_a_closed_pipe_ends_the_cli_quietly(argv):
    # Reproducer: `skfem-npfem scenes | head -1` printed
    # "error: [Errno 32] Broken pipe" and exited 2.  Here the reader closes
    # the pipe before the CLI writes, so every write meets the closed pipe.
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "skfem_npfem", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    proc.stdout.close()
    err = proc.stderr.read().decode()
    code = proc.wait(timeout=60)
    assert err == ""
    assert code in (0, 141)  # 141 = 128 + SIGPIPE, as a shell reports `cat`


def test_sweep_without_a_grid_asks_for_one():
    # Reproducer: `skfem-npfem sweep SCENE --out DIR` said "invalid --grid=None".
    code, _, err = cli(["sweep", "elastic-column", "--out", "unused"])
    assert code == 2
    assert err == (
        "error: missing --grid: a sweep needs at least one --grid name=v1,v2,... "
        "(a parameter to vary and its values, e.g. --grid spacing=0.02,0.01)\n"
    )
    assert not Path("unused").exists()


# ------------------------------------------------- progress and step times --
REC = type("R", (), {"dt": 0.1, "status": "Solved", "iterations": 9})


def _record(step: int):
    rec = REC()
    rec.step = step
    return rec


def test_progress_at_the_end_shows_100_percent_and_no_negative_eta():
    # Reproducer: `eta -0.0 s` at 100 %: the summed time ends a hair past
    # t_end (0.1 + 0.1 + 0.1 = 0.30000000000000004 > 0.3).
    p = Progress(True, n_target=None, t_end=0.3)
    p.start -= 3.0
    text = p.text(_record(3), 0.1 + 0.1 + 0.1, 0, 0.0)
    assert "100.0%" in text and text.endswith("eta     0.0 s"), text
    assert "-" not in text


def test_progress_after_a_resume_continues_from_the_resumed_share():
    # Reproducer: a run resumed at t = 0.5 of t_end = 1 started again at 0 %.
    # 4 s of wall time from 0.5 to 0.6: 60 % done, 0.4 left at 0.1 per 4 s.
    p = Progress(True, n_target=None, t_end=1.0)
    p.start -= 4.0
    text = p.text(_record(60), 0.6, 50, 0.5)
    assert " 60.0%" in text, text
    assert float(text.split("eta")[1].split()[0]) == pytest.approx(16.0, abs=0.05)
    # By steps (a step target) the same.
    p = Progress(True, n_target=100, t_end=None)
    p.start -= 4.0
    text = p.text(_record(60), 0.6, 50, 0.5)
    assert " 60.0%" in text and "eta    16.0 s" in text, text


def test_a_resumed_run_reports_its_share_of_the_whole_run(tmp_path):
    scene = npfem.get_scene("column-collapse")
    values = scene.resolve({**dict(s.split("=") for s in COARSE), "t_end": 0.04})
    srun = scene.build(values, out=None, progress=False)
    sim = srun.simulation
    sim.checkpoint_dir, sim.checkpoint_every = tmp_path, 4
    sim.run(t_end=0.02)
    again = scene.build(values, out=None, progress=True).simulation
    again.restore(tmp_path / "checkpoint_000004.npz")
    again.progress_interval = 0.0
    buf = io.StringIO()
    with redirect_stderr(buf):
        again.run(t_end=0.04)
    shares = [
        float(ln.split("%")[0].split()[-1]) for ln in buf.getvalue().split("\n") if ln
    ]
    assert shares == [62.5, 75.0, 87.5, 100.0]


def test_step_times_in_the_index_are_clean(tmp_path):
    # Reproducer: the .pvd listed 0.30000000000000016 for t = 0.3 (the sum of
    # 60 steps of 0.005 s).  Output every 5 steps: t = 0.025 k exactly.
    d = tmp_path / "k"
    argv = ["run", "column-collapse", *sets(*COARSE, "t_end=0.3"), "--out", str(d)]
    assert cli([*argv, "--quiet"])[0] == 0
    stamps = re.findall(r'timestep="([^"]*)"', (d / "result.pvd").read_text())
    assert stamps == [repr(k * 25 / 1000) for k in range(13)]
    series = json.loads((d / "result.vtu.series").read_text())
    assert [f["time"] for f in series["files"]] == [k * 25 / 1000 for k in range(13)]
    last = npio.read_step(d / "result_000060.vtu")
    assert last.field_data["TimeValue"][0] == 0.3


# ------------------------------------------- temporaries a killed run left --
LEFTOVERS = [
    ".tmp_result.vtu.series",
    ".tmp_result.pvd",
    ".tmp_result_000005.vtu",
    ".tmp_checkpoint_000006.npz",
    ".tmp_scene.json",
    ".tmp_s.json",
    "plots/.tmp_stress_yy_t1.png",
]


@pytest.mark.parametrize("resume", [False, True])
def test_temporaries_left_by_kill_9_are_removed_by_the_next_run(tmp_path, resume):
    # Reproducer: kill -9 during a write left a 0-byte .tmp_result.vtu.series
    # (and could leave any other temporary), which stayed for good although
    # docs/output.md said the temporary is always removed.
    d = tmp_path / "k"
    base = ["run", "column-collapse", "--out", str(d), "--quiet"]
    assert cli([*base, *sets(*COARSE, "t_end=0.02")])[0] == 0
    (d / "plots").mkdir()
    for name in LEFTOVERS:
        (d / name).write_bytes(b"")
    (d / "notes.tmp").write_text("mine")
    again = [*base, *sets(*COARSE, "t_end=0.03"), "--summary", str(d / "s.json")]
    assert cli([*again, *(["--resume"] if resume else [])])[0] == 0
    assert [p.name for p in d.rglob(".tmp_*")] == []
    assert (d / "notes.tmp").read_text() == "mine"
    times = [t for t, _ in npio.read_pvd(d / "result.pvd")]
    assert times[-1] == 0.03 and (d / "checkpoint_000006.npz").is_file()


# ---------------------------------------------- a run that ended before rest --
def test_a_collapse_stopped_by_t_end_before_rest_says_so(tmp_path):
    # Reproducer: a collapse that reached t_end while still flowing reported
    # its run-out as final (only `at_rest: false`, easy to miss), silently.
    s = tmp_path / "s.json"
    base = ["run", "column-collapse", *sets(COARSE[0], COARSE[2]), "--quiet"]
    code, _, err = cli([*base, *sets("t_end=0.6"), "--summary", str(s)])
    assert code == 0
    m = json.loads(s.read_text())["metrics"]
    # (this coarse column also sheds grains: their warning comes after)
    rest = [w for w in m["warnings"] if "t_end" in w]
    assert m["at_rest"] is False and len(rest) == 1 and m["warnings"][0] == rest[0]
    assert m["warnings"][0].startswith(
        "column-collapse: the run ended at t_end = 0.6 s while the kinetic energy "
        "was still "
    )
    assert "not at rest, so the run-out and height are not final" in m["warnings"][0]
    assert sorted(err.splitlines()) == sorted(f"warning: {w}" for w in m["warnings"])
    # Ended before the earliest stop at rest (min_time = 2 sqrt(H0/g)).
    code, _, err = cli([*base, *sets("t_end=0.1")])
    assert code == 0
    assert "before the earliest stop at rest, min_time = 0.4039 s" in err
    # With the rule off (rest_fraction = 0) the user chose t_end: no warning.
    code, _, err = cli([*base, *sets("t_end=0.1", "rest_fraction=0")])
    assert code == 0 and "t_end" not in err


def test_sweep_plot_marks_the_runs_that_were_not_at_rest(tmp_path, monkeypatch):
    pytest.importorskip("pandas", reason="needs the sweep extra")
    plt = pytest.importorskip("matplotlib.pyplot", reason="needs the viz extra")
    from skfem_npfem.sweeps.plot import NOT_AT_REST
    from skfem_npfem.sweeps.table import write_table

    rows = [
        {
            "run": f"a{a}",
            "status": "ok",
            "error": "",
            "resumed": False,
            "aspect": a,
            "normalised_runout": r,
            "at_rest": rest,
        }
        for a, r, rest in [(0.5, 0.6, True), (1.0, 1.3, True), (2.0, 2.1, False)]
    ]
    write_table(rows, tmp_path)
    spec = {"scene": "column-collapse", "grid": {"aspect": [0.5, 1.0, 2.0]}}
    (tmp_path / "sweep.json").write_text(json.dumps(spec))
    figures = []
    monkeypatch.setattr(plt, "close", figures.append)
    code, out, err = cli(["sweep-plot", str(tmp_path), "normalised_runout", "aspect"])
    assert code == 0 and out.strip().endswith("normalised_runout_vs_aspect.png")
    assert err == (
        "warning: 1 of 3 runs ended at t_end before the material came to rest "
        "(at_rest = false): their normalised_runout is not final; open markers "
        "in the plot\n"
    )
    ax = figures[0].axes[0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [NOT_AT_REST]
    hollow = [ln for ln in ax.lines if ln.get_markerfacecolor() == "white"]
    assert [list(ln.get_xdata()) for ln in hollow] == [[2.0], []]
