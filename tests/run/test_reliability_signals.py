"""SIGINT/SIGTERM stop a run cleanly; progress everywhere.

The reproducer: Ctrl-C exited 130 with a message glued to the progress line,
wrote no checkpoint (nothing to resume before the first one) and no summary;
SIGTERM exited 143 silently.  Now the step in progress finishes, a checkpoint
and the partial summary (``"interrupted": true``) are written, one line is
printed on its own line, and the exit code is 128 + the signal.
"""

from __future__ import annotations

import io
import json
import os
import pty
import signal
import subprocess
import sys
import threading
import time
from contextlib import redirect_stderr
from pathlib import Path

import numpy as np
import pytest

import skfem_npfem as npfem
import skfem_npfem.io as npio
from skfem_npfem import RunInterrupted
from skfem_npfem.run.control import Progress
from skfem_npfem.run.rest import AtRest

pytestmark = pytest.mark.skipif(
    sys.platform == "win32", reason="POSIX signals and pseudo-terminals"
)

COARSE = {
    "spacing": 0.2 / 6,
    "rest_fraction": 0.0,
    "linear_solver": "qdldl",
    "checkpoint_every": 1000,
}


def _argv(out: Path, summary: Path, t_end: float) -> list[str]:
    sets = [f"{k}={v}" for k, v in {**COARSE, "t_end": t_end}.items()]
    argv = [sys.executable, "-m", "skfem_npfem", "run", "column-collapse"]
    for item in sets:
        argv += ["--set", item]
    return [*argv, "--out", str(out), "--summary", str(summary)]


