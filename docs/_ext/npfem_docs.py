"""Local Sphinx extension of the skfem-npfem documentation.

The examples of ``demos/`` are rendered by sphinx-gallery (``conf.py``); this
extension adds what it does not do.  At ``builder-inited`` it writes the
generated pages (never committed):

* ``api/``: one page per group of ``skfem_npfem.__all__`` (the ``#:`` comments
  of ``skfem_npfem/__init__.py``), so a name added to ``__all__`` appears in
  the reference without editing the docs (:mod:`npfem_api`);
* ``gallery/studies*``, ``gallery/benchmarks-*``, ``gallery/results-*``: one
  page per study of ``demos/studies/`` and script of ``benchmarks/`` (never run
  by the build) with its docstring, the figures it committed under ``docs/``,
  the pages that quote it and its source, and one per Markdown report of
  ``benchmarks/results`` (:mod:`npfem_studies`).

It gives sphinx-gallery the figures the examples save as files
(:func:`saved_figures`) and registers the ``pending-section`` directive of the
theory page.  (The tables of the pages are fragments the studies and
benchmarks write next to their JSON, ``benchmarks/_tables.py``, included with
MyST's ``{include}``.)

A page that no toctree lists (say a page another branch adds without
touching ``index.md``) would fail the ``-W`` build; instead it is listed
under "More" in the site's navigation (:func:`list_unlisted_pages`) and the
build says so in its log.
"""

from __future__ import annotations

import fnmatch
import os
import posixpath
import re
import shutil
from pathlib import Path
from typing import ClassVar

import npfem_api
import npfem_studies
from docutils import nodes
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)

TOCTREE = re.compile(r"^(`{3,}|:{3,})\{toctree\}[^\n]*\n(.*?)^\1[ \t]*$", re.M | re.S)


def write_if_changed(path: Path, text: str) -> None:
    """Write ``text`` unless the file already holds it (keeps Sphinx's cache)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def generate(app: Sphinx) -> None:
    """Write the generated pages into the source folder."""
    src = Path(app.srcdir)
    for rel, text in npfem_api.pages().items():
        write_if_changed(src / "api" / rel, text)
    for rel, text in npfem_studies.pages(src).items():
        write_if_changed(src / "gallery" / rel, text)


#: Where the examples of ``demos/`` save their figures (they read it).
OUT_ENV = "NPFEM_GALLERY_OUT"
#: Figure files already shown, with the modification time they were shown at.
_SHOWN: dict[Path, int] = {}


def saved_figures(block, block_vars: dict, gallery_conf: dict) -> str:
    """Sphinx-gallery image scraper: the PNG files a code block saved.

    The examples save their figures as files under ``$NPFEM_GALLERY_OUT``
    (``fig.savefig``, pyvista's ``screenshot``) instead of leaving them open;
    every file that appears or changes while a block runs is shown below it.
    """
    from sphinx_gallery.scrapers import figure_rst

    shown = []
    for png in sorted(Path(os.environ[OUT_ENV]).rglob("*.png")):
        stamp = png.stat().st_mtime_ns
        if _SHOWN.get(png) != stamp:
            _SHOWN[png] = stamp
            target = next(block_vars["image_path_iterator"])
            shutil.copyfile(png, target)
            shown.append(target)
    return figure_rst(shown, gallery_conf["src_dir"])


def toctree_entries(srcdir: Path, docnames: set[str]) -> set[str]:
    """The documents the toctrees of the Markdown sources list.

    Reads the fenced ``{toctree}`` blocks of every source (entries relative
    to their page, ``Title <entry>`` links, ``:glob:`` patterns).
    """
    listed: set[str] = set()
    for doc in docnames:
        path = srcdir / f"{doc}.md"
        if not path.exists():
            continue
        base = posixpath.dirname(doc)
        for block in TOCTREE.finditer(path.read_text(encoding="utf-8")):
            body = block.group(2)
            glob = re.search(r"^:glob:", body, re.M) is not None
            for line in body.splitlines():
                entry = line.strip()
                if not entry or entry.startswith(":"):
                    continue
                m = re.fullmatch(r".*<(.+)>", entry)
                entry = (m.group(1) if m else entry).removesuffix(".md")
                if entry.startswith("/"):
                    target = entry.lstrip("/")
                else:
                    target = posixpath.normpath(posixpath.join(base, entry))
                if glob:
                    listed.update(fnmatch.filter(docnames, target))
                else:
                    listed.add(target)
    return listed


def list_unlisted_pages(app: Sphinx, docname: str, source: list[str]) -> None:
    """Append a hidden "More" toctree of unlisted pages to the root page."""
    if docname != app.config.root_doc:
        return
    docnames = set(app.env.found_docs)
    unlisted = sorted(
        docnames - toctree_entries(Path(app.srcdir), docnames) - {docname}
    )
    if not unlisted:
        return
    logger.info("pages in no toctree, listed under 'More': %s", ", ".join(unlisted))
    entries = "\n".join(unlisted)
    source[0] += f"\n\n```{{toctree}}\n:hidden:\n:caption: More\n\n{entries}\n```\n"


def reread_root_on_new_pages(
    app: Sphinx, env, added: set[str], changed: set[str], removed: set[str]
) -> list[str]:
    """Rebuild the root page's navigation when pages come or go."""
    return [app.config.root_doc] if added or removed else []


class PendingSection(SphinxDirective):
    """A pointer to a section that another piece of work adds to a page.

    ``pattern`` is a regular expression matched against the headings of the
    page named by ``:page:`` (default: the current one).  If a heading
    matches, the directive renders the body (the pointer) with ``{heading}``
    replaced by the heading's text and ``{slug}`` by its anchor; otherwise a
    clearly marked "pending" note with the ``:pending:`` text.  So the page
    updates itself when the section lands.
    """

    required_arguments = 1
    final_argument_whitespace = True
    option_spec: ClassVar[dict] = {"page": str, "pending": str}
    has_content = True

    def run(self) -> list[nodes.Node]:
        """Render the pointer, or the pending note."""
        pattern = re.compile(self.arguments[0], re.IGNORECASE)
        page = self.options.get("page")
        if page:
            path = Path(self.env.srcdir) / page
        else:
            path = Path(self.env.doc2path(self.env.docname))
        self.env.note_dependency(str(path))
        heading = None
        for line in path.read_text(encoding="utf-8").splitlines():
            m = re.match(r"^#{2,4}\s+(.*\S)\s*$", line)
            if m and pattern.search(m.group(1)):
                heading = m.group(1)
                break
        if heading is not None:
            from myst_parser.mdit_to_docutils.base import default_slugify

            text = "\n".join(self.content).replace("{heading}", heading)
            text = text.replace("{slug}", default_slugify(heading))
            return self.parse_text_to_nodes(text)
        if "pending" not in self.options:
            return []
        note = nodes.admonition(classes=["pending-section"])
        note += nodes.title(text="Pending")
        note += self.parse_text_to_nodes(self.options.get("pending", ""))
        return [note]


def setup(app: Sphinx) -> dict:
    """Register the extension."""
    app.connect("builder-inited", generate)
    app.connect("source-read", list_unlisted_pages)
    app.connect("env-get-outdated", reread_root_on_new_pages)
    app.add_directive("pending-section", PendingSection)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
