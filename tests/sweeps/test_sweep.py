"""Parameter sweeps on Dask: tables, resume, failures, a real scheduler.

The reference of every sweep result is the same case run by hand through
:func:`skfem_npfem.run_scene` (and, for the static column, the analytic
settlement ``rho g H^2 / (2 M)``).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_the_readme_test_command_installs_the_sweep_extra():
    # The tests below skip without Dask; CI must therefore install it.
    readme = (ROOT / "README.md").read_text()
    pattern = r'^python3 -m venv .* pip install "\.\[test'  # as .ci/run reads it
    line = next(ln for ln in readme.splitlines() if re.match(pattern, ln))
    assert re.search(r'"\.\[[^\]]*\bsweep\b[^\]]*\]"', line), line


distributed = pytest.importorskip(
    "distributed", reason="needs the sweep extra: pip install '.[sweep]'"
)
pd = pytest.importorskip("pandas", reason="needs the sweep extra")

from skfem_npfem import run_scene, sweep  # noqa: E402
from skfem_npfem.cli import main  # noqa: E402
from skfem_npfem.errors import NpfemError, ParameterError  # noqa: E402
from skfem_npfem.step.backends import available_cores  # noqa: E402
from skfem_npfem.sweeps import read_table, run_name, run_tasks  # noqa: E402

SCENE = "elastic-column"
GRID = {"spacing": [0.5, 0.25], "nu": [0.2, 0.3]}
FIXED = {"mode": "static", "steps": 1}


def _by_hand(varied: dict, fixed: dict = FIXED) -> dict:
    # threads=1: what the sweep gives each run on 2 workers with <= 2 cores.
    return run_scene(SCENE, {**fixed, **varied, "threads": 1})


def _assert_row_matches(row, summary: dict) -> None:
    for key, val in summary["metrics"].items():
        if val is None or (isinstance(val, float) and np.isnan(val)):
            assert row[key] is None or np.isnan(row[key]), key
        elif not isinstance(val, list):
            assert row[key] == pytest.approx(val, rel=1e-12, abs=1e-15), key
    assert row["solver.steps"] == summary["solver"]["steps"]
    its = summary["solver"]["ipm_iterations_total"]
    assert row["solver.ipm_iterations_total"] == its
    for key, val in summary["parameters"].items():
        if val is not None and key != "threads":
            assert row[key] == val, key


@pytest.fixture(scope="module")
def grid_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "grid"
    lines: list[str] = []
    table = sweep(SCENE, GRID, fixed=FIXED, out=out, workers=2, progress=lines.append)
    return out, table, lines


def test_grid_on_two_local_workers_equals_runs_by_hand(grid_sweep):
    out, table, lines = grid_sweep
    assert list(table["run"]) == [
        "spacing=0.5_nu=0.2",
        "spacing=0.5_nu=0.3",
        "spacing=0.25_nu=0.2",
        "spacing=0.25_nu=0.3",
    ]
    assert list(table.columns[:6]) == [
        "run",
        "status",
        "error",
        "resumed",
        "spacing",
        "nu",
    ]
    assert (table["status"] == "ok").all()
    assert any("2 local workers" in ln for ln in lines)
    assert sum(ln.startswith("[") for ln in lines) == 4  # one line per run
    assert "ETA" in lines[-3]
    for (spacing, nu), row in zip(
        [(s, n) for s in GRID["spacing"] for n in GRID["nu"]],
        table.to_dict("records"),
        strict=True,
    ):
        ref = _by_hand({"spacing": spacing, "nu": nu})
        _assert_row_matches(row, ref)
        # Independent reference: the oedometric settlement rho g H^2 / (2 M).
        E, rho, g, H = 1e7, 2000.0, 9.81, 4.0
        M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
        assert row["settlement"] == pytest.approx(rho * g * H**2 / (2 * M), rel=2e-3)
        assert row["threads"] == 1  # 2 workers on this 2-core machine
    # The same table on disk (CSV), and a summary per run folder.
    disk = read_table(out)
    assert list(disk["run"]) == list(table["run"])
    np.testing.assert_allclose(disk["settlement"], table["settlement"], rtol=1e-15)
    for name in table["run"]:
        s = json.loads((out / "runs" / name / "summary.json").read_text())
        assert s["scene"] == SCENE


def test_rerun_skips_finished_runs_and_adds_new_ones(grid_sweep):
    out, table, _ = grid_sweep
    stamps = {
        name: (out / "runs" / name / "summary.json").stat().st_mtime_ns
        for name in table["run"]
    }
    lines: list[str] = []
    again = sweep(SCENE, GRID, fixed=FIXED, out=out, progress=lines.append)
    assert "4 finished before, 0 to run" in lines[0]
    assert not any(ln.startswith("running on") for ln in lines)  # no cluster
    pd.testing.assert_frame_equal(again, table)
    # A third nu value: only its two runs run; the four finished ones are kept.
    grid = {"spacing": GRID["spacing"], "nu": [0.2, 0.3, 0.4]}
    lines.clear()
    bigger = sweep(SCENE, grid, fixed=FIXED, out=out, workers=1, progress=lines.append)
    assert "4 finished before, 2 to run" in lines[0]
    ran = {ln.split(":")[0].split()[1] for ln in lines if ln.startswith("[")}
    assert ran == {"spacing=0.5_nu=0.4", "spacing=0.25_nu=0.4"}
    for name, stamp in stamps.items():
        assert (out / "runs" / name / "summary.json").stat().st_mtime_ns == stamp
    assert len(bigger) == 6
    row = bigger.set_index("run").loc["spacing=0.25_nu=0.4"]
    ref = _by_hand({"spacing": 0.25, "nu": 0.4})
    assert row["settlement"] == pytest.approx(ref["metrics"]["settlement"], rel=1e-12)


def test_a_failing_run_is_recorded_and_the_others_finish(tmp_path):
    # E = 1 kPa: the column settles more than its height in the first step and
    # the fixed mesh turns inside out in the second (a library error).
    grid = {"E": [1e7, 1e3], "spacing": [0.5]}
    fixed = {"steps": 2}
    table = sweep(SCENE, grid, fixed=fixed, out=tmp_path, workers=2, progress=False)
    ok, bad = table.to_dict("records")
    assert ok["status"] == "ok" and ok["error"] == ""
    assert bad["status"] == "failed" and "inside out" in bad["error"]
    assert bad["run"] == "E=1000_spacing=0.5" and bad["E"] == 1e3
    assert np.isnan(bad["settlement"])
    assert "inside out" in (tmp_path / "runs" / bad["run"] / "error.txt").read_text()
    _assert_row_matches(ok, _by_hand({"E": 1e7, "spacing": 0.5}, fixed))
    with pytest.raises(NpfemError, match="inside out"):
        _by_hand({"E": 1e3, "spacing": 0.5}, fixed)


def test_a_run_with_a_checkpoint_continues_from_it(tmp_path):
    # A worker lost after 2 of 4 steps leaves a checkpoint and no summary.
    fixed = {"mode": "dynamic", "dt": 0.002, "spacing": 0.5}
    name = run_name({"nu": 0.3})
    folder = tmp_path / "runs" / name
    run_scene(SCENE, {**fixed, "nu": 0.3, "steps": 2, "threads": 1}, out=folder)
    first = (folder / "result_000001.vtu").stat().st_mtime_ns
    assert (folder / "checkpoint_000002.npz").exists()
    table = sweep(  # cases= (a list of runs) instead of a grid
        SCENE,
        cases=[{"nu": 0.3}],
        fixed={**fixed, "steps": 4},
        out=tmp_path,
        workers=1,
        progress=False,
    )
    row = table.to_dict("records")[0]
    assert row["resumed"] and row["status"] == "ok"
    assert (folder / "result_000001.vtu").stat().st_mtime_ns == first  # kept
    summary = json.loads((folder / "summary.json").read_text())
    assert [h["step"] for h in summary["history"]] == [1, 2, 3, 4]
    straight = _by_hand({"nu": 0.3}, {**fixed, "steps": 4})
    _assert_row_matches(row, straight)


def test_run_tasks_runs_a_demo_function_and_records_failures():
    out = run_tasks(
        _cube_or_fail, {"two": (2,), "bad": (-1,)}, workers=1, progress=False
    )
    assert out["two"].ok and out["two"].value == 8
    assert not out["bad"].ok and "ParameterError" in out["bad"].error


def test_a_function_workers_cannot_import_by_name_is_shipped_by_value(tmp_path):
    # A module loaded from a file path (as pytest's importlib mode loads test
    # modules) cannot be imported by name on a worker; before the fix the
    # worker's connection died on unpickling and the sweep waited forever.
    import importlib.util

    from skfem_npfem.sweeps.engine import portable
    from skfem_npfem.sweeps.task import ByValue

    src = tmp_path / "hidden" / "somewhere.py"
    src.parent.mkdir()
    src.write_text("def cube(x):\n    return x ** 3\n")
    spec = importlib.util.spec_from_file_location("nowhere_pkg.somewhere", src)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        spec.loader.exec_module(module)
        assert isinstance(portable(module.cube), ByValue)
        assert portable(run_scene) is run_scene  # importable: by reference
        out = run_tasks(module.cube, {"three": (3,)}, workers=1, progress=False)
    finally:
        del sys.modules[spec.name]
    assert out["three"].ok and out["three"].value == 27


def _cube_or_fail(x: int) -> int:
    if x < 0:
        raise ParameterError("x", x, "x >= 0")
    return x**3


# ---------------------------------------------------------------------------
# Bad input: one `error:` line, exit code 2, nothing started.
# ---------------------------------------------------------------------------

BAD = [
    (["no-such-scene", "--grid", "nu=0.2"], "scene"),
    (["elastic-column", "--grid", "nuu=0.2,0.3"], "nuu"),
    (["elastic-column"], "--grid"),
    (["elastic-column", "--grid", "nu="], "non-empty"),
    (["elastic-column", "--grid", "nu0.2"], "name=v1,v2"),
    (["elastic-column", "--grid", "nu=0.2,,0.3"], "non-empty"),
    (["elastic-column", "--grid", "nu=0.2", "--grid", "nu=0.3"], "twice"),
    (["elastic-column", "--grid", "nu=0.2,0.20"], "distinct"),
    (["elastic-column", "--grid", "nu=0.2,0.7"], "nu"),
    (["elastic-column", "--grid", "nu=0.2", "--set", "nu=0.3"], "either varied"),
    (["elastic-column", "--grid", "nu=0.2", "--workers", "0"], "--workers"),
    (["elastic-column", "--grid", "nu=0.2", "--scheduler", "a b"], "--scheduler"),
]


@pytest.mark.parametrize(("argv", "needle"), BAD)
def test_bad_input_is_one_error_line(argv, needle, tmp_path, capsys):
    rc = main(["sweep", *argv, "--out", str(tmp_path / "s")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and err[0].startswith("error: ") and needle in err[0], err
    assert not (tmp_path / "s").exists()


def test_unreachable_scheduler_is_one_error_line_after_the_timeout(tmp_path, capsys):
    import socket

    with socket.socket() as s:  # a loopback port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    start = time.perf_counter()
    rc = main(
        [
            "sweep",
            SCENE,
            "--grid",
            "nu=0.2",
            "--scheduler",
            f"tcp://127.0.0.1:{port}",
            "--connect-timeout",
            "1",
            "--out",
            str(tmp_path),
        ]
    )
    wall = time.perf_counter() - start
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("error")]
    assert rc == 2 and len(err) == 1
    assert "--scheduler" in err[0] and "within 1 s" in err[0]
    assert 0.9 < wall < 15.0


def test_without_dask_the_command_says_how_to_install_it(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)
    rc = main(["sweep", SCENE, "--grid", "nu=0.2", "--out", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    assert "pip install 'skfem-npfem[sweep]'" in err[0]


def test_sweep_plot_draws_a_metric_against_a_parameter(grid_sweep, capsys):
    pytest.importorskip("matplotlib")
    out, _, _ = grid_sweep
    assert main(["sweep-plot", str(out), "settlement", "nu"]) == 0
    png = Path(capsys.readouterr().out.strip())
    assert png == out / "settlement_vs_nu.png" and png.stat().st_size > 5000
    assert main(["sweep-plot", str(out), "no_such_metric", "nu"]) == 2
    assert "no_such_metric" in capsys.readouterr().err


# ---------------------------------------------------------------------------
# A scheduler and workers started as separate processes (`dask scheduler`).
# ---------------------------------------------------------------------------


def _dask_cli() -> str | None:
    here = Path(sys.executable).parent / "dask"
    return str(here) if here.exists() else shutil.which("dask")


class _Processes:
    def __init__(self, tmp: Path) -> None:
        self.tmp = tmp
        self.procs: list[subprocess.Popen] = []

    def start(self, *args: str, name: str) -> subprocess.Popen:
        log = open(self.tmp / f"{name}.log", "w")
        proc = subprocess.Popen(
            [_dask_cli(), *args],
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # its own process group, ended as one
            cwd=self.tmp,
        )
        self.procs.append(proc)
        return proc

    def stop(self) -> None:
        for proc in self.procs:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGTERM)
        for proc in self.procs:
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()


@pytest.fixture
def scheduler(tmp_path):
    if _dask_cli() is None:
        pytest.skip("the dask command line (dask scheduler / dask worker) is missing")
    procs = _Processes(tmp_path)
    file = tmp_path / "scheduler.json"
    try:
        procs.start(
            "scheduler",
            "--host",
            "127.0.0.1",
            "--port",
            "0",
            "--no-dashboard",
            "--scheduler-file",
            str(file),
            name="scheduler",
        )
        deadline = time.monotonic() + 60
        while not file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert file.exists(), (tmp_path / "scheduler.log").read_text()
        address = json.loads(file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")

        def worker(name: str, *extra: str) -> subprocess.Popen:
            return procs.start(
                "worker",
                address,
                "--nthreads",
                "1",
                "--no-dashboard",
                "--name",
                name,
                *extra,
                name=f"worker-{name}",
            )

        yield address, worker, tmp_path
    finally:
        procs.stop()


def _wait_for_workers(address: str, n: int) -> None:
    with distributed.Client(address, timeout=30) as client:
        client.wait_for_workers(n, timeout=60)


def test_sweep_through_a_separately_started_scheduler(scheduler, capsys):
    address, worker, tmp = scheduler
    worker("a")
    _wait_for_workers(address, 1)
    out = tmp / "remote"
    argv = ["sweep", SCENE, "--grid", "spacing=0.5,0.25", "--set", "nu=0.25"]
    argv += ["--set", "mode=static", "--scheduler", address, "--out", str(out)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    threads = available_cores()  # one worker thread on this machine
    assert f"running on {address}, {threads} solver thread" in err
    table = read_table(out)
    assert list(table["run"]) == ["spacing=0.5", "spacing=0.25"]
    for spacing, row in zip((0.5, 0.25), table.to_dict("records"), strict=True):
        ref = run_scene(SCENE, {"spacing": spacing, "nu": 0.25, "mode": "static"})
        _assert_row_matches(row, ref)


def test_a_run_whose_worker_is_killed_continues_from_its_checkpoint(scheduler):
    # Two single-process workers; the one running the case is killed (SIGKILL)
    # after the case wrote its second checkpoint.  The scheduler hands the task
    # to the other worker, which resumes from the checkpoint in the run folder.
    address, worker, tmp = scheduler
    procs = {name: worker(name, "--no-nanny") for name in ("a", "b")}
    _wait_for_workers(address, 2)
    out = tmp / "killed"
    fixed = {"spacing": 0.025, "checkpoint_every": 5, "output_every": 20}
    cmd = [sys.executable, "-m", "skfem_npfem", "sweep", "column-collapse"]
    cmd += ["--grid", "aspect=1", "--scheduler", address, "--out", str(out)]
    cmd += [arg for k, v in fixed.items() for arg in ("--set", f"{k}={v}")]
    folder = out / "runs" / "aspect=1"
    with distributed.Client(address, timeout=30) as client:
        sweep_proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
        try:
            deadline = time.monotonic() + 120
            while not (folder / "checkpoint_000010.npz").exists():
                assert time.monotonic() < deadline and sweep_proc.poll() is None
                time.sleep(0.02)
            busy = [a for a, keys in client.processing().items() if keys]
            assert len(busy) == 1
            assert not (folder / "summary.json").exists()  # killed mid-run
            name = client.scheduler_info()["workers"][busy[0]]["name"]
            os.killpg(procs[name].pid, signal.SIGKILL)
            _, err = sweep_proc.communicate(timeout=180)
        finally:
            if sweep_proc.poll() is None:
                sweep_proc.kill()
                sweep_proc.wait()
    assert sweep_proc.returncode == 0, err
    assert "resumed from its checkpoint" in err
    row = read_table(out).to_dict("records")[0]
    assert row["status"] == "ok" and row["resumed"]
    summary = json.loads((folder / "summary.json").read_text())
    steps = [h["step"] for h in summary["history"]]
    assert steps == list(range(1, len(steps) + 1)) and steps[-1] > 10
    # The same case run without interruption (reproducible mode: bit-identical).
    ref = run_scene("column-collapse", {**fixed, "aspect": 1.0})
    assert row["solver.steps"] == ref["solver"]["steps"]
    for key in ("normalised_runout", "final_height", "collapse_time"):
        assert row[key] == pytest.approx(ref["metrics"][key], rel=1e-9), key


def _csv(out: Path):
    exact = {"float_precision": "round_trip"} if pd.__version__ < "3" else {}
    return pd.read_csv(out / "table.csv", **exact)


def test_parquet_table_beside_the_csv_when_pyarrow_is_installed(grid_sweep):
    pytest.importorskip("pyarrow", reason="Parquet output needs pyarrow (optional)")
    out, table, _ = grid_sweep  # (a later test may have added runs to it)
    parquet = pd.read_parquet(out / "table.parquet")
    csv = _csv(out)
    assert list(parquet.columns) == list(csv.columns) == list(table.columns)
    assert list(parquet["run"]) == list(csv["run"])
    np.testing.assert_array_equal(parquet["settlement"], csv["settlement"])
    np.testing.assert_array_equal(parquet["solver.steps"], csv["solver.steps"])
    ref = _by_hand({"spacing": 0.25, "nu": 0.3})["metrics"]["settlement"]
    assert parquet.set_index("run").loc["spacing=0.25_nu=0.3", "settlement"] == ref


def test_another_set_value_in_the_same_folder_is_refused(grid_sweep):
    out, _, _ = grid_sweep
    with pytest.raises(ParameterError, match=r"--out.*fixed"):
        sweep(SCENE, GRID, fixed={**FIXED, "steps": 2}, out=out, progress=False)
    with pytest.raises(ParameterError, match=r"--out.*scene"):
        sweep("strip-footing", {"c": [2e4]}, out=out, progress=False)


def test_run_names_are_the_same_from_the_command_line_and_python():
    from skfem_npfem.scenes import get_scene
    from skfem_npfem.sweeps import plan_runs

    scene = get_scene(SCENE)
    cli = plan_runs(scene, {"E": ["1e7", "2.5e6"], "mode": ["static"]})
    py = plan_runs(scene, {"E": [1e7, 2.5e6], "mode": ["static"]})
    assert [r.name for r in cli] == [r.name for r in py]
    assert [r.name for r in py] == ["E=1e+07_mode=static", "E=2500000_mode=static"]
    assert py[1].values["E"] == 2.5e6 and py[1].values["nu"] == 0.3  # default kept
    cases = plan_runs(scene, cases=[{"E": 1e7}, {"nu": 0.25}], fixed={"dt": 0.5})
    assert [r.name for r in cases] == ["E=1e+07", "nu=0.25"]
    assert cases[1].overrides == {"dt": 0.5, "nu": 0.25}
    with pytest.raises(ParameterError, match="distinct"):
        plan_runs(scene, {"E": ["1e7", 1e7]})
    with pytest.raises(ParameterError, match="not both"):
        plan_runs(scene, {"E": [1e7]}, cases=[{"nu": 0.2}])


def _sigint_default() -> None:
    """In the child: SIGINT at its default, as for a command typed in a shell."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_ctrl_c_stops_a_sweep_quietly_and_names_the_way_to_continue(tmp_path):
    # Reproducer: Ctrl-C during `skfem-npfem sweep` sometimes printed a Dask
    # worker traceback, and the closing line advised `--resume`, which sweep
    # does not have.  Ctrl-C goes to the whole process group (the sweep and
    # its local workers); sent here once the first run has finished.
    out = tmp_path / "sw"
    argv = [
        sys.executable, "-m", "skfem_npfem", "sweep", "column-collapse",
        "--grid", "aspect=0.5,1,2,3", "--workers", "2", "--out", str(out),
        "--set", "spacing=0.03333333333333333", "--set", "linear_solver=qdldl",
        "--set", "rest_fraction=0",
    ]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        argv,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        env=env,
        start_new_session=True,
        preexec_fn=_sigint_default,
    )
    lines = []
    try:
        for line in proc.stderr:
            lines.append(line)
            if line.startswith("[1/4]"):
                break
        os.killpg(proc.pid, signal.SIGINT)
        lines += proc.stderr.readlines()
        code = proc.wait(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    err = "".join(lines)
    assert code == 130, err
    assert "Traceback" not in err and "ERROR" not in err and "--resume" not in err
    assert lines[-1] == (
        "interrupted; finished runs are kept, and running the same sweep command "
        "again skips them and continues the interrupted runs from their latest "
        "checkpoints\n"
    )
    # The advice holds: the same command finishes the sweep.
    done = subprocess.run(argv, capture_output=True, text=True, env=env, check=False)
    assert done.returncode == 0, done.stderr
    assert re.search(r"4 runs, [1-3] finished before", done.stderr), done.stderr
    assert len(pd.read_csv(out / "table.csv")) == 4


def test_a_metric_named_like_a_parameter_is_renamed_and_documented():
    # spfem's metric `explicit_dt` (largest substep used) clashes with the
    # parameter `explicit_dt`; docs/sweep.md said metrics keep their names.
    from skfem_npfem.sweeps.table import summary_row

    row = summary_row(
        {
            "parameters": {"explicit_dt": None, "dt": 0.01},
            "metrics": {"explicit_dt": 2.5e-5, "runout": 0.5, "warnings": ["a", "b"]},
        }
    )
    assert row["metric.explicit_dt"] == 2.5e-5 and row["runout"] == 0.5
    assert np.isnan(row["explicit_dt"]) and row["warnings"] == "a+b"
    doc = (Path(__file__).resolve().parents[2] / "docs" / "sweep.md").read_text()
    line = next(r for r in doc.splitlines() if r.startswith("| scene metrics |"))
    assert "`metric.<name>`" in line and "`metric.explicit_dt`" in line
    assert "joined by `+`" in line
