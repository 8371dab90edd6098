"""The repository speaks for itself: no references to things outside it.

Every tracked text file (``git ls-files``: ``.py .md .inc .toml .txt .cfg .json
.yml .yaml``; binary files skipped) is scanned line by line for

* design notes that are not in the repository (the formulation, benchmark
  catalogue, architecture, ecosystem and style notes, each a ``<name>.md``; a
  name is fine when a tracked file of that name exists), their numbered
  pitfalls, and paths outside the checkout (a ``shared`` folder beside it, the
  machine's work folders);
* issue and defect numbers in their usual forms (the word, an optional ``#``
  and a number; a ``#`` number in parentheses), the numbering of a tracker the
  reader cannot see;
* tests named after a defect list (``test_<digits>_...``) instead of what they
  check.

What such a reference stood for belongs in the project's own words: a formula,
pitfall or benchmark definition goes into ``docs/theory.md``,
``docs/verification.md`` or ``docs/validation.md`` and the code cites that page
and section (e.g. ``docs/theory.md, "Time integration: why θ2 = 1"``).  Links
to a third-party project's issue tracker (``github.com/<owner>/<repo>/issues/N``)
and published references such as "Lube et al. (2005)" are fine.  The failure
names every offending ``file:line`` with what was found and how to fix it.  A
plain text scan: fast, no build needed.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: The text files scanned, by suffix.
SUFFIXES = {".py", ".md", ".inc", ".toml", ".txt", ".cfg", ".json", ".yml", ".yaml"}
#: Folders never scanned when the file list cannot come from git.
UNTRACKED = {".git", ".venv", "venv", "_build", "build", "dist", "node_modules"}

#: Design notes that were never part of the repository.
DESIGN_NOTES = ("formulation", "benchmarks", "architecture", "ecosystem-notes", "style")

#: (pattern, what it is, how to fix it).  Case-insensitive.
RULES: list[tuple[re.Pattern[str], str, str]] = [
    (
        re.compile(r"(?<![\w/.-])(" + "|".join(DESIGN_NOTES) + r")\.md\b", re.I),
        "a design note outside the repository",
        "state its content in docs/ and cite the docs page and section",
    ),
    (
        re.compile(r"\bpitfalls? ?#?\d+", re.I),
        "a numbered pitfall of a design note",
        "cite docs/theory.md, 'Pitfalls the implementation avoids'",
    ),
    (
        re.compile(
            r"\.\./shared\b|\bshared[\"']?\s*/\s*[\"']?tools\b|/work/(shared|main|wt)\b",
            re.I,
        ),
        "a path outside the repository",
        "use the package (e.g. skfem_npfem.stress_roughness) or a path in the repo",
    ),
    (
        re.compile(r"(?<![/\w])issues? ?#?\d+", re.I),
        "an issue number",
        "say what the change or check is, not which ticket asked for it",
    ),
    (
        re.compile(r"(?<![&\w])\(#\d{1,5}\)|(?<![/\w])(pr|pull request) ?#\d+", re.I),
        "an issue or pull-request number",
        "say what the change or check is, not which ticket asked for it",
    ),
    (
        re.compile(r"\bdefects? ?#?\d+", re.I),
        "a defect number",
        "say what the defect was",
    ),
    (
        re.compile(r"\btest_\d+_\w*"),
        "a test named after a defect list",
        "name the test after what it checks",
    ),
]


def tracked_files(root: Path = ROOT) -> list[Path]:
    """The repository's text files of the scanned kinds (tracked by git if possible)."""
    try:
        out = subprocess.run(
            ["git", "ls-files", "-z"],
            cwd=root,
            capture_output=True,
            check=True,
            timeout=60,
        ).stdout.decode("utf-8", "surrogateescape")
        names = [n for n in out.split("\0") if n]
    except (OSError, subprocess.SubprocessError):
        names = [
            str(p.relative_to(root))
            for p in root.rglob("*")
            if p.is_file() and not UNTRACKED & set(p.relative_to(root).parts)
        ]
    return sorted(
        root / n
        for n in names
        if Path(n).suffix.lower() in SUFFIXES and (root / n).is_file()
    )


