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
