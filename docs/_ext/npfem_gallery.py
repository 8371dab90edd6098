"""The gallery: one generated page per script of ``demos/`` and ``benchmarks/``.

Three kinds of scripts:

* **Examples** (``demos/*.py`` with ``# %%`` cells): short literate scripts
  that run in seconds.  The build runs each one (:func:`run_examples`, two at a
  time, in a fresh interpreter, cell by cell) and its page shows the
  docstring, every cell's prose (the comment lines that open the cell,
  Markdown), code, printed output and the figures the cell saved.  A script
  that fails fails the build.  Results are cached under
  ``docs/gallery/_run/`` and reused while neither the script nor the package
  sources change.
* **Studies** (``demos/studies/*.py``, and top-level demos without cells):
  studies of minutes to hours, never run by the build.  They commit what they
  produce (figures and JSON under ``docs/``, generated pages such as
  ``choosing.md``); the page shows their docstring, every figure of ``docs/``
  whose file name the script mentions, links to the JSON results and pages it
  mentions, the pages that quote it and its source.
* **Benchmarks** (``benchmarks/*.py``): like the studies, plus one page per
  Markdown report of ``benchmarks/results``.

A docstring is reStructuredText (shown verbatim if it does not parse cleanly,
so a new script can never break the build).  A script added to ``demos/``
appears on the next build.

Run an example the way the build does (``OUT.json`` gets the cells' output
and figure names)::

    python docs/_ext/npfem_gallery.py run demos/one_step_by_hand.py OUT.json
"""

from __future__ import annotations

import ast
import contextlib
import hashlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import traceback
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from docutils.core import publish_doctree
from docutils.utils import SystemMessage

#: Scripts that are listed, not run: (folder, its pages' prefix, section title).
STUDY_SECTIONS = (
    ("demos/studies", "studies", "Studies and validation"),
    ("benchmarks", "benchmarks", "Benchmarks: time and memory"),
)
#: Folders of the docs tree that are not searched for figures and pages.
SKIP_DIRS = {"_build", "api", "gallery", "jupyter_execute", "_ext", "tutorials"}
FILE_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_./<>-]*\.(?:png|gif|json|md)\b")
#: A cell starts at a line ``# %%`` (optionally ``# %% [markdown]`` or a title).
CELL_RE = re.compile(r"^# %%(.*)$")
#: Where an example's figures and results go (the examples read it).
OUT_ENV = "NPFEM_GALLERY_OUT"
#: Seconds an example may take at build time before the build fails.
TIMEOUT = 300
#: Examples run at once.
WORKERS = 2


# ------------------------------------------------------------- examples ----
def is_example(path: Path) -> bool:
    """True for a literate example: a script with ``# %%`` cells."""
    return any(
        CELL_RE.match(ln) for ln in path.read_text(encoding="utf-8").splitlines()
    )


def split_cells(text: str) -> list[dict]:
    """The cells of a literate script, after its module docstring.

    Each cell is ``{"line": first line (1-based), "prose": Markdown, "code":
    Python}``: the comment lines that open a cell are its prose (``# `` removed),
    the rest its code.  A ``# %% [markdown]`` cell is all prose.  Code before
    the first ``# %%`` (after the docstring) is a cell of its own.
    """
    lines = text.splitlines()
    tree = ast.parse(text)
    first = 0
    if tree.body and isinstance(tree.body[0], ast.Expr):
        value = tree.body[0].value
        if isinstance(value, ast.Constant) and isinstance(value.value, str):
            first = tree.body[0].end_lineno
    starts, headers = [first], [""]
    for i in range(first, len(lines)):
        m = CELL_RE.match(lines[i])
        if m:
            starts.append(i)
            headers.append(m.group(1).strip())
    cells = []
    for k, start in enumerate(starts):
        stop = starts[k + 1] if k + 1 < len(starts) else len(lines)
        body = lines[start + (k > 0) : stop]
        n = 0
        markdown = headers[k].lower() == "[markdown]"
        while n < len(body) and (
            markdown or (body[n].startswith("#") and not CELL_RE.match(body[n]))
        ):
            n += 1
        prose = "\n".join(
            ln[2:] if ln.startswith("# ") else ln.lstrip("#") for ln in body[:n]
        )
        code = "\n".join(body[n:]).strip("\n")
        if headers[k] and not markdown:
            prose = f"### {headers[k]}\n\n{prose}"
        if prose.strip() or code.strip():
            cells.append(
                {"line": start + (k > 0) + n + 1, "prose": prose.strip(), "code": code}
            )
    return cells


def _pngs(folder: Path) -> dict[Path, float]:
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*.png")}


