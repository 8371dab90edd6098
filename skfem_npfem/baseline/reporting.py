"""Files of the comparison demos: JSON results, PNG figures, Markdown tables.

Every file goes through :mod:`skfem_npfem.io`'s atomic writer and JSON policy
(NaN and inf as ``null``), so a demo interrupted mid-write never leaves a
half-written result in ``docs/validation/comparison``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..io import atomic_path, write_json

__all__ = ["markdown_table", "save_png", "write_result"]


def write_result(path: str | Path, result: dict) -> Path:
    """Write a demo's result dict as JSON (folders created); return the path."""
    return write_json(path, result)


def save_png(fig: Any, path: str | Path, dpi: int = 120) -> Path:
    """Save a matplotlib figure as PNG atomically and close it."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    plt.close(fig)
    return path


def markdown_table(headers: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    """A Markdown table; floats in 4 significant digits, None as a dash.

    Examples
    --------
    >>> print(markdown_table(["a", "b"], [[1, 0.123456], ["x", None]]))
    | a | b |
    |---|---|
    | 1 | 0.1235 |
    | x | – |
    """

    def cell(v: Any) -> str:
        if v is None:
            return "–"
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)