def _as_from_a_terminal() -> None:
    """In the child: SIGINT at its default, as for a command typed in a shell
    (the tests may run under nohup or as a background job, which ignore it)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _interrupt(argv: list[str], out: Path, sig: int, tty: bool) -> tuple[int, str]:
    """Start the run, send ``sig`` once step 5 is on disk; return (rc, stderr)."""
    if tty:
        master, slave = pty.openpty()
        proc = subprocess.Popen(
            argv,
            stderr=slave,
            stdout=subprocess.DEVNULL,
            preexec_fn=_as_from_a_terminal,
        )
        os.close(slave)
        chunks: list[bytes] = []

        def drain() -> None:
            while True:
                try:
                    data = os.read(master, 4096)
                except OSError:
                    return
                if not data:
                    return
                chunks.append(data)

        reader = threading.Thread(target=drain, daemon=True)
        reader.start()
    else:
        proc = subprocess.Popen(
            argv,
            stderr=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            text=True,
            preexec_fn=_as_from_a_terminal,
        )
    try:
        deadline = time.monotonic() + 120
        while not (out / "result_000005.vtu").exists():
            assert proc.poll() is None, "the run ended before the signal"
            assert time.monotonic() < deadline, "no step 5 after 120 s"
            time.sleep(0.05)
        proc.send_signal(sig)
        if tty:
            rc = proc.wait(timeout=60)
            reader.join(timeout=10)
            os.close(master)
            err = b"".join(chunks).decode()
        else:
            _, err = proc.communicate(timeout=60)
            rc = proc.returncode
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return rc, err


def _check_interrupted(out: Path, summary: Path, signame: str) -> dict:
    s = json.loads(summary.read_text())
    assert s["interrupted"] is True and s["interrupted_by"] == signame
    step = s["solver"]["steps"]
    assert step >= 5 and len(s["history"]) == step
    assert s["checkpoint"] == str(out / f"checkpoint_{step:06d}.npz")
    _, meta = npio.load_checkpoint(s["checkpoint"])
    assert meta["step"] == step
    assert meta["time"] == pytest.approx(s["solver"]["time"], rel=1e-12)
    return s


def _resume_matches_an_uninterrupted_run(out, summary, s, tmp_path):
    t_end = s["solver"]["time"] + 0.01  # two more steps
    argv = _argv(out, summary, t_end)[1:]
    proc = subprocess.run(
        [sys.executable, *argv, "--resume", "--quiet"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    resumed = json.loads(summary.read_text())
    assert resumed["interrupted"] is False
    ref = npfem.run_scene("column-collapse", {**COARSE, "t_end": t_end})
    assert resumed["solver"]["steps"] == ref["solver"]["steps"]
    assert resumed["metrics"]["runout"] == ref["metrics"]["runout"]  # bit for bit
    last = npio.read_step(npio.read_pvd(out / "result.pvd")[-1][1])
    assert last.field_data["TimeValue"][0] == pytest.approx(t_end, rel=1e-12)


def test_ctrl_c_on_a_terminal_checkpoints_and_prints_one_clean_line(tmp_path):
    out, summary = tmp_path / "run", tmp_path / "s.json"
    rc, err = _interrupt(_argv(out, summary, 5.0), out, signal.SIGINT, tty=True)
    assert rc == 130, err
    s = _check_interrupted(out, summary, "SIGINT")
    # The progress line is rewritten with \r; the message starts a new line.
    assert "\rstep " in err
    lines = err.replace("\r\n", "\n").split("\n")
    message = [ln for ln in lines if "interrupted by" in ln]
    assert len(message) == 1 and message[0].startswith("interrupted by SIGINT")
    assert f"after step {s['solver']['steps']} " in message[0]
    assert "continue with --resume" in message[0] and "Traceback" not in err
    _resume_matches_an_uninterrupted_run(out, summary, s, tmp_path)


def test_sigterm_without_a_terminal_exits_143_with_a_checkpoint(tmp_path):
    out, summary = tmp_path / "run", tmp_path / "s.json"
    rc, err = _interrupt(_argv(out, summary, 5.0), out, signal.SIGTERM, tty=False)
    assert rc == 143, err
    s = _check_interrupted(out, summary, "SIGTERM")
    lines = err.strip().splitlines()
    # Without a terminal: progress lines (the first step at least), then the
    # one message line.
    assert lines[0].startswith("step     1  t=0.005 s")
    assert lines[-1].startswith(
        f"interrupted by SIGTERM after step {s['solver']['steps']} "
    )
    assert "\r" not in err


def _sim(tmp_path, t_end=1.0):
    scene = npfem.get_scene("column-collapse")
    values = scene.resolve({**COARSE, "t_end": t_end})
    srun = scene.build(values, out=tmp_path, progress=False)
    sim = srun.simulation
    sim.checkpoint_dir, sim.checkpoint_every = tmp_path, 1000
    return sim


@pytest.fixture
def sigint_handled():
    """SIGINT raises KeyboardInterrupt during the test (as in an interactive
    shell), whatever the test process was started with; put back after."""
    found = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, found)


@pytest.mark.parametrize("second", [False, True])
def test_second_signal_abandons_the_step_in_progress(tmp_path, second, sigint_handled):
    sim = _sim(tmp_path)
    before = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    original = sim._advance

    def signalling(dt):
        if sim.step + 1 == 3:  # signals arrive while step 3 is being solved
            os.kill(os.getpid(), signal.SIGINT)
            if second:
                os.kill(os.getpid(), signal.SIGINT)
        return original(dt)

    sim._advance = signalling
    with pytest.raises(RunInterrupted) as info:
        sim.run(t_end=1.0)
    err = info.value
    assert err.abandoned is second
    finished = 2 if second else 3
    assert err.step == sim.step == len(sim.records) == finished
    assert err.checkpoint == tmp_path / f"checkpoint_{finished:06d}.npz"
    _, meta = npio.load_checkpoint(err.checkpoint)
    assert meta["step"] == finished and err.exit_code == 130
    # The last finished step is in the result series although the output
    # schedule (every 5th step) skips it: the state the run stopped in.
    assert sim.output_every == 5
    step, time_, name = sim.writer.entries[-1]
    assert step == finished and time_ == pytest.approx(sim.time, rel=1e-12)
    written = npio.read_step(tmp_path / name)
    np.testing.assert_array_equal(written.points[:, :2], sim.particles.x)
    # The handlers found before the run are put back after it.
    assert {sig: signal.getsignal(sig) for sig in before} == before


def test_a_run_started_with_sigint_ignored_stays_deaf_to_it(tmp_path):
    # Under nohup, or as a background job of a script (`cmd &`), a process
    # starts with SIGINT ignored.  The run must keep it ignored (not become
    # interruptible by it), still stop on SIGTERM, and put back both handlers.
    found = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        sim = _sim(tmp_path)
        original = sim._advance

        def signalling(dt):
            if sim.step + 1 == 2:
                os.kill(os.getpid(), signal.SIGINT)  # ignored
            if sim.step + 1 == 4:
                os.kill(os.getpid(), signal.SIGTERM)  # stops after step 4
            return original(dt)

        sim._advance = signalling
        term = signal.getsignal(signal.SIGTERM)
        with pytest.raises(RunInterrupted) as info:
            sim.run(t_end=1.0)
        assert info.value.signal_name == "SIGTERM" and info.value.step == 4
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGTERM) is term
    finally:
        signal.signal(signal.SIGINT, found)


def test_progress_without_a_terminal_prints_lines(monkeypatch):
    # Progress to a pipe (CI, nohup, a notebook): the first step, then one line
    # per interval, and the last step; each with step, t, dt, iterations,
    # wall time and ETA.
    buf = io.StringIO()
    with redirect_stderr(buf):
        sim = _sim(None, t_end=0.05)
        sim.progress, sim.progress_interval = True, 0.0
        sim.run(t_end=0.05)
    lines = buf.getvalue().splitlines()
    assert len(lines) == 10 == len(sim.records)
    for k, line in enumerate(lines, start=1):
        assert line.startswith(f"step {k:5d}  t={0.005 * k:.4g} s  dt=0.005")
        assert " it)" in line and "wall" in line and "eta" in line
    assert f"{100 * 10 / 10:5.1f}%" in lines[-1]
    # With a long interval: the first and the last step only.
    buf = io.StringIO()
    with redirect_stderr(buf):
        sim = _sim(None, t_end=0.05)
        sim.progress, sim.progress_interval = True, 3600.0
        sim.run(t_end=0.05)
    lines = buf.getvalue().splitlines()
    assert [ln[:10] for ln in lines] == ["step     1", "step    10"]


def test_progress_says_why_a_run_ended_early():
    # A run that ends on its stop rule before t_end: the last line names the
    # rule (an AtRest run says "at rest") instead of a share and a time left
    # that no longer apply (a run that reaches t_end ends on 100 %: above).
    class Rule:
        label = "three steps"

        def __call__(self, sim):
            return sim.step >= 3

    for stop, reason in [
        (Rule(), "three steps"),
        (lambda s: s.step >= 3, "stop rule met"),
    ]:
        buf = io.StringIO()
        with redirect_stderr(buf):
            sim = _sim(None, t_end=0.05)
            sim.progress, sim.progress_interval = True, 3600.0
            sim.run(t_end=0.05, stop=stop)
        lines = buf.getvalue().splitlines()
        assert sim.step == 3 and sim.stopped_by == reason
        assert lines[-1].startswith("step     3  t=0.015 s")
        assert "Solved (" in lines[-1] or "AlmostSolved (" in lines[-1]
        assert f" it)  stopped: {reason}  wall " in lines[-1]
        assert "eta" not in lines[-1] and "%" not in lines[-1]
    assert AtRest.label == "at rest"


def test_progress_estimate_of_the_time_left():
    # Half of the steps done in a measured wall time: the ETA is that time.
    p = Progress(True, n_target=20, t_end=None)
    rec = type("R", (), {"step": 10, "dt": 0.1, "status": "Solved", "iterations": 9})
    p.start -= 4.0  # 4 s of wall time so far
    text = p.text(rec, 1.0, 0, 0.0)
    assert " 50.0%" in text and "(9 it)" in text
    eta = float(text.split("eta")[1].split()[0])
    assert eta == pytest.approx(4.0, abs=0.05)
    assert np.isfinite(eta)


def test_a_resumed_run_reports_the_peak_memory_of_the_whole_run(tmp_path):
    # Peak memory is a process's; a run stopped and continued in another
    # process reports the larger of the two (the checkpoint carries the first).
    from skfem_npfem.io.checkpoints import save_checkpoint
    from skfem_npfem.run.statistics import peak_memory_mb

    sim = _sim(tmp_path / "a")
    sim.run(steps=2)
    arrays, meta = npio.load_checkpoint(sim.save_checkpoint())
    assert 0.0 < meta["peak_memory_mb"] <= peak_memory_mb()
    # As if the first process had peaked far above this one.
    big = save_checkpoint(tmp_path / "big.npz", arrays, {**meta, "peak_memory_mb": 1e9})
    resumed = _sim(tmp_path / "b")
    resumed.restore(big)
    resumed.run(steps=1)
    assert resumed.summary()["peak_memory_mb"] == 1e9
    _, again = npio.load_checkpoint(resumed.save_checkpoint())
    assert again["peak_memory_mb"] == 1e9  # and a third process would see it
    # A checkpoint without the record (older files): the process's own peak.
    old = save_checkpoint(
        tmp_path / "old.npz",
        arrays,
        {k: v for k, v in meta.items() if k != "peak_memory_mb"},
    )
    fresh = _sim(tmp_path / "c")
    fresh.restore(old)
    assert fresh.summary()["peak_memory_mb"] == pytest.approx(
        peak_memory_mb(), rel=0.05
    )
