"""Shared harness of the benchmark and demo scripts.

``step_time.py``, ``suite.py``, ``presets.py`` and ``dt_sweep.py`` measure in
the same way: they wait for a quiet machine, time a block of work (wall,
process CPU, cores used by other processes), fingerprint the library sources
(:mod:`skfem_npfem.io.provenance`), run every case in a fresh interpreter
that prints its record as one tagged JSON line, and write a JSON report with a
Markdown table next to it.  This module holds the one copy of that code, so
that the scripts cannot drift apart.  The scripts import it as a sibling
(``import _harness as harness``): Python puts a script's folder on
``sys.path``.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
import platform
import resource
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

from skfem_npfem.io.provenance import git, source_sha1

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
#: Prefix of the stdout line that carries a child's JSON record.
RESULT_TAG = "@@RESULT@@ "
_CLK_TCK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


# --------------------------------------------------------------------------------
# Which step a seed-column benchmark measures
# --------------------------------------------------------------------------------
#: ``--method`` of the seed-column benchmarks: ``bare`` is the reference
#: paper's bare method, which their committed results measured; ``default`` is
#: the geometry's defaults of today (stabilised and volume-keeping).
METHODS = ("bare", "default")


def add_method_argument(ap) -> None:
    """Add ``--method {bare,default}`` to a benchmark's argument parser."""
    ap.add_argument(
        "--method",
        choices=METHODS,
        default="bare",
        help="bare (default): the paper's bare method, as the committed results "
        "were measured (no stabilisation or volume correction, alpha 1.3, in 3D "
        "buried slivers dropped); default: the geometry's defaults of today",
    )


def method_overrides(geometry: str, method: str) -> dict:
    """``column-collapse`` overrides that select ``method`` for ``geometry``."""
    from skfem_npfem.scenes.collapse.runs import bare_method

    if method not in METHODS:
        raise ValueError(f"method {method!r}: expected one of {METHODS}")
    return bare_method(geometry) if method == "bare" else {}


# --------------------------------------------------------------------------------
# Machine load
# --------------------------------------------------------------------------------
def cpu_busy_s() -> float:
    """Busy CPU seconds of all cores since boot.

    Returns
    -------
    float
        user .. steal jiffies of ``/proc/stat`` in seconds (NaN without
        ``/proc/stat``).
    """
    try:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:9]]
    except OSError:
        return math.nan
    return (sum(v) - v[3] - v[4]) / _CLK_TCK


def wait_for_idle(max_cores: float, max_wait: float, window: float = 3.0) -> dict:
    """Wait until the other processes use fewer than ``max_cores`` cores.

    Measured over ``window`` seconds from /proc/stat (not the 1-min load
    average, which lags and includes our own previous run).

    Parameters
    ----------
    max_cores : float
        Busy cores below which the machine counts as idle.
    max_wait : float
        Longest wait (s); the last measurement is returned after it.
    window : float
        Length of one measurement (s).

    Returns
    -------
    dict
        ``waited_s`` (the wait) and ``busy_cores`` (the last measured busy
        cores).
    """
    t0 = time.monotonic()
    while True:
        b0, w0 = cpu_busy_s(), time.monotonic()
        time.sleep(window)
        busy = (cpu_busy_s() - b0) / (time.monotonic() - w0)
        if not busy >= max_cores or time.monotonic() - t0 >= max_wait:
            return {"waited_s": time.monotonic() - t0, "busy_cores": busy}


def wait_for_quiet(max_load: float, max_wait: float) -> float:
    """Sleep until the 1-min load average is below ``max_load`` (or time out).

    Parameters
    ----------
    max_load : float
        Load average to wait for.
    max_wait : float
        Longest wait (s).

    Returns
    -------
    float
        The 1-min load average at the end of the wait.
    """
    t0 = time.monotonic()
    while os.getloadavg()[0] > max_load and time.monotonic() - t0 < max_wait:
        time.sleep(5.0)
    return os.getloadavg()[0]


class Meter:
    """Wall time, process CPU time and other processes' cores of a ``with`` block.

    Attributes set on entry: ``load_before`` (1-min load average); on exit:
    ``wall`` (s), ``cpu`` (process CPU time of all threads, s) and ``others``
    (mean number of cores used by other processes meanwhile: busy time of
    /proc/stat minus our CPU time, over the wall time)::

        with Meter() as m:
            sim.run(steps=1)
        record = {"wall": m.wall, "cpu": m.cpu, "other_cores": m.others}
    """

    load_before: float
    wall: float
    cpu: float
    others: float

    def __enter__(self) -> Meter:
        self.load_before = os.getloadavg()[0]
        self._busy0 = cpu_busy_s()
        self._cpu0 = time.process_time()
        self._t0 = time.perf_counter()
        return self

    def __exit__(self, *exc: object) -> None:
        self.wall = time.perf_counter() - self._t0
        self.cpu = time.process_time() - self._cpu0
        self.others = max((cpu_busy_s() - self._busy0 - self.cpu) / self.wall, 0.0)