def read_text(path: Path) -> str | None:
    """The file's text, or None for a binary or non-UTF-8 file."""
    data = path.read_bytes()
    if b"\0" in data[:8192]:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def findings(text: str, own_names: frozenset[str] = frozenset()) -> list[str]:
    """``line: what: excerpt (fix)`` for every outside reference in ``text``.

    ``own_names`` are file names the repository does have: a design-note name
    that is one of them is a reference inside the repository.
    """
    found = []
    for n, line in enumerate(text.splitlines(), 1):
        for pattern, what, fix in RULES:
            for m in pattern.finditer(line):
                if m.group(0).lower() in own_names:
                    continue
                excerpt = line.strip()
                if len(excerpt) > 120:
                    start = max(0, line.find(m.group(0)) - 50)
                    excerpt = "..." + line[start : start + 110].strip() + "..."
                found.append(f"{n}: {what} {m.group(0)!r}: {excerpt}  [fix: {fix}]")
    return found


def test_the_scan_flags_outside_references():
    # Built so that this file does not flag itself.
    num = 12
    cases = [
        f"Sign conventions ({'formulation'}.md §4.3) of the wall rows.",
        f"# {'benchmarks'}.md T5: one step from rest.",
        f"see the {'architecture'}.md note",
        f"see {'formulation'}.md pitfall {8}",
        f"Path('/work/{'shared'}/tools/stress_roughness.py')",
        f"ROOT.parent / '../{'shared'}' / 'tools'",
        f"path = parent / {'shared'!r} / 'tools' / 'stress_roughness.py'",
        f"The sweep (issue {num}): column-collapse at 0.02 m.",
        f"Issue #{num} asks for 30x.",
        f"fixed in (#{num})",
        f"the library before issue {num} phase 2",
        f"Reliability defect {3}: the zero-area element.",
        f"def test_{num}_volume_is_conserved():",
    ]
    for line in cases:
        assert findings(line), line


def test_the_scan_spares_the_project_own_words():
    fine = [
        "Lube et al. (2005) and Lajeunesse et al. (2005) measured 1.2a.",
        "See docs/theory.md, 'Time integration: why theta2 = 1'.",
        "benchmarks/README.md and benchmarks/results/suite.md",
        "docs/performance.md, 'Reference timings'",
        "def test_2d_round_trip(tmp_path):",
        "def test_3d_default_is_vertical_stress(tmp_path):",
        "color='#303030', edgecolor='#404040'",
        "See [conventions](../index.md#conventions), #3d-with-the-volume-correction.",
        "upstream: https://github.com/oxfordcontrol/Clarabel.rs/issues/123",
        "--out /shared/collapse-sweep on a shared file system",
        "Also issued as a UserWarning.",
        "The pitfalls the implementation avoids.",
        "a scene catalogue; the shared helpers of demos/studies/_common.py",
    ]
    for line in fine:
        assert findings(line) == [], line
    # A design-note name is fine when the repository has such a file.
    note = f"see {'style'}.md"
    assert findings(note, frozenset({note[4:]})) == []
    assert findings(note) != []


FILES = tracked_files()


def test_the_scan_sees_the_repository():
    rel = {p.relative_to(ROOT).as_posix() for p in FILES}
    assert {"README.md", "pyproject.toml", "tests/conftest.py"} <= rel


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_file_refers_to_nothing_outside_the_repository(path):
    text = read_text(path)
    if text is None:
        return  # binary or not UTF-8: not prose
    own = frozenset(p.name.lower() for p in FILES)
    found = findings(text, own)
    rel = path.relative_to(ROOT).as_posix()
    assert not found, (
        f"{len(found)} reference(s) to things outside the repository:\n"
        + "\n".join(f"{rel}:{f}" for f in found)
    )
