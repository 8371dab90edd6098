#!/usr/bin/env python
"""CPTu: the coupled cone's u2 and its dissipation against Teh & Houlsby's T*_50.

Runs ``cone-penetration`` with the weightless effective-stress clay of
docs/validation/cone_penetration.md (c' = 0, phi' = 25 deg, psi = 0,
p'_0 = sigma0 = 50 kPa, nu' = 0.3, I_r = G/s_u = 100) with coupled drainage
(k = 1e-8 m/s: c_h = k M / gamma_w = 7.5e-6 m^2/s, V = v D / c_h = 95 at
2 cm/s), pushed ``push`` x D (from 10 D deep in the scene's 30 D radius, or
from 4 D deep in a 10 D radius with ``--domain small``), then held
(``dissipation=true``) to T* = 2.  At each spacing D/n and cone step
(spacing / ``per`` a step) it tabulates u2 at the end of the push (u2(0)),
the steady u2 (its mean over the push's last diameter) and u2's largest value,
the u2 of the held cone's first step over u2(0), and the T* at which u2 fell
to half of u2(0), against Teh & Houlsby's (1991) T*_50 = 0.245 at u2; then
the T* of 20 to 80 % dissipation against their table, and the curves beside
theirs in the figure.  u2 is read on the shaft just behind the shoulder
(the scene's filter, 0.15 D tall).

Usage (from the repository root)::

    python demos/studies/cptu.py [--n 8 10] [--push 4 4] [--per 4 4]
        [--domain scene scene] [--tables]

``--tables`` writes ``docs/validation/cptu.json``, the table
``docs/validation/cptu.inc`` and the figure ``docs/validation/cptu.png``
(included by docs/validation/cone_penetration.md).
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from _common import VALIDATION
from _reporting import save_png

import skfem_npfem as npfem
from skfem_npfem.scenes.footing.cone_dissipation import (
    TEH_HOULSBY_T50_U2,
    TEH_HOULSBY_U2,
    half_time,
)

D = 0.0357
K = 1.0e-8
CLAY = {"material": "mohr-coulomb", "phi": 25.0, "nu": 0.3}
STAGE = {
    "drainage": "coupled",
    "k": K,
    "dissipation": True,
    "dT": 0.002,
    "dt_growth": 1.3,
    "dT_max": 0.1,
    "T_end": 2.0,
}
#: The domains: the scene's (the cone 10 D deep at the start, 30 D wide, 8 D of
#: soil under the tip's last position) and a small one (4 D, 10 D, 3 D).
DOMAINS = {
    "scene": {},
    "small": {"depth": 4 * D, "domain_below": 3.0, "domain_radius": 10.0},
}


def run_row(n: int, push: float, per: float, domain: str = "scene") -> dict:
    """The CPTu at D/n pushed ``push`` D, the cone moving spacing/per a step."""
    h = D / n
    over = {
        **CLAY,
        **DOMAINS[domain],
        **STAGE,
        "spacing": h,
        "dt": h / per / 0.02,
        "penetration": push * D,
    }
    t0 = time.perf_counter()
    m = npfem.run_scene("cone-penetration", over)["metrics"]
    curve = m["dissipation"]
    return {
        "n": n,
        "push": push,
        "per": per,
        "domain": domain,
        "su": m["undrained_strength"],
        "u2_max": m["u2_max"],
        "u2_end": m["u2_end"],
        "u2_steady": m["u2_steady"],
        "first_held": curve[1][1] if len(curve) > 1 else None,
        "t50_star": m["t50_star"],
        "t50_star_steady": half_time(
            [[t, u * m["u2_end"] / m["u2_steady"]] for t, u in curve]
        ),
        "V": m["normalised_velocity"],
        "c_h": m["consolidation_coefficient"],
        "N_c": m["cone_factor"],
        "times": [half_time(curve, 1.0 - U) for U, _ in TEH_HOULSBY_U2],
        "curve": curve,
        "wall_s": time.perf_counter() - t0,
    }


def fmt(t50: float | None) -> str:
    """``T*_50 (+x %)`` against Teh & Houlsby, or n/a."""
    if t50 is None:
        return "n/a"
    return f"{t50:.3g} ({t50 / TEH_HOULSBY_T50_U2 - 1:+.0%})"


def markdown(rows: list[dict]) -> str:
    """One line per domain, spacing, push and cone step."""
    lines = [
        "| domain, D/n, push, cone step | V | N_c | u2(0) = u2 at the end of the "
        "push / s_u | steady u2 / s_u | u2_max / s_u | first held step: u2/u2(0) "
        "| T*_50 (vs 0.245) | T*_50 from the steady u2 | wall (s) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        su = r["su"]
        lines.append(
            f"| {r['domain']}, D/{r['n']}, {r['push']:g} D, h/{r['per']:g} | "
            f"{r['V']:.0f} | {r['N_c']:.2f} | {r['u2_end'] / su:.2f} | "
            f"{r['u2_steady'] / su:.2f} | {r['u2_max'] / su:.2f} | "
            f"{r['first_held']:.2f} | {fmt(r['t50_star'])} | "
            f"{fmt(r['t50_star_steady'])} | {r['wall_s']:.0f} |"
        )
    lines += [
        "",
        "T* at a degree of dissipation U = 1 - u2/u2(0), against Teh & Houlsby's "
        "(1991) table at u2:",
        "",
        "| | " + " | ".join(f"U = {U:.0%}" for U, _ in TEH_HOULSBY_U2) + " |",
        "|---" * (len(TEH_HOULSBY_U2) + 1) + "|",
        "| Teh & Houlsby | " + " | ".join(f"{T:g}" for _, T in TEH_HOULSBY_U2) + " |",
    ]
    for r in rows:
        cells = [
            "n/a" if t is None else f"{t:.3g} ({t / T - 1:+.0%})"
            for t, (_, T) in zip(r["times"], TEH_HOULSBY_U2, strict=True)
        ]
        row = f"| {r['domain']}, D/{r['n']}, {r['push']:g} D | "
        lines.append(row + " | ".join(cells) + " |")
    return "\n".join(lines).replace("%", " %") + "\n"


def figure(rows: list[dict], path: Path) -> None:
    """u2/u2(0) against T* of each row, and Teh & Houlsby's T*_50 at u2."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.8))
    for r in rows:
        c = np.asarray(r["curve"][1:])  # T* = 0 has no place on a log axis
        ax.semilogx(
            c[:, 0],
            c[:, 1],
            ".-",
            ms=4,
            label=f"N-PFEM, {r['domain']} domain, D/{r['n']}, push {r['push']:g} D, "
            f"step h/{r['per']:g}",
        )
    th = np.asarray(TEH_HOULSBY_U2)
    ax.semilogx(
        th[:, 1],
        1.0 - th[:, 0],
        "ks--",
        ms=5,
        label="Teh & Houlsby (1991), u2: their table, U = 20 to 80 %",
    )
    ax.plot([TEH_HOULSBY_T50_U2], [0.5], "k*", ms=12)
    ax.axhline(0.5, color="0.7", lw=0.8)
    ax.set_xlabel("T* = c_h t / (R^2 sqrt(I_r))")
    ax.set_ylabel("u2(t) / u2(end of push)")
    ax.set_title("CPTu dissipation at the shoulder (u2)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    save_png(fig, path, dpi=110)


def main() -> None:
    """Run the rows; print the table; with ``--tables`` write it and the figure."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, nargs="+", default=[8, 10])
    parser.add_argument("--push", type=float, nargs="+", default=[4.0, 4.0])
    parser.add_argument("--per", type=float, nargs="+", default=[4.0, 4.0])
    parser.add_argument(
        "--domain", nargs="+", default=["scene", "scene"], choices=list(DOMAINS)
    )
    parser.add_argument("--jobs", type=int, default=1, help="rows run at once")
    parser.add_argument("--tables", action="store_true", help="write the results")
    args = parser.parse_args()
    specs = list(zip(args.n, args.push, args.per, args.domain, strict=True))
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = list(pool.map(run_row, *zip(*specs, strict=True)))
    page = markdown(rows)
    print(page)
    if args.tables:
        (VALIDATION / "cptu.json").write_text(json.dumps(rows, indent=1) + "\n")
        (VALIDATION / "cptu.inc").write_text(page)
        figure(rows, VALIDATION / "cptu.png")


if __name__ == "__main__":
    main()
