"""Verification cases shared by the tests and the demos.

:mod:`cases.extremes` is the extremes matrix (docs/extremes.md): short runs of
the ``elastic-column`` and ``strip-footing`` scenes, and of the step API where a
scene cannot express the case, with parameters pushed to the edges.
``tests/scenes/test_extremes.py`` asserts every case;
``demos/studies/extremes_matrix.py`` runs them all and writes docs/extremes.md.
"""
