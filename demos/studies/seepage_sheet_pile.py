#!/usr/bin/env python
"""Steady seepage under a sheet pile in a layer of finite depth: mesh convergence.

A permeable layer of thickness ``T`` on an impermeable base, a sheet pile (an
impermeable cut of zero thickness) of penetration ``s`` at ``x = 0``, total
head ``H`` on the upstream ground surface (``x < 0``) and 0 downstream; the
layer runs ``L = 4 T`` each side (the truncation changes the flow by
``O(exp(-pi L / T))``, below 1e-5).  The flow rate under the pile
(Polubarinova-Kochina, "Theory of Ground Water Movement", 1962; Harr,
"Groundwater and Seepage", 1962, the sheet pile in a layer of finite depth)
is

    q / (k H) = K(m') / (2 K(m)),   m = sin(pi s / (2 T)),   m'^2 = 1 - m^2,

``K`` the complete elliptic integral of the first kind of modulus ``m``
(``scipy.special.ellipk`` takes the parameter ``m^2``).  Derivation: by
antisymmetry the head is ``H / 2`` on ``x = 0`` below the tip; ``zeta =
sinh(pi (x + i y) / (2 T))^2`` (``y`` the depth) maps the downstream half of
the layer onto the upper half plane with the head 0 on ``(0, inf)``, the
pile on ``(-m^2, 0)``, the head ``H / 2`` on ``(-1, -m^2)`` and the base on
``(-inf, -1)``, a quadrilateral of modulus ``K(m') / K(m)``.  Limits:
``s -> 0`` gives ``m -> 0`` and an unbounded flow (logarithmically, the head
drops across a vanishing cut), ``s -> T`` gives ``m -> 1`` and no flow;
``s = T / 2`` gives exactly ``q = k H / 2``.

The mesh is two structured blocks of right triangles, upstream and
downstream of ``x = 0``, which share only the nodes at and below the pile's
tip: the nodes above it are doubled, one copy for each side.

Usage (repository root)::

    python demos/studies/seepage_sheet_pile.py            # print the table
    python demos/studies/seepage_sheet_pile.py --tables   # and write it

``--tables`` writes ``demos/studies/results/seepage_sheet_pile.json`` and the
table ``seepage_sheet_pile.inc`` beside it (included by docs/theory.md).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from scipy.special import ellipk

from skfem_npfem.water import HeadBoundary, Seepage

RESULTS = Path(__file__).resolve().parent / "results"

#: Penetration ratios s / T and spacings T / h of the refinement table.
RATIOS = (0.25, 0.5, 0.75)
DIVISIONS = (4, 8, 16, 32)


def reference(ratio: float) -> float:
    """``q / (k H)`` under a sheet pile of penetration ``s = ratio T``."""
    m2 = np.sin(0.5 * np.pi * ratio) ** 2
    return float(ellipk(1.0 - m2) / (2.0 * ellipk(m2)))


def sheet_pile_mesh(
    depth: float, penetration: float, n: int, length: float = 4.0
) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (N, 2) and triangles (3, ne) of the layer cut by the pile.

    ``n`` divisions over the depth (spacing ``depth / n``; the tip is a grid
    line, so ``penetration / depth * n`` must be an integer) and
    ``length * n`` each side of the pile.
    """
    h = depth / n
    tip = round((depth - penetration) / h)
    if not np.isclose(tip * h, depth - penetration):
        raise ValueError("the pile's tip must fall on a grid line")
    nx = round(length * n)
    xs = np.linspace(-length * depth, length * depth, 2 * nx + 1)
    zs = np.linspace(0.0, depth, n + 1)
    X, Z = np.meshgrid(xs, zs, indexing="ij")  # node (i, j) is i * (n + 1) + j
    x = np.column_stack([X.ravel(), Z.ravel()])
    ids = np.arange(x.shape[0]).reshape(2 * nx + 1, n + 1)
    a, b = ids[:-1, :-1].ravel(), ids[1:, :-1].ravel()
    c, d = ids[1:, 1:].ravel(), ids[:-1, 1:].ravel()
    t = np.hstack([np.array([a, b, c]), np.array([a, c, d])])
    # Doubled nodes of the pile (above its tip) for the downstream block.
    pile = ids[nx, tip + 1 :]
    twin = np.full(x.shape[0], -1)
    twin[pile] = x.shape[0] + np.arange(pile.size)
    x = np.vstack([x, x[pile]])
    downstream = x[t].mean(axis=0)[:, 0] > 0.0
    moved = t[:, downstream]
    moved[twin[moved] >= 0] = twin[moved][twin[moved] >= 0]
    t[:, downstream] = moved
    return x, t


def sheet_pile_seepage(depth: float, head: float, length: float = 4.0) -> Seepage:
    """The head boundaries of the sheet pile: ``head`` upstream, 0 downstream."""
    up = HeadBoundary([[-length * depth, depth], [0.0, depth]], head, "upstream")
    down = HeadBoundary([[0.0, depth], [length * depth, depth]], 0.0, "downstream")
    return Seepage([up, down], k=1.0)


def flow(ratio: float, n: int) -> float:
    """``q / (k H)`` of the P1 solution with ``n`` elements over the depth."""
    x, t = sheet_pile_mesh(1.0, ratio, n)
    field = sheet_pile_seepage(1.0, 1.0).solve(x, t)
    return field.inflow["upstream"]


def table() -> list[dict]:
    """The refinement table: the flow at every ratio and spacing.

    The error is O(h) (the flow is an energy, and the head has an ``r^(1/2)``
    singularity at the pile's tip), so ``2 q_h - q_2h`` (Richardson) is the
    extrapolated flow of each halving.
    """
    rows = []
    for ratio in RATIOS:
        ref = reference(ratio)
        previous = None
        for n in DIVISIONS:
            q = flow(ratio, n)
            extrapolated = None if previous is None else 2.0 * q - previous
            rows.append(
                {
                    "s/T": ratio,
                    "T/h": n,
                    "q/kH": q,
                    "extrapolated": extrapolated,
                    "reference": ref,
                    "error": q / ref - 1,
                }
            )
            previous = q
    return rows


def markdown(rows: list[dict]) -> str:
    """The table as a MyST fragment."""
    lines = [
        "| s / T | T / h | q / (k H), P1 | error | extrapolated (2 q_h - q_2h) "
        "| conformal mapping |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        ex = "" if r["extrapolated"] is None else f"{r['extrapolated']:.5f}"
        lines.append(
            f"| {r['s/T']:g} | {r['T/h']} | {r['q/kH']:.5f} "
            f"| {100 * r['error']:+.2f} % | {ex} | {r['reference']:.5f} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--tables", action="store_true", help="write the JSON and the .inc table"
    )
    args = parser.parse_args()
    rows = table()
    page = markdown(rows)
    print(page)
    if args.tables:
        RESULTS.mkdir(parents=True, exist_ok=True)
        out = RESULTS / "seepage_sheet_pile.json"
        out.write_text(json.dumps(rows, indent=1) + "\n")
        out.with_suffix(".inc").write_text(page)


if __name__ == "__main__":
    main()
