"""Linear-solver backends of Clarabel and the automatic choice between them.

Clarabel factorises one KKT system per interior-point iteration; that is over 95 %
of an N-PFEM step.  Its ``direct_solve_method`` can be ``qdldl`` (single-threaded),
``faer`` (supernodal, multithreaded) or ``mkl`` (Intel MKL Pardiso).

MKL Pardiso is optional (``pip install "skfem-npfem[mkl]"``).  Clarabel loads it at
run time by looking for an *unversioned* ``libmkl_rt.so`` in ``LD_LIBRARY_PATH``,
``$MKLROOT/lib``, ``$MKL_PARDISO_PATH`` or ``/opt/intel/oneapi/mkl/latest/lib``; the
PyPI ``mkl`` wheel only ships ``libmkl_rt.so.<N>`` in ``<sys.prefix>/lib``.
:func:`mkl_available` bridges that gap without any user set-up: it adds the
unversioned link next to the wheel's libraries (or, if that folder is read-only,
builds a private folder in the user cache with the runtime library and links to its
sibling libraries, which MKL loads from its own folder), points
``MKL_PARDISO_PATH`` there before the first solve, and checks with a 2x2 solve.
Clarabel tries to load MKL once per process, so the check runs before any solve
that asks for ``mkl``.
"""

from __future__ import annotations

import ctypes
import functools
import glob
import hashlib
import os
import shutil
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import clarabel
import numpy as np
import scipy.sparse as sp

__all__ = [
    "available_cores",
    "choose_linear_solver",
    "faer_threads",
    "mkl_available",
    "mkl_library_dir",
    "pardiso_threads",
]

# Problem sizes (number of cone-program variables) where the backends cross over,
# measured on a 2-core machine (s/step, high preset; docs/performance.md).
# Without MKL (benchmarks/results/crossover_2d.md, faer single-threaded as it runs
# there by default): qdldl beats faer on the 2D collapse at 5.3k and 10.3k
# variables (0.221 vs 0.359 s, 0.623 vs 0.836 s) and loses at 20.3k (2.16 vs
# 1.83 s); on the structured strip-footing mesh faer wins already at 4.8k (0.35 vs
# 0.48 s) -- the crossover follows the fill-in, not only the size, and is placed
# for the remeshed PFEM case.  MKL Pardiso (2 threads, no iterative refinement;
# benchmarks/results/suite.md) loses to qdldl on the 1k-particle collapse (5.3k
# variables: 0.27 vs 0.23 s) and wins from the 2k-particle collapse on (10k
# variables: 0.58 vs 0.67 s; 20k: 1.34 vs 2.42 s) and on every 3D case (3k
# particles: 4.05 s vs faer 8.03 s).
QDLDL_MAX_VARIABLES_2D = 15_000
MKL_MIN_VARIABLES = 8_000


def _wheel_lib_dirs() -> list[Path]:
    """Folders that may hold the PyPI ``mkl`` wheel's ``libmkl_rt.so.<N>``."""
    cands = {Path(sys.prefix) / "lib", Path(sys.base_prefix) / "lib"}
    for var in ("MKLROOT", "CONDA_PREFIX"):
        if os.environ.get(var):
            cands.add(Path(os.environ[var]) / "lib")
    return [c for c in cands if c.is_dir()]


def mkl_library_dir() -> Path | None:
    """Folder with an unversioned ``libmkl_rt.so`` usable by Clarabel, or None.

    Creates the unversioned link (or a private folder in the user cache) when only
    the versioned library of the PyPI wheel exists.
    """
    if sys.platform != "linux":
        return None
    for folder in _wheel_lib_dirs():
        unversioned = folder / "libmkl_rt.so"
        if unversioned.exists():
            return folder
        versioned = sorted(glob.glob(str(folder / "libmkl_rt.so.*")))
        if not versioned:
            continue
        try:  # next to the wheel's libraries, where MKL finds its siblings
            unversioned.symlink_to(Path(versioned[-1]).name)
            return folder
        except OSError:
            pass
        return _private_copy(folder, Path(versioned[-1]))
    return None


def _private_copy(folder: Path, runtime: Path) -> Path | None:
    """A cache folder with the runtime library and links to its siblings."""
    key = hashlib.sha1(str(runtime.resolve()).encode()).hexdigest()[:12]
    base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    target = base / "skfem-npfem" / f"mkl-{key}"
    try:
        target.mkdir(parents=True, exist_ok=True)
        rt = target / "libmkl_rt.so"
        if not rt.exists():
            tmp = target / ".libmkl_rt.so.tmp"
            shutil.copy2(runtime, tmp)
            tmp.replace(rt)
        for lib in folder.glob("lib*.so*"):
            if lib.name.startswith("libmkl_rt."):
                continue
            link = target / lib.name
            if not link.exists():
                link.symlink_to(lib)
    except OSError:
        return None
    return target