def peak_rss_mb() -> float:
    """Peak resident set size of this process, MB (Linux: ru_maxrss in kB)."""
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r / 1024.0 if sys.platform != "darwin" else r / 2**20


# --------------------------------------------------------------------------------
# Code version and machine
# --------------------------------------------------------------------------------
def source_hash() -> str:
    """SHA-1 (12 hex digits) of the library sources, to tell code versions apart."""
    return source_sha1(ROOT)


def code_info() -> dict:
    """Git HEAD, locally modified library files and the source hash (read-only)."""
    info: dict = {"source_sha1": source_hash()}
    head = git("rev-parse", "--short", "HEAD")
    if head is None:
        return info
    info["git_head"] = head.strip()
    status = git("status", "--porcelain", "--", "skfem_npfem")
    if status is not None:
        info["git_modified"] = [ln[3:] for ln in status.splitlines() if ln.strip()]
    return info


def machine_info() -> dict:
    """CPU, cores, memory, package versions (MKL too) and the code version."""
    import clarabel
    import numpy
    import scipy
    import skfem

    cpu = platform.processor() or "unknown"
    flags_bits = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name") and cpu in ("unknown", "", "x86_64"):
                cpu = line.split(":", 1)[1].strip()
            if line.startswith("flags") and not flags_bits:
                fl = line.split(":", 1)[1].split()
                flags_bits = " ".join(f for f in ("avx2", "avx512f", "fma") if f in fl)
    except OSError:
        pass
    mem_gb = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                mem_gb = round(int(line.split()[1]) / 2**20, 1)
    except OSError:
        pass
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = os.cpu_count()
    try:
        from skfem_npfem import __version__ as npfem_version
    except ImportError:
        npfem_version = "unknown"
    info = {
        "cpu": cpu,
        "cpu_flags": flags_bits,
        "cores": os.cpu_count(),
        "cores_available": affinity,
        "memory_gb": mem_gb,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "clarabel": clarabel.__version__,
        "scikit-fem": getattr(skfem, "__version__", "unknown"),
        "skfem-npfem": npfem_version,
        "date": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
        "code": code_info(),
    }
    try:
        from importlib.metadata import version

        info["mkl"] = version("mkl")
    except Exception:
        info["mkl"] = None
    try:
        from skfem_npfem.step.backends import mkl_available

        info["mkl_available"] = bool(mkl_available())
    except Exception:
        info["mkl_available"] = False
    return info


# --------------------------------------------------------------------------------
# Child interpreters
# --------------------------------------------------------------------------------
def emit_result(obj: dict) -> None:
    """Print a child's JSON record as the tagged stdout line :func:`run_child` reads."""
    print(RESULT_TAG + json.dumps(obj), flush=True)