def run_cells(script: Path, result: Path) -> None:
    """Run ``script`` cell by cell; write each cell's output and new figures.

    Runs in the current interpreter with ``__name__ == "__main__"``; figures are
    the PNG files that appear or change under ``$NPFEM_GALLERY_OUT`` while a cell
    runs.  ``result`` gets ``{"seconds": ..., "cells": [{"stdout": ...,
    "figures": [paths relative to the output folder]}]}``.
    """
    out = Path(os.environ.get(OUT_ENV, "out/gallery")).resolve()
    out.mkdir(parents=True, exist_ok=True)
    text = script.read_text(encoding="utf-8")
    namespace = {"__name__": "__main__", "__file__": str(script)}
    cells, start = [], time.perf_counter()
    for cell in split_cells(text):
        before = _pngs(out)
        stdout = io.StringIO()
        code = "\n" * (cell["line"] - 1) + cell["code"]
        with contextlib.redirect_stdout(stdout):
            exec(compile(code, str(script), "exec"), namespace)
        after = _pngs(out)
        new = sorted(p for p, t in after.items() if before.get(p) != t)
        cells.append(
            {
                "stdout": stdout.getvalue(),
                "figures": [p.relative_to(out).as_posix() for p in new],
            }
        )
        print(stdout.getvalue(), end="")
    seconds = time.perf_counter() - start
    result.write_text(json.dumps({"seconds": seconds, "cells": cells}, indent=1))


