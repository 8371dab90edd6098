"""Files of the studies: JSON results, PNG figures, Markdown tables, Pareto fronts.

Every file goes through :mod:`skfem_npfem.io`'s atomic writer and JSON policy
(NaN and inf as ``null``), so a study interrupted mid-write never leaves a
half-written result in ``docs/validation``.  The studies import it as
``import _reporting`` (see :mod:`_common`); ``benchmarks/`` puts this folder on
``sys.path`` for its figures.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from skfem_npfem.io import atomic_path, write_json

__all__ = [
    "best_within",
    "cheapest_within",
    "markdown_table",
    "palette_png",
    "pareto_front",
    "save_png",
    "write_result",
]


def write_result(path: str | Path, result: dict) -> Path:
    """Write a study's result dict as JSON (folders created); return the path."""
    return write_json(path, result)


def save_png(fig: Any, path: str | Path, dpi: int = 120, palette: bool = True) -> Path:
    """Save a matplotlib figure as PNG atomically and close it.

    Parameters
    ----------
    fig
        The matplotlib figure (closed afterwards).
    path
        The PNG file (folders created).
    dpi
        Resolution.
    palette
        Store the picture with a palette of 256 colours (no dithering): plots
        and rendered fields look the same and take about a third of the bytes
        of a true-colour PNG, which matters for the figures committed with the
        docs.  False: the true-colour PNG matplotlib writes.

    Returns
    -------
    Path
        ``path``.
    """
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    fig.savefig(buf, dpi=dpi, format="png")
    plt.close(fig)
    data = palette_png(buf.getvalue()) if palette else buf.getvalue()
    with atomic_path(path) as tmp:
        Path(tmp).write_bytes(data)
    return path


def palette_png(data: bytes) -> bytes:
    """An opaque PNG ``data`` re-encoded with a palette of 256 colours.

    Median-cut quantisation without dithering (flat areas stay flat), then the
    encoder's optimisation; transparency is dropped.
    """
    from PIL import Image

    image = Image.open(io.BytesIO(data)).convert("RGB")
    quantised = image.quantize(
        colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
    )
    out = io.BytesIO()
    quantised.save(out, format="PNG", optimize=True)
    return out.getvalue()


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


def pareto_front(points: Sequence[tuple[float, float]]) -> list[int]:
    """Indices of the points not beaten in both cost and error, cheapest first.

    A point ``(cost, error)`` is on the front when no other point is at most
    as costly *and* at most as wrong (one of the two strictly).

    Examples
    --------
    >>> pareto_front([(1.0, 0.5), (2.0, 0.6), (3.0, 0.1), (0.5, 0.9)])
    [3, 0, 2]
    """
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front: list[int] = []
    best = float("inf")
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def cheapest_within(points: Sequence[tuple[float, float]], target: float) -> int | None:
    """Index of the cheapest point with error at most ``target`` (None: none).

    Examples
    --------
    >>> cheapest_within([(1.0, 0.5), (2.0, 0.05), (3.0, 0.01)], 0.1)
    1
    """
    ok = [i for i, (_, e) in enumerate(points) if e <= target]
    return min(ok, key=lambda i: points[i][0]) if ok else None


def best_within(points: Sequence[tuple[float, float]], budget: float) -> int | None:
    """Index of the most accurate point costing at most ``budget`` (None: none).

    Examples
    --------
    >>> best_within([(1.0, 0.5), (2.0, 0.05), (3.0, 0.01)], 2.5)
    1
    """
    ok = [i for i, (c, _) in enumerate(points) if c <= budget]
    return min(ok, key=lambda i: points[i][1]) if ok else None
