"""Sphinx configuration of the skfem-npfem documentation.

Build (from the repository root, with the ``docs`` extra installed)::

    python -m sphinx -W -b html docs docs/_build/html

The build needs no network (no intersphinx), and neither do the built pages
(MathJax is copied into the site by ``sphinx-mathjax-offline``).  It runs
nothing heavy: the tutorials and the short gallery examples of ``demos/*.py``
execute (a few seconds each; the examples by sphinx-gallery), the studies of
``demos/studies/`` and the benchmarks are shown from the results those scripts
committed.  Pages generated at build time (``api/``, ``gallery/``) are written
by sphinx-gallery and the local extension ``_ext/npfem_docs`` and are not
committed.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE / "_ext"))

# The tutorials call the command line (`!skfem-npfem ...`) and read the committed
# study results: the notebook kernels inherit this environment.
os.environ["PATH"] = str(Path(sys.executable).parent) + os.pathsep + os.environ["PATH"]
os.environ["SKFEM_NPFEM_REPO"] = str(ROOT)
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
# The gallery examples save their figures here (npfem_docs.saved_figures shows them).
os.environ["NPFEM_GALLERY_OUT"] = tempfile.mkdtemp(prefix="npfem-gallery-")

import skfem_npfem  # noqa: E402

project = "skfem-npfem"
author = "skfem-npfem developers"
copyright = "skfem-npfem developers, BSD-3-Clause"
release = skfem_npfem.__version__
version = release

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    # MathJax 3 served from the site itself (_static/mathjax/), not from a
    # CDN: formulas render offline and the built pages load nothing from
    # another host (tests/docs/test_docs_build.py checks it).
    "sphinx-mathjax-offline",
    "sphinx_gallery.gen_gallery",
    "npfem_docs",
]

# The gallery: sphinx-gallery runs every example of demos/ (its ``# %%`` cells,
# each with its output and the figures it saved) on every build, so the pages
# show what the package gives today; a failing example fails the build.  The
# studies (demos/studies/, no gallery header) are not run; npfem_docs lists them.
sphinx_gallery_conf = {
    "examples_dirs": ["../demos"],
    "gallery_dirs": ["gallery"],
    "filename_pattern": r"\.py$",
    "run_stale_examples": True,
    "image_scrapers": ("npfem_docs.saved_figures",),
    "capture_repr": (),
    "download_all_examples": False,
    "write_computation_times": False,
    "within_subsection_order": "FileNameSortKey",
}

# Pages and files that are not part of the site.
exclude_patterns = [
    "_build",
    "jupyter_execute",
    ".jupyter_cache",
    "**.ipynb_checkpoints",
    # sphinx-gallery's notebook of each example (a download, not a page)
    "gallery/*.ipynb",
]
source_suffix = {".md": "myst-nb", ".rst": "restructuredtext"}
root_doc = "index"

# MyST: Markdown prose, `$...$` maths, ::: fences, heading anchors for
# cross-page links such as theory.md#nodal-integration.
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist", "amsmath"]
myst_heading_anchors = 3
myst_dmath_double_inline = True

# MyST-NB: the tutorials are MyST notebooks, executed on every build (they are
# part of the test suite through tests/docs/test_docs_build.py); an error fails the
# build.
nb_execution_mode = "force"
nb_execution_timeout = 300
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_execution_in_temp = True
nb_merge_streams = True

# API: NumPy-style docstrings.
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented_params"
autodoc_default_options = {"members": True, "undoc-members": False}
autodoc_preserve_defaults = True
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_ivar = True

html_theme = "furo"
html_title = f"skfem-npfem {release}"
html_static_path: list[str] = []
html_show_sourcelink = True
html_last_updated_fmt = None

nitpicky = False
suppress_warnings: list[str] = []