def _sources_digest(root: Path) -> str:
    """Digest of the package sources: a cached example reruns when they change."""
    h = hashlib.sha256()
    for path in sorted((root / "skfem_npfem").rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def _run_one(script: Path, cache: Path, key: str) -> str | None:
    """Run one example into ``cache``; return an error text, or None."""
    with tempfile.TemporaryDirectory(prefix="npfem-gallery-") as tmp:
        env = dict(os.environ, MPLBACKEND="Agg", PYVISTA_OFF_SCREEN="true")
        env[OUT_ENV] = str(Path(tmp) / "out")
        result = Path(tmp) / "result.json"
        cmd = [sys.executable, __file__, "run", str(script), str(result)]
        try:
            proc = subprocess.run(
                cmd, cwd=tmp, env=env, capture_output=True, text=True, timeout=TIMEOUT
            )
        except subprocess.TimeoutExpired:
            return f"took longer than {TIMEOUT} s"
        if proc.returncode != 0:
            return proc.stderr[-3000:]
        data = json.loads(result.read_text())
        if cache.exists():
            shutil.rmtree(cache)
        cache.mkdir(parents=True)
        for cell in data["cells"]:
            names = []
            for rel in cell["figures"]:
                name = rel.removeprefix(f"{script.stem}/").replace("/", "-")
                shutil.copyfile(Path(env[OUT_ENV]) / rel, cache / name)
                names.append(name)
            cell["figures"] = names
        data["key"] = key
        (cache / "result.json").write_text(json.dumps(data, indent=1))
    return None


def run_examples(
    root: Path, src: Path, scripts: list[Path], warn: Callable[[str], None]
) -> dict[str, dict]:
    """Run the examples whose cached result is missing or stale.

    Returns ``{stem: result}`` with figure names relative to
    ``src/gallery/_run/STEM``; a failed example is reported through ``warn``
    (a warning fails the ``-W`` build) and left out.
    """
    digest = _sources_digest(root)
    results: dict[str, dict] = {}
    todo = []
    for script in scripts:
        key = hashlib.sha256((digest + script.read_text(encoding="utf-8")).encode())
        cache = src / "gallery" / "_run" / script.stem
        cached = cache / "result.json"
        if cached.exists():
            data = json.loads(cached.read_text())
            if data.get("key") == key.hexdigest():
                results[script.stem] = data
                continue
        todo.append((script, cache, key.hexdigest()))
    with ThreadPoolExecutor(max_workers=WORKERS) as pool:
        errors = list(pool.map(lambda job: _run_one(*job), todo))
    for (script, cache, _), error in zip(todo, errors, strict=True):
        if error is None:
            results[script.stem] = json.loads((cache / "result.json").read_text())
        else:
            warn(f"gallery: demos/{script.name} failed when run for the docs:\n{error}")
    return results


def _example_page(root: Path, path: Path, result: dict | None):
    text = path.read_text(encoding="utf-8")
    doc = ast.get_docstring(ast.parse(text)) or path.stem
    title, body = _title(doc)
    script = path.relative_to(root).as_posix()
    lines = [
        f"# {title}",
        "",
        f"<!-- Generated by docs/_ext/npfem_gallery.py from {script}; do not edit. -->",
        "",
    ]
    if body:
        lines += _docstring(body)
    cells = split_cells(text)
    figures = []
    outputs = result["cells"] if result else [None] * len(cells)
    for cell, output in zip(cells, outputs, strict=False):
        if cell["prose"]:
            lines += [cell["prose"], ""]
        if cell["code"].strip():
            lines += ["```python", cell["code"], "```", ""]
        if output and output["stdout"].strip():
            lines += ["```text", output["stdout"].rstrip("\n"), "```", ""]
        for name in output["figures"] if output else []:
            rel = f"_run/{path.stem}/{name}"
            figures.append(rel)
            lines += [f"```{{image}} {rel}", f":alt: {name}", "```", ""]
    ran = (
        f"The docs build ran it (in {result['seconds']:.0f} s); the output and "
        "figures above are the script's own."
        if result
        else "It did not run in this build."
    )
    lines += [
        "## Run it",
        "",
        f"From the repository root: `python {script}` (figures go to "
        f"`out/gallery/{path.stem}/`, or under `${OUT_ENV}`). {ran} "
        f"{{download}}`Download {path.name} <../../{script}>`.",
        "",
    ]
    return title, figures, "\n".join(lines)


# -------------------------------------------------------------- studies ----
def _rst_is_clean(text: str) -> bool:
    """True if ``text`` parses as reStructuredText without a warning."""
    stream = io.StringIO()
    try:
        publish_doctree(
            text,
            settings_overrides={
                "report_level": 2,
                "halt_level": 2,
                "warning_stream": stream,
                "file_insertion_enabled": False,
                "raw_enabled": False,
            },
        )
    except (SystemMessage, Exception):
        return False
    return not stream.getvalue()


def _docs_files(src: Path) -> dict[str, list[Path]]:
    """Files of the docs tree by base name (figures, JSON, pages)."""
    found: dict[str, list[Path]] = {}
    for path in sorted(src.rglob("*")):
        rel = path.relative_to(src)
        if rel.parts[0] in SKIP_DIRS or path.is_dir():
            continue
        if path.suffix in {".png", ".gif", ".json", ".md"}:
            found.setdefault(path.name, []).append(rel)
    return found


def _quoting_pages(src: Path, script: str) -> list[Path]:
    """Pages of the docs tree whose text names ``script`` (``demos/x.py``)."""
    pages = []
    for path in sorted(src.rglob("*.md")):
        rel = path.relative_to(src)
        if rel.parts[0] in SKIP_DIRS:
            continue
        if script in path.read_text(encoding="utf-8"):
            pages.append(rel)
    return pages


def _title(doc: str) -> tuple[str, str]:
    first, _, rest = doc.strip().partition("\n")
    return first.strip().rstrip("."), rest.strip()


def _docstring(body: str) -> list[str]:
    if _rst_is_clean(body):
        return ["```{eval-rst}", body, "```", ""]
    return ["```text", body, "```", ""]


def _study_page(root: Path, src: Path, path: Path, files: dict[str, list[Path]]):
    text = path.read_text(encoding="utf-8")
    doc = ast.get_docstring(ast.parse(text)) or path.stem
    title, body = _title(doc)
    script = path.relative_to(root).as_posix()
    names = {Path(n).name for n in set(FILE_RE.findall(text))}
    figures, data, pages = [], [], []
    for name in sorted(names):
        for rel in files.get(name, []):
            if rel.suffix in {".png", ".gif"}:
                figures.append(rel)
            elif rel.suffix == ".json":
                data.append(rel)
            else:
                pages.append(rel)
    quoting = [p for p in _quoting_pages(src, script) if p not in pages]
    lines = [
        f"# {title}",
        "",
        f"<!-- Generated by docs/_ext/npfem_gallery.py from {script}; do not edit. -->",
        "",
        f"`{script}` · rerun from the repository root: `python {script}` "
        "(see the usage below; nothing of it runs when the docs are built, the "
        "results shown are the ones the script committed).",
        "",
    ]
    if body:
        lines += _docstring(body)
    if figures:
        lines += ["## Figures", ""]
        for rel in figures:
            lines += [
                f"```{{figure}} ../{rel.as_posix()}",
                f":alt: {rel.name}",
                "",
                f"`docs/{rel.as_posix()}`",
                "```",
                "",
            ]
    if pages or quoting:
        lines += ["## Where the results are discussed", ""]
        for rel in pages:
            lines.append(
                f"* [{rel.as_posix()}](../{rel.as_posix()}) (written by the script)"
            )
        for rel in quoting:
            lines.append(f"* [{rel.as_posix()}](../{rel.as_posix()})")
        lines.append("")
    if data:
        lines += ["## Results (JSON)", ""]
        for rel in data:
            lines.append(f"* {{download}}`docs/{rel.as_posix()} <../{rel.as_posix()}>`")
        lines.append("")
    lines += [
        "## Source",
        "",
        f"```{{literalinclude}} ../../{script}",
        ":language: python",
        "```",
        "",
    ]
    return title, [f"../{f.as_posix()}" for f in figures], "\n".join(lines)


def _result_pages(root: Path) -> dict[str, str]:
    """One page per Markdown report of ``benchmarks/results`` (included as is)."""
    out = {}
    for path in sorted((root / "benchmarks" / "results").glob("*.md")):
        out[f"results-{path.stem}.md"] = "\n".join(
            [
                f"# Benchmark report `{path.name}`",
                "",
                f"<!-- Generated by docs/_ext/npfem_gallery.py from "
                f"benchmarks/results/{path.name}; do not edit. -->",
                "",
                f"Written by the benchmark scripts next to `{path.stem}.json` "
                "(rerun a script, or its `--render` option, to regenerate it).",
                "",
                f"```{{include}} ../../benchmarks/results/{path.name}",
                ":heading-offset: 1",
                "```",
                "",
            ]
        )
    return out


def _scripts(folder: Path) -> list[Path]:
    return sorted(p for p in folder.glob("*.py") if not p.name.startswith("_"))


def _entry(title: str, name: str, script: str, figures: list[str]) -> list[str]:
    lines = [f"* [{title}]({name}.md) (`{script}`)"]
    if figures:
        lines += [
            "",
            f"  ```{{image}} {figures[0]}",
            "  :width: 320px",
            f"  :target: {name}.html",
            "  ```",
            "",
        ]
    return lines


def pages(src: Path, warn: Callable[[str], None] = print) -> dict[str, str]:
    """``{relative path: MyST text}`` of the gallery (runs the examples)."""
    root = src.parent
    files = _docs_files(src)
    results = _result_pages(root)
    for name in results:
        # Reports are found by their file name, like the docs' own results.
        files.setdefault(name.removeprefix("results-"), []).append(
            Path("gallery") / name
        )
    out: dict[str, str] = {}
    index = [
        "# Gallery",
        "",
        "<!-- Generated by docs/_ext/npfem_gallery.py; do not edit. -->",
        "",
        "**Examples** are short scripts of `demos/`, one thing each, that run in "
        "seconds: the docs build runs them and shows their output and figures "
        "(`tests/docs/test_gallery.py` checks the number each one verifies). "
        "**Studies** (`demos/studies/`) and **benchmarks** take minutes to hours; "
        "they are listed with the figures and results they committed, and the "
        "build runs none of them.",
        "",
    ]
    toc = []
    demos = _scripts(root / "demos")
    examples = [p for p in demos if is_example(p)]
    ran = run_examples(root, src, examples, warn)
    if examples:
        index += ["## Examples", ""]
        for path in examples:
            name = f"demos-{path.stem}"
            title, figures, text = _example_page(root, path, ran.get(path.stem))
            out[f"{name}.md"] = text
            toc.append(name)
            # The thumbnail is the example's last figure (usually its result).
            index += _entry(title, name, f"demos/{path.name}", figures[::-1])
        index.append("")
    # Top-level demos without cells are studies not yet in demos/studies/.
    sections = [
        (
            [p for p in demos if p not in examples] + _scripts(root / folder),
            prefix,
            heading,
        )
        if folder == "demos/studies"
        else (_scripts(root / folder), prefix, heading)
        for folder, prefix, heading in STUDY_SECTIONS
    ]
    for scripts, prefix, heading in sections:
        if not scripts:
            continue
        index += [f"## {heading}", ""]
        for path in scripts:
            folder = path.parent.relative_to(root).as_posix()
            name = f"{'demos' if folder == 'demos' else prefix}-{path.stem}"
            title, figures, text = _study_page(root, src, path, files)
            out[f"{name}.md"] = text
            toc.append(name)
            index += _entry(title, name, f"{folder}/{path.name}", figures)
        index.append("")
    if results:
        index += ["## Benchmark reports", ""]
        for name in results:
            index.append(
                f"* [`benchmarks/results/{name.removeprefix('results-')}`]({name})"
            )
            toc.append(name.removesuffix(".md"))
        index.append("")
        out.update(results)
    index += ["```{toctree}", ":hidden:", "", *toc, "```", ""]
    out["index.md"] = "\n".join(index)
    return out


if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] != "run":
        sys.exit("usage: python npfem_gallery.py run SCRIPT.py RESULT.json")
    try:
        run_cells(Path(sys.argv[2]).resolve(), Path(sys.argv[3]).resolve())
    except Exception:
        traceback.print_exc()
        sys.exit(1)