def child_env() -> dict[str, str]:
    """This process's environment with the repository root first in PYTHONPATH."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT), *filter(None, [env.get("PYTHONPATH")])]
    )
    return env


class ChildRun(NamedTuple):
    """Outcome of :func:`run_child`."""

    #: The child's record (last tagged stdout line), None if it printed none.
    result: dict | None
    #: Why there is no record (failure with the stderr tail, or the timeout).
    note: str | None
    #: Wall time of the child (s).
    wall_s: float
    #: CPU time of the child (user + system, all threads, s).
    cpu_s: float


def run_child(
    script: Path | str,
    args: list[str],
    timeout: float | None = None,
    *,
    failed: str = "failed",
    killed: str = "killed after {timeout:.0f} s",
    tail: int = 1500,
) -> ChildRun:
    """Run ``python script *args`` with the repository root on PYTHONPATH.

    The child reports with :func:`emit_result`; its last tagged stdout line is
    the result.

    Parameters
    ----------
    script : Path or str
        The script to run (in a fresh interpreter, ``sys.executable``).
    args : list of str
        Its command-line arguments.
    timeout : float or None
        Seconds after which the child is killed (None: no limit).
    failed : str
        Start of the note when the child printed no result; the note reads
        ``"<failed> (rc=<returncode>): <stderr tail>"``.
    killed : str
        Note on a timeout, formatted with ``timeout``.
    tail : int
        Characters of the child's stderr kept in the failure note.

    Returns
    -------
    ChildRun
        ``(result, note, wall_s, cpu_s)``: exactly one of ``result`` and
        ``note`` is None.
    """
    cmd = [sys.executable, str(script), *args]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()

    def cpu_s() -> float:
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)

    try:
        proc = subprocess.run(
            cmd, env=child_env(), capture_output=True, text=True, timeout=timeout
        )
    except subprocess.TimeoutExpired:
        wall = time.perf_counter() - t0
        return ChildRun(None, killed.format(timeout=timeout), wall, cpu_s())
    wall = time.perf_counter() - t0
    cpu = cpu_s()
    for line in reversed(proc.stdout.splitlines()):
        if line.startswith(RESULT_TAG):
            return ChildRun(json.loads(line[len(RESULT_TAG) :]), None, wall, cpu)
    note = f"{failed} (rc={proc.returncode}): {proc.stderr.strip()[-tail:]}"
    return ChildRun(None, note, wall, cpu)


# --------------------------------------------------------------------------------
# Reports
# --------------------------------------------------------------------------------
#: Phases of ``StepRecord.timings`` that belong to the cone solver (Clarabel's
#: constructor, which includes the symbolic analysis, and the solve).
SOLVER_PHASES = ("setup", "solve")


def non_solver_s(phase_s: dict) -> float:
    """Seconds of a step outside the cone solver, from a phase -> seconds dict.

    Parameters
    ----------
    phase_s : dict
        Seconds per phase (e.g. ``median_phase_s`` of a summary).

    Returns
    -------
    float
        The sum over every phase but :data:`SOLVER_PHASES`.
    """
    return sum(v for k, v in phase_s.items() if k not in SOLVER_PHASES)


def fmt_s(x: float) -> str:
    """Seconds for a table: 3 decimals below 1 s, 2 below 10, 1 below 100, else 0."""
    if x >= 100:
        return f"{x:.0f}"
    if x >= 10:
        return f"{x:.1f}"
    if x >= 1:
        return f"{x:.2f}"
    return f"{x:.3f}"


def code_line(code: dict) -> str:
    """``Code: git <head>, library source hash <hash> (locally modified: ...).``"""
    return (
        f"Code: git {code.get('git_head', '?')}, library source hash "
        f"{code.get('source_sha1', '?')}"
        + (
            f" (locally modified: {', '.join(code['git_modified'])})"
            if code.get("git_modified")
            else ""
        )
        + "."
    )


def runs_by_hash(
    runs: list[dict], label: Callable[[dict], str]
) -> dict[str, list[str]]:
    """Library source hash -> labels of the runs made with it.

    More than one key: the sources changed during the sweep.

    Parameters
    ----------
    runs : list of dict
        Run records with a ``source_sha1`` (runs without one are left out).
    label : callable
        Name of a run in the list.

    Returns
    -------
    dict
        Hash -> run labels, in the order of first appearance.
    """
    by_hash: dict[str, list[str]] = {}
    for r in runs:
        if r.get("source_sha1"):
            by_hash.setdefault(r["source_sha1"], []).append(label(r))
    return by_hash


def finish_markdown(lines: list[str], notes: list[str]) -> str:
    """Append the ``Notes:`` list (if any) to the lines; the Markdown text."""
    if notes:
        lines = [*lines, "", "Notes:", "", *notes]
    return "\n".join([*lines, ""])


def load_pair(path_a: str, path_b: str) -> tuple[dict, dict, list[str]]:
    """Two reports to compare and the header lines naming them.

    Parameters
    ----------
    path_a, path_b : str
        The JSON reports (A: before, B: after).

    Returns
    -------
    tuple
        ``(a, b, lines)``: the reports and the ``A = ...``, ``B = ...`` lines
        (with their dates) followed by a blank line.
    """
    a = json.loads(Path(path_a).read_text())
    b = json.loads(Path(path_b).read_text())
    lines = [
        f"A = {path_a} ({a['machine'].get('date', '?')})",
        f"B = {path_b} ({b['machine'].get('date', '?')})",
        "",
    ]
    return a, b, lines


def write_report(path: Path, report: dict, markdown: str) -> None:
    """Write ``report`` to ``path`` (JSON) and ``markdown`` next to it (``.md``)."""
    path.write_text(json.dumps(report, separators=(",", ":")) + "\n")  # compact
    path.with_suffix(".md").write_text(markdown)


def render(path: Path | str, markdown: Callable[[dict], str]) -> int:
    """Rewrite ``FILE.md`` from ``FILE.json`` with ``markdown`` and print it.

    Parameters
    ----------
    path : Path or str
        The JSON report.
    markdown : callable
        Report -> Markdown text.

    Returns
    -------
    int
        0 (an exit status).
    """
    path = Path(path)
    md = markdown(json.loads(path.read_text()))
    path.with_suffix(".md").write_text(md)
    print(md)
    return 0
