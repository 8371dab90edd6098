#!/usr/bin/env python
"""Figure of docs/performance.md: seconds per step against the program's size.

Reads the committed suite reports of ``benchmarks/results/`` and pools them
exactly as the page's "time-per-step" table does (``benchmarks/suite.py``:
the newest clean measurement per case, backend and preset), then plots the
high preset's median step time per backend against the number of variables,
one line per family of cases (2D collapse, footing, 3D block, 3D quarter
cylinder), with the reference implementation's times per step beside them.
No benchmark is run.

Usage (from the repository root)::

    python benchmarks/plot_time_per_step.py            # docs/pictures/time_per_step.png
    python benchmarks/plot_time_per_step.py --out /tmp/t.png
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = ROOT / "docs" / "pictures" / "time_per_step.png"

#: Case families: name prefix -> (label, marker).
FAMILIES = {
    "collapse-": ("2D collapse", "o"),
    "footing-": ("2D footing", "s"),
    "block3d-": ("3D block", "^"),
    "cylinder3d-": ("3D quarter cylinder", "D"),
}
#: Backends of the high preset -> (label, colour); faer is the better of its
#: automatic threads and one thread, as in the table.
BACKENDS = {
    "qdldl": ("qdldl", "C0"),
    "faer": ("faer", "C1"),
    "mkl": ("MKL Pardiso", "C2"),
}


def pooled() -> dict[tuple[str, str, str], dict]:
    """The table's pooled measurements (benchmarks/suite.py)."""
    if str(HERE) not in sys.path:
        sys.path.insert(0, str(HERE))
    import suite

    return suite._pooled()


def series(pool: dict) -> dict[tuple[str, str], list[tuple[float, float]]]:
    """(family, backend) -> [(variables, s/step)], by size."""
    out: dict[tuple[str, str], list[tuple[float, float]]] = {}
    cases = sorted({k[0] for k in pool})
    for case in cases:
        family = next((f for f in FAMILIES if case.startswith(f)), None)
        if family is None:
            continue
        for backend in BACKENDS:
            names = [backend] + (["faer (1 thr.)"] if backend == "faer" else [])
            keys = [(case, b, "high") for b in names]
            found = [pool[k] for k in keys if k in pool]
            if not found:
                continue
            best = min(found, key=lambda s: s["median_s"])
            out.setdefault((family, backend), []).append(
                (float(best["variables"]), best["median_s"])
            )
    return {k: sorted(v) for k, v in out.items()}


def references(pool: dict) -> list[tuple[float, float]]:
    """The reference implementation's s/step at the size of each suite case."""
    bench = str(HERE)
    if bench not in sys.path:
        sys.path.insert(0, bench)
    import suite

    points = []
    for case, ref in suite.REFERENCE.items():
        size = next((s["variables"] for k, s in pool.items() if k[0] == case), None)
        if size is not None:
            points += [(float(size), v) for v in ref.values()]
    return points


def plot(path: Path = OUT) -> Path:
    """Draw the figure and store it as a palette PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    studies = str(ROOT / "demos" / "studies")
    if studies not in sys.path:
        sys.path.insert(0, studies)
    from _reporting import save_png

    pool = pooled()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for (family, backend), pts in series(pool).items():
        label, marker = FAMILIES[family]
        name, colour = BACKENDS[backend]
        x, y = zip(*pts, strict=True)
        ax.plot(x, y, marker=marker, color=colour, ms=5, lw=1, alpha=0.85)
    ref = references(pool)
    if ref:
        x, y = zip(*ref, strict=True)
        ax.plot(x, y, "kx", ms=7, ls="none", label="reference implementation")
    for name, colour in BACKENDS.values():
        ax.plot([], [], color=colour, label=name)
    for label, marker in FAMILIES.values():
        ax.plot([], [], marker=marker, color="0.4", ls="none", label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("variables of the cone program")
    ax.set_ylabel("s per step (median, high preset)")
    ax.set_title("Time per step by backend (2 cores)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return save_png(fig, path)


def main(argv: list[str] | None = None) -> Path:
    """Command line: ``--out`` the PNG."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--out", type=Path, default=OUT, help=f"PNG (default {OUT})")
    args = ap.parse_args(argv)
    path = plot(args.out)
    print(path)
    return path


if __name__ == "__main__":
    main()
