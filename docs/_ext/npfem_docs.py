"""Local Sphinx extension of the skfem-npfem documentation.

At ``builder-inited`` it writes the generated pages (never committed):

* ``api/``: one page per group of ``skfem_npfem.__all__`` (the ``#:`` comments
  of ``skfem_npfem/__init__.py``), so a name added to ``__all__`` appears in
  the reference without editing the docs (:mod:`npfem_api`);
* ``gallery/``: one page per script of ``demos/`` with its docstring, the
  figures it committed under ``docs/``, the pages that quote it and its source
  (:mod:`npfem_gallery`).

It also registers the directives that build tables from the JSON the demos
and benchmarks commit (:mod:`npfem_tables`) and the ``pending-section``
directive of the theory page.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

import npfem_api
import npfem_gallery
import npfem_tables
from docutils import nodes
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective


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
    for rel, text in npfem_gallery.pages(src).items():
        write_if_changed(src / "gallery" / rel, text)


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
        import re

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
    app.add_directive("pending-section", PendingSection)
    npfem_tables.setup(app)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
