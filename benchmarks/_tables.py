"""The tables the documentation shows, written from committed JSON as fragments.

A study or benchmark that commits JSON results also renders the tables the
pages show from them: each table is a function of the script registered with
:func:`registry`, and ``python SCRIPT --tables`` rewrites its fragments (a
Markdown table and a note naming the JSON it was read from) without rerunning
anything.  A fragment lies next to the first JSON it reads, as
``<table-name>.inc``, and a page includes it with MyST's ``{include}``;
``tests/docs/test_docs.py`` checks that every committed fragment is what its
function renders from the committed JSON today.

Studies import this module through ``_common.benchmark("_tables")``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NNBSP = "\u202f"  # thousands separator, as in 1 035
MINUS = "\u2212"
#: The benchmarks' committed reports, from the repository root.
RESULTS = "benchmarks/results"

#: The help of the scripts' ``--tables`` option.
HELP = "only rewrite the docs tables (.inc fragments) from the committed JSON"

#: fragment path (from the repository root) -> (builder, JSON files it reads)
Tables = dict[str, tuple[Callable[[], str], tuple[str, ...]]]


def registry(tables: Tables) -> Callable:
    """A decorator ``@table(*sources)`` that registers builders in ``tables``.

    The fragment of ``def collapse_sweep()`` reading ``docs/validation/x.json``
    is ``docs/validation/collapse-sweep.inc``.
    """

    def table(*sources: str) -> Callable:
        def register(fn: Callable[[], str]) -> Callable[[], str]:
            name = fn.__name__.replace("_", "-")
            tables[f"{Path(sources[0]).parent.as_posix()}/{name}.inc"] = (fn, sources)
            return fn

        return register

    return table


def stored(rel: str, name: str) -> Tables:
    """The tables of a study that stores its Markdown table in its JSON (``table``).

    ``name`` names the fragment, ``<folder of rel>/<name>.inc``.
    """

    def builder() -> str:
        return load(rel)["table"]

    builder.__name__ = name
    tables: Tables = {}
    registry(tables)(rel)(builder)
    return tables


def load(rel: str):
    """A committed JSON file, by its path from the repository root."""
    return json.loads((ROOT / rel).read_text(encoding="utf-8"))


# ---------------------------------------------------------------------------
# Number formats (the conventions of the hand-written pages).


def _missing(x) -> bool:
    return x is None or (isinstance(x, float) and not math.isfinite(x))


def num(x, digits: int = 3) -> str:
    """Fixed decimals, a real minus sign, "—" for a missing value."""
    return "—" if _missing(x) else f"{x:.{digits}f}".replace("-", MINUS)


def sig(x, digits: int = 3) -> str:
    """Significant digits (``%g``)."""
    return "—" if _missing(x) else f"{x:.{digits}g}".replace("-", MINUS)


def pct(x, digits: int = 1, sign: bool = True) -> str:
    """A fraction as a signed percentage: ``-0.035`` -> ``−3.5 %``."""
    if _missing(x):
        return "—"
    s = f"{100 * x:+.{digits}f} %" if sign else f"{100 * x:.{digits}f} %"
    return s.replace("-", MINUS)


def count(n) -> str:
    """An integer with a narrow space every three digits."""
    return f"{int(n):,}".replace(",", NNBSP)


def sci(x, digits: int = 2) -> str:
    """Scientific notation, ``3.26e-02``."""
    return "—" if x is None else f"{x:.{digits}e}"


def md(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table."""
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def statuses(counts: dict) -> str:
    """``{"Solved": 171, "AlmostSolved": 1}`` -> ``171 Solved, 1 AlmostSolved``."""
    order = sorted(counts.items(), key=lambda kv: (kv[0] != "Solved", kv[0]))
    return ", ".join(f"{n} {s}" for s, n in order)


# ---------------------------------------------------------------------------
# Fragments.


def _machine(meta: dict) -> str:
    """``Intel(R) Xeon(R) Processor, 2 cores, 23.5 GB, clarabel 0.11.1, MKL ...``."""
    parts = [str(meta.get("cpu") or "unknown CPU")]
    if meta.get("cores"):
        parts.append(f"{meta['cores']} cores")
    if meta.get("memory_gb"):
        parts.append(f"{meta['memory_gb']:g} GB")
    if meta.get("clarabel"):
        parts.append(f"clarabel {meta['clarabel']}")
    if meta.get("mkl"):
        parts.append(f"MKL {meta['mkl']}")
    return ", ".join(parts)


def measured_on(sources: tuple[str, ...]) -> str:
    """`` Measured on DATE (MACHINE).`` from the sources' ``machine`` records.

    Benchmark reports record the date and the machine of their measurement;
    the table's note carries them, so the prose around it does not.  Sources
    without such a record add nothing.
    """
    dates: dict[str, list[str]] = {}
    for src in sources:
        try:
            data = load(src)
        except (OSError, ValueError):
            continue
        meta = data.get("machine") if isinstance(data, dict) else None
        if isinstance(meta, dict) and meta.get("date"):
            dates.setdefault(_machine(meta), []).append(str(meta["date"])[:10])
    out = []
    for machine, when in dates.items():
        lo, hi = min(when), max(when)
        span = lo if lo == hi else f"{lo} to {hi}"
        out.append(f"{span} ({machine})")
    return f" Measured on {'; '.join(out)}." if out else ""


def render(builder: Callable[[], str], sources: tuple[str, ...]) -> str:
    """A fragment: the table and a note naming its JSON (and measurement)."""
    note = ", ".join(f"`{src}`" for src in sources)
    return f"{builder()}\n\n<small>Table from {note}.{measured_on(sources)}</small>\n"


def write(tables: Tables) -> int:
    """Rewrite the fragments of ``tables`` from the committed JSON; print them."""
    for rel, (builder, sources) in tables.items():
        (ROOT / rel).write_text(render(builder, sources), encoding="utf-8")
        print(f"wrote {rel}")
    return 0
