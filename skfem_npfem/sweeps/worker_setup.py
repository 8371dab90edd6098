"""Set-up of the local cluster's worker processes (a Dask worker preload).

A local cluster's workers are in the terminal's process group, so Ctrl-C
reaches them as well as the sweep.  A worker must not react to it: the sweep
stops the cluster in order (its runs are resumed by the next invocation), and a
worker that dies of the SIGINT first makes its nanny log a traceback.  Nor
must it print one when the sweep's process, which holds the local cluster's
scheduler, has gone: a worker's heartbeat then fails with a traceback that is
no news (:func:`quiet_lost_scheduler`; the worker retries a heartbeat that
failed for any other reason).  Loaded by the workers of
:func:`~skfem_npfem.sweeps.dask_session`'s local cluster.
"""

from __future__ import annotations

import logging
import signal
from typing import Any

__all__ = ["dask_setup", "ignore_sigint", "quiet_lost_scheduler"]

#: What a worker logs (with a traceback) when a heartbeat finds no scheduler.
LOST_HEARTBEAT = "Failed to communicate with scheduler during heartbeat"


def _not_a_lost_heartbeat(record: logging.LogRecord) -> bool:
    return not str(record.msg).startswith(LOST_HEARTBEAT)


def quiet_lost_scheduler() -> None:
    """Drop the worker's lost-heartbeat record (the sweep is stopping).

    Examples
    --------
    >>> quiet_lost_scheduler()
    >>> log = logging.getLogger("distributed.worker")
    >>> log.filter(logging.makeLogRecord({"msg": LOST_HEARTBEAT + "."}))
    False
    >>> bool(log.filter(logging.makeLogRecord({"msg": "Closing worker."})))
    True
    """
    log = logging.getLogger("distributed.worker")
    if _not_a_lost_heartbeat not in log.filters:
        log.addFilter(_not_a_lost_heartbeat)


def ignore_sigint() -> bool:
    """Ignore SIGINT in this process; False where that is not possible."""
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread
        return False
    return True


def dask_setup(worker: Any) -> None:
    """The preload hook Dask calls when the worker starts."""
    ignore_sigint()
    quiet_lost_scheduler()


ignore_sigint()
quiet_lost_scheduler()
