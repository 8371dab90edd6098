"""Shared pytest set-up: headless rendering, no time limit for slow studies."""

import importlib.util
import os
import sys
from pathlib import Path

import pytest

# The studies of demos/studies import their shared module (``import _common``)
# and each other by name, as they do when run as scripts; the tests import them
# the same way (``import collapse_validation``).
STUDIES = Path(__file__).resolve().parents[1] / "demos" / "studies"
if str(STUDIES) not in sys.path:
    sys.path.insert(0, str(STUDIES))

# pyvista/VTK: render off-screen through EGL without trying an X server first.
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")


#: The numerical libraries' thread pools, one thread each under pytest-xdist.
THREAD_POOLS = (
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "RAYON_NUM_THREADS",
)


def pytest_configure(config):
    """Give each pytest-xdist worker one thread of every numerical library.

    The workers (``-n``, one per core by default) share the machine's cores;
    a worker whose BLAS or sparse solver also started a thread per core would
    oversubscribe them.  Set in the controller before the workers start, so
    they inherit it; a value the user set is kept.
    """
    workers = getattr(config.option, "numprocesses", None)
    if workers and not os.environ.get("PYTEST_XDIST_WORKER"):
        for name in THREAD_POOLS:
            os.environ.setdefault(name, "1")


#: Docstring examples that start a Dask cluster (the ``sweep`` extra).
NEEDS_SWEEP_EXTRA = {"skfem_npfem.sweeps.engine.run_tasks"}


def _sweep_extra_missing() -> bool:
    return any(importlib.util.find_spec(m) is None for m in ("distributed", "pandas"))


def pytest_collection_modifyitems(config, items):
    """Lift the per-test time limit (``timeout`` in pyproject) for slow studies;
    skip the docstring examples that need the sweep extra when it is missing."""
    missing = _sweep_extra_missing()
    for item in items:
        if item.get_closest_marker("slow") is not None:
            item.add_marker(pytest.mark.timeout(0))
        if missing and item.name in NEEDS_SWEEP_EXTRA:
            item.add_marker(pytest.mark.skip(reason="needs the sweep extra (Dask)"))
