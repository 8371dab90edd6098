"""Progress reports and interrupt handling of the time loop.

:class:`Progress` reports on stderr while :class:`~skfem_npfem.Simulation`
runs: on a terminal one line that is rewritten after every step; elsewhere (CI,
``nohup``, a notebook, a pipe) a new line every :data:`INTERVAL` seconds, plus
the first and the last step, so that a long run is never silent.  Each report
gives the step, t, Δt, the solver status and IPM iterations, the share done,
the wall time and an estimate of the time left.  :func:`end_line` ends an open
terminal line, so that whatever is printed next starts on its own line.

:class:`SignalGuard` turns SIGINT (Ctrl-C) and SIGTERM into a request to stop
after the step in progress; a second signal while a step is being solved
abandons that step (:class:`AbandonStep`).  Only the main thread can install
signal handlers; elsewhere (Dask workers) the guard does nothing.
"""

from __future__ import annotations

import math
import signal
import sys
import threading
import time
from typing import Any

import numpy as np

__all__ = ["INTERVAL", "AbandonStep", "Progress", "SignalGuard", "end_line"]

#: Seconds between progress lines when stderr is not a terminal.
INTERVAL = 10.0

_open_line = {"width": 0}


def end_line() -> None:
    """End a progress line left open on a terminal (no-op otherwise)."""
    if _open_line["width"]:
        _open_line["width"] = 0
        print(file=sys.stderr, flush=True)


def _isatty() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class Progress:
    """Progress reports of one :meth:`Simulation.run` call on stderr.

    Parameters
    ----------
    enabled : bool
        False: report nothing.
    n_target : int or None
        Step at which the run ends (None: unknown).
    t_end : float or None
        End time, s (None: unknown).
    interval : float
        Seconds between lines when stderr is not a terminal.
    """

    def __init__(
        self,
        enabled: bool,
        n_target: int | None,
        t_end: float | None,
        interval: float = INTERVAL,
    ) -> None:
        self.enabled = enabled
        self.tty = _isatty()
        self.n_target, self.t_end, self.interval = n_target, t_end, interval
        self.start = time.perf_counter()
        self.last_line = -math.inf
        self.lines = 0
        self.pending: str | None = None

    def share(self, step: int, t: float) -> float:
        """Share of the whole run done at ``step``/``t``, in [0, 1] (NaN: unknown).

        Counted from step 0 and t = 0, so a resumed run continues where the
        interrupted one stopped.
        """
        if self.n_target:
            done = step / self.n_target
        elif self.t_end:
            done = t / self.t_end
        else:
            return math.nan
        return min(max(done, 0.0), 1.0)

    def text(
        self,
        rec: Any,
        t: float,
        start_step: int,
        start_time: float,
        stopped: str | None = None,
    ) -> str:
        """One report: step, t, dt, status, iterations, done, wall and ETA.

        The share done counts the whole run (a resumed run continues from the
        share it was resumed at); the estimate of the time left extrapolates
        the progress made since this call of ``run`` started (never < 0).
        ``stopped``: the run ends at this step, before its step count or end
        time, for this reason (``"at rest"``); the report says so instead of
        the share and the time left.
        """
        wall = time.perf_counter() - self.start
        head = (
            f"step {rec.step:5d}  t={t:.4g} s  dt={rec.dt:.3g}  "
            f"{rec.status} ({rec.iterations} it)  "
        )
        if stopped is not None:
            return head + f"stopped: {stopped}  wall {wall:7.1f} s"
        done = self.share(rec.step, t)
        begun = self.share(start_step, start_time)
        made = done - begun
        left = max(wall * (1 - done) / made, 0.0) if made > 0 else math.nan
        share = f"{100 * done:5.1f}%" if math.isfinite(done) else "   ? %"
        eta = f"{left:7.1f} s" if math.isfinite(left) else "      ?  "
        return head + f"{share}  wall {wall:7.1f} s  eta {eta}"

    def update(
        self,
        rec: Any,
        t: float,
        start_step: int,
        start_time: float,
        stopped: str | None = None,
    ) -> None:
        """Report the step just finished (rate-limited off a terminal)."""
        if not self.enabled:
            return
        msg = self.text(rec, t, start_step, start_time, stopped)
        if self.tty:
            pad = max(0, _open_line["width"] - len(msg))
            print("\r" + msg + " " * pad, end="", file=sys.stderr, flush=True)
            _open_line["width"] = len(msg)
            return
        now = time.perf_counter()
        if self.lines == 0 or now - self.last_line >= self.interval:
            print(msg, file=sys.stderr, flush=True)
            self.last_line, self.pending = now, None
            self.lines += 1
        else:
            self.pending = msg

    def close(self) -> None:
        """End the terminal line, or print the last step if not yet reported."""
        if not self.enabled:
            return
        if self.tty:
            end_line()
        elif self.pending is not None:
            print(self.pending, file=sys.stderr, flush=True)
            self.pending = None


class AbandonStep(KeyboardInterrupt):
    """A second SIGINT/SIGTERM arrived while a step was being solved."""


class SignalGuard:
    """Turn SIGINT/SIGTERM into a stop request while a run is in progress.

    Use as a context manager around the time loop; check :attr:`signum` after
    each step.  While :attr:`in_step` is True, a second signal raises
    :class:`AbandonStep` (the step in progress is dropped; the state of the
    last finished step is intact).

    A signal that is ignored when the guard is entered stays ignored: a run
    started under ``nohup`` or as a background job of a script (``cmd &``,
    which start it with SIGINT ignored) is not stopped by SIGINT, and still
    by SIGTERM.  On exit every handler the guard replaced is put back as it
    was found.
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.signum: int | None = None
        self.in_step = False
        self._previous: dict[int, Any] = {}

    def _handler(self, signum: int, frame: Any) -> None:
        if self.signum is not None and self.in_step:
            self.in_step = False
            raise AbandonStep
        if self.signum is None:
            self.signum = signum

    def __enter__(self) -> SignalGuard:
        if threading.current_thread() is threading.main_thread():
            for sig in self.SIGNALS:
                try:
                    if signal.getsignal(sig) is signal.SIG_IGN:
                        continue  # ignored by whoever started us: keep it so
                    self._previous[sig] = signal.signal(sig, self._handler)
                except (ValueError, OSError):  # pragma: no cover - exotic hosts
                    pass
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, old in self._previous.items():
            # None: a handler installed outside Python, which cannot be put
            # back from here; the default is the closest.
            signal.signal(sig, signal.SIG_DFL if old is None else old)
        self._previous.clear()


def next_dt(
    x_before: np.ndarray, new: Any, rec: Any, dt: float, limit_h: float, sim: Any
) -> tuple[float, float]:
    """The next step of displacement control and this step's displacement ratio.

    The largest displacement from ``x_before`` (where the step's particles
    started, after any refinement) against ``limit_h`` times the mean
    spacing of the step's mesh.
    """
    h = (rec.mesh_volume / max(rec.n_active, 1)) ** (1.0 / new.dim)
    du = float(np.max(np.linalg.norm(new.x - x_before, axis=1)))
    limit = limit_h * h
    nxt = sim.dt
    if du > limit:
        nxt = max(0.9 * dt * limit / du, sim.dt_min)
    elif du > 0:
        nxt = min(sim.dt_max, 2 * dt, 0.9 * dt * limit / du)
    return nxt, du / limit
