"""Where a sweep runs: a local Dask cluster or an existing scheduler.

Dask (``dask.distributed``) is an optional dependency (the ``sweep`` extra); it is
imported only here and only when a sweep starts.
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import re
import socket
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from ..errors import NpfemError, ParameterError
from ..step.backends import available_cores

__all__ = [
    "CONNECT_TIMEOUT",
    "DaskSession",
    "check_options",
    "dask_session",
    "require_dask",
    "solver_threads",
]

#: Seconds to wait for ``--scheduler`` to answer before giving up.
CONNECT_TIMEOUT = 10.0

INSTALL_HINT = "pip install 'skfem-npfem[sweep]'"

_ADDRESS = re.compile(
    r"^([a-z]+://)?[^\s/:]+(:\d+)?$|^[a-z]+://\[[0-9a-fA-F:]+\](:\d+)?$"
)


def require_dask() -> None:
    """Raise one clear line when Dask or pandas is missing."""
    missing = [m for m in ("distributed", "pandas") if _find_spec(m) is None]
    if missing:
        raise NpfemError(
            f"sweeps need Dask and pandas ({', '.join(missing)} not installed): "
            f"{INSTALL_HINT}"
        )


def _find_spec(name: str) -> Any:
    try:
        return importlib.util.find_spec(name)
    except (ImportError, ValueError):  # a module set to None in sys.modules
        return None


@dataclass
class DaskSession:
    """An open Dask client and what the sweep reports about it.

    Attributes
    ----------
    client : distributed.Client
        Connected client.
    where : str
        "N local workers" or the scheduler address.
    dashboard : str
        Dashboard address ("" when there is none).
    local : bool
        True for a cluster started (and stopped) by the sweep itself.
    """

    client: Any
    where: str
    dashboard: str
    local: bool


@contextlib.contextmanager
def dask_session(
    workers: int | None = None,
    scheduler: Any = None,
    connect_timeout: float = CONNECT_TIMEOUT,
) -> Iterator[DaskSession]:
    """A Dask client for a sweep; the local cluster is stopped on exit.

    Parameters
    ----------
    workers : int, optional
        Local cluster only: worker processes (default: one per available core),
        each with one thread.
    scheduler : str, Client or Cluster, optional
        ``tcp://HOST:PORT`` of a running scheduler (``dask scheduler``), an open
        ``distributed.Client``, or a cluster object (e.g. dask-jobqueue's
        ``SLURMCluster``).  Default: a local cluster.
    connect_timeout : float
        Seconds to wait for a scheduler address to answer.

    Raises
    ------
    ParameterError
        ``workers`` < 1, ``workers`` with ``scheduler``, a malformed address, or
        no answer from the scheduler within ``connect_timeout`` seconds.
    """
    require_dask()
    check_options(workers, scheduler, connect_timeout)
    from distributed import Client

    if scheduler is None:
        with _local_cluster(workers or available_cores()) as session:
            yield session
        return
    if isinstance(scheduler, Client):
        yield DaskSession(scheduler, _address(scheduler), _dashboard(scheduler), False)
        return
    if isinstance(scheduler, str):
        client = _connect(scheduler, connect_timeout)
    else:  # a cluster object (LocalCluster, dask-jobqueue, ...)
        client = Client(scheduler)
    try:
        yield DaskSession(client, _address(client), _dashboard(client), False)
    finally:
        client.close()


def check_options(workers: Any, scheduler: Any, connect_timeout: Any) -> None:
    """Raise :class:`ParameterError` for cluster options that cannot work."""
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise ParameterError("--workers", workers, "an integer >= 1")
    if scheduler is not None and workers is not None:
        raise ParameterError(
            "--workers",
            workers,
            "only with the local cluster (with --scheduler the scheduler's "
            "workers run the sweep)",
        )
    if isinstance(scheduler, str) and not _ADDRESS.match(scheduler.strip()):
        raise ParameterError(
            "--scheduler", scheduler, "a scheduler address such as tcp://HOST:8786"
        )
    if not (
        isinstance(connect_timeout, int | float)
        and not isinstance(connect_timeout, bool)
        and 0 < connect_timeout < float("inf")
    ):
        raise ParameterError("--connect-timeout", connect_timeout, "seconds > 0")


def _connect(address: str, timeout: float) -> Any:
    from distributed import Client

    try:
        return Client(address.strip(), timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as err:
        raise ParameterError(
            "--scheduler",
            address,
            f"a running Dask scheduler (no answer within {timeout:g} s: "
            f"{str(err).splitlines()[0] if str(err) else type(err).__name__})",
        ) from None


@contextlib.contextmanager
def _local_cluster(n: int) -> Iterator[DaskSession]:
    from distributed import Client, LocalCluster

    # The dashboard needs bokeh; without it the page would be a 404.
    with_dashboard = _find_spec("bokeh") is not None
    cluster = LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":8787" if with_dashboard and _port_free(8787) else ":0",
        silence_logs=logging.ERROR,
        # Ctrl-C is for the sweep, not for its workers (see worker_setup).
        preload=[WORKER_SETUP],
    )
    try:
        client = Client(cluster, set_as_default=False)
        try:
            where = f"{n} local worker{'s' * (n != 1)}"
            link = _dashboard(client) if with_dashboard else ""
            yield DaskSession(client, where, link, True)
        except KeyboardInterrupt:
            # Stopping on Ctrl-C: the cluster is shut down below, with tasks
            # still running; what Dask logs about them is no news to the user.
            _quiet_dask_logs()
            raise
        finally:
            client.close()
    finally:
        cluster.close()


#: Module the local cluster's workers load at start (they ignore SIGINT).
WORKER_SETUP = "skfem_npfem.sweeps.worker_setup"


def _quiet_dask_logs() -> None:
    """Silence Dask's loggers for the rest of the process (a shutdown)."""
    for name in ("distributed", "tornado", "asyncio"):
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)


def _port_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def _address(client: Any) -> str:
    try:
        return str(client.scheduler.address)
    except AttributeError:  # pragma: no cover - depends on the client state
        return "scheduler"


def _dashboard(client: Any) -> str:
    try:
        return str(client.dashboard_link or "")
    except (KeyError, AttributeError, ValueError):
        return ""


def solver_threads(client: Any) -> int:
    """Solver threads per run so that no machine runs more threads than cores.

    Each machine's available cores divided by the Dask task slots on it (its
    workers times their threads); the smallest over the machines, at least 1.
    Returns 1 while no worker is connected.
    """
    try:
        info = client.scheduler_info(n_workers=-1)  # all workers (dask >= 2025.4)
    except TypeError:
        info = client.scheduler_info()
    workers = info.get("workers", {})
    if not workers:
        return 1
    cores = client.run(available_cores)
    slots: dict[str, int] = defaultdict(int)
    host_cores: dict[str, int] = {}
    for addr, info in workers.items():
        host = info.get("host", addr)
        slots[host] += int(info.get("nthreads", 1))
        host_cores[host] = int(cores.get(addr, 1))
    return max(1, min(host_cores[h] // max(1, slots[h]) for h in slots))