@functools.cache
def mkl_available() -> bool:
    """True if Clarabel can use MKL Pardiso in this process (checked once)."""
    folder = mkl_library_dir()
    if folder is None:
        return False
    os.environ.setdefault("MKL_PARDISO_PATH", str(folder))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.direct_solve_method = "mkl"
    try:
        solver = clarabel.DefaultSolver(
            sp.csc_matrix(np.eye(2)),
            np.array([1.0, -1.0]),
            sp.csc_matrix(np.eye(2)),
            np.ones(2),
            [clarabel.NonnegativeConeT(2)],
            settings,
        )
        return str(solver.solve().status) == "Solved"
    except Exception:  # Clarabel reports an unavailable backend as Exception
        return False


#: faer with its default thread count (all cores) was 17-22 % slower than with one
#: thread on a 2-core machine in every case measured (2D 4k / 16k, 3D 3k:
#: benchmarks/results/threads.md); machines with this many cores or fewer run faer
#: single-threaded unless ``max_threads`` says otherwise.
FAER_SERIAL_MAX_CORES = 2


def available_cores() -> int:
    """Cores this process may run on (CPU affinity where the OS reports it)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def faer_threads(requested: int = 0) -> int:
    """Threads to give faer: ``requested`` if > 0, else 1 on small machines.

    0 (Clarabel's automatic choice) is returned on machines with more than
    :data:`FAER_SERIAL_MAX_CORES` cores, where no measurement says otherwise.
    """
    if requested > 0:
        return int(requested)
    return 1 if available_cores() <= FAER_SERIAL_MAX_CORES else 0


#: ``MKL_DOMAIN_PARDISO`` of mkl_types.h: MKL's thread setting for Pardiso only.
_MKL_DOMAIN_PARDISO = 4


@functools.cache
def _mkl_runtime() -> ctypes.CDLL | None:
    """The ``libmkl_rt`` that Clarabel loaded into this process (None: no MKL).

    Found in ``/proc/self/maps`` after :func:`mkl_available` has made Clarabel
    load it, so that thread settings reach the very library Pardiso runs in.
    """
    if not mkl_available():
        return None
    path = None
    try:
        with open("/proc/self/maps") as f:
            for line in f:
                name = line.rsplit(None, 1)[-1]
                if os.path.basename(name).startswith("libmkl_rt.so"):
                    path = name
                    break
    except OSError:
        pass
    if path is None:
        path = str(Path(os.environ.get("MKL_PARDISO_PATH", "")) / "libmkl_rt.so")
    try:
        return ctypes.CDLL(path)
    except OSError:
        return None


def pardiso_thread_count(requested: int = 0) -> int:
    """Threads MKL Pardiso runs with: ``requested`` if > 0, else MKL's own setting.

    Returns 0 when MKL is not available.
    """
    lib = _mkl_runtime()
    if lib is None:
        return 0
    if requested > 0:
        return int(requested)
    return int(lib.MKL_Domain_Get_Max_Threads(_MKL_DOMAIN_PARDISO))


@contextmanager
def pardiso_threads(n: int) -> Iterator[None]:
    """Run MKL Pardiso with ``n`` threads inside the block (0: MKL's setting).

    Clarabel 0.11 applies its ``max_threads`` to Pardiso only *after* the
    symbolic analysis, and MKL 2026.2 then crashes (SIGSEGV) in 3D programs when
    the count drops to 1 (a 225-node block already).  Setting MKL's Pardiso
    thread count before the solver is built avoids that; the previous setting
    is restored afterwards.
    """
    lib = _mkl_runtime() if n > 0 else None
    if lib is None:
        yield
        return
    old = int(lib.MKL_Domain_Get_Max_Threads(_MKL_DOMAIN_PARDISO))
    lib.MKL_Domain_Set_Num_Threads(int(n), _MKL_DOMAIN_PARDISO)
    try:
        yield
    finally:
        lib.MKL_Domain_Set_Num_Threads(old, _MKL_DOMAIN_PARDISO)


def choose_linear_solver(n_variables: int, dim: int, coupled: bool = False) -> str:
    """Pick Clarabel's direct solver from availability, dimension and size.

    MKL Pardiso when installed and the problem is not tiny; otherwise qdldl for
    small 2D problems and faer for large 2D and all 3D problems (denser factors).
    ``coupled``: the objective couples neighbouring stresses (the stabilisation
    of :mod:`skfem_npfem.step.stabilisation`) or excess pore pressures (the
    pressure projection and Darcy's term of undrained and coupled water,
    :func:`~skfem_npfem.step.conic.couples_pore_pressures`); the factors are
    then denser and faer wins from small sizes on (1 035-particle collapse,
    beta = 30: qdldl 0.66 s, faer 0.48 s a step; without stabilisation 0.20 s
    and 0.35 s; shared machine, stepped alternately in one process).

    Examples
    --------
    >>> choose_linear_solver(500, 2) in ("qdldl", "mkl")
    True
    """
    if n_variables >= MKL_MIN_VARIABLES and mkl_available():
        return "mkl"
    if dim == 2 and n_variables < QDLDL_MAX_VARIABLES_2D and not coupled:
        return "qdldl"
    return "faer"
