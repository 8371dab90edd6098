"""Shared pytest set-up: headless rendering for the viz tests."""

import os

# pyvista/VTK: render off-screen through EGL without trying an X server first.
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
