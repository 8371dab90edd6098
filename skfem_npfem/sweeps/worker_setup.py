"""Set-up of the local cluster's worker processes (a Dask worker preload).

A local cluster's workers are in the terminal's process group, so Ctrl-C
reaches them as well as the sweep.  A worker must not react to it: the sweep
stops the cluster in order (its runs are resumed by the next invocation), and a
worker that dies of the SIGINT first makes its nanny log a traceback.  Loaded
by the workers of :func:`~skfem_npfem.sweeps.dask_session`'s local cluster.
"""

from __future__ import annotations

import signal
from typing import Any

__all__ = ["dask_setup", "ignore_sigint"]


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


ignore_sigint()
