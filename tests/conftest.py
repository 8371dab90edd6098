"""Shared pytest set-up: headless rendering, no time limit for slow studies."""

import os

import pytest

# pyvista/VTK: render off-screen through EGL without trying an X server first.
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")


def pytest_collection_modifyitems(config, items):
    """Lift the per-test time limit (``timeout`` in pyproject) for slow studies."""
    for item in items:
        if item.get_closest_marker("slow") is not None:
            item.add_marker(pytest.mark.timeout(0))
