"""Shared pytest set-up: headless rendering, no time limit for slow studies."""

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


def pytest_collection_modifyitems(config, items):
    """Lift the per-test time limit (``timeout`` in pyproject) for slow studies."""
    for item in items:
        if item.get_closest_marker("slow") is not None:
            item.add_marker(pytest.mark.timeout(0))
