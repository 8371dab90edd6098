#!/usr/bin/env python
"""A sensitive-clay slope that retrogresses: our run-out against a published one.

The set-up of del Castillo, Borja & Fávero Neto (2026, section 5.1; the
benchmark geometry of Bui & Nguyen 2021): a 5 m slope at 45 deg, 20 m of crest,
on a rigid base (``foundation_depth = 0``, the run-out spreads on it), of an
undrained clay (Tresca) with ``E`` = 25 MPa, ``nu`` = 0.3, ``rho`` = 2150
kg/m^3, a peak strength of 15.1 kPa softening to 1.5 kPa as
``c_r + (c_p - c_r) exp(-eta eps)`` with ``eta`` = 5 (our law with ``S_t`` =
15.1/1.5 and ``xi_95 = 3 sqrt(3) / eta``, reading their accumulated plastic
strain as the von Mises equivalent one), initial stresses ``K0`` = 0.5, and
the slide triggered by dividing the strength by 1.65.  Their undrained SPH
run: run-out 21.6 m, retrogression 14.0 m, three slides.

Runs at spacings 0.5 m and 0.25 m (and, with ``--variants``, the residual
strength left unreduced, a slower softening, ``xi_95`` = 3, and the nonlocal
strain over 1 m at both spacings), each to rest or 30 s; and the
independent check of what a fully remoulded mass must do: at rest on a rough
floor a Tresca layer of strength ``c`` needs
``gamma h |dh/dx| <= c``, so the area ``A`` of the slope, remoulded, spreads
over at least ``L = (3 A / (2 sqrt(2 c / gamma)))^(2/3)`` from the back wall.

Usage (from the repository root)::

    python demos/studies/retrogression.py [--out docs/validation] [--quick]
        [--variants]

``--quick`` runs the 0.5 m spacing only.  Writes ``<out>/retrogression.json``
and ``<out>/retrogression.inc``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from pathlib import Path

from _common import VALIDATION, write_results

import skfem_npfem as npfem
from skfem_npfem.constants import GRAVITY

PEAK, RESIDUAL, ETA, TRIGGER = 15.1e3, 1.5e3, 5.0, 1.65
SLOPE = {
    "material": "tresca",
    "c": PEAK,
    "rho": 2150.0,
    "E": 25.0e6,
    "nu": 0.3,
    "height": 5.0,
    "angle": 45.0,
    "foundation_depth": 0.0,
    "crest_length": 20.0,
    "toe_length": 40.0,
    "initial_stress": "k0",
    "K0": 0.5,
    "runout": True,
    "reduction": TRIGGER,
    "sensitivity": PEAK / RESIDUAL,
    "ductility": 3.0 * math.sqrt(3.0) / ETA,
    "t_end": 30.0,
}
#: Their undrained SPH run (section 5.1).
PUBLISHED = {"runout": 21.6, "retrogression": 14.0, "slides": 3}
NONLOCAL = {"softening_length": 1.0}
VARIANTS = {
    "residual unreduced": {"sensitivity": PEAK / TRIGGER / RESIDUAL},
    "slower softening (xi_95 = 3)": {"ductility": 3.0},
}


def remoulded_spread(area: float, c: float, gamma: float) -> float:
    """The shortest deposit (m from the back wall) of a remoulded mass at rest."""
    return (1.5 * area / math.sqrt(2.0 * c / gamma)) ** (2.0 / 3.0)


def run(label: str, over: dict) -> dict:
    """One run-out's metrics of interest and its wall time."""
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = npfem.run_scene("slope", {**SLOPE, **over})["metrics"]
    keep = ("runout", "retrogression", "blocks", "at_rest", "moved_volume")
    out = {"label": label, **{k: m[k] for k in keep}}
    return out | {"spacing": over["spacing"], "wall_s": time.perf_counter() - t0}


def main() -> None:
    """Run the cases; write the JSON and the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=VALIDATION)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--variants", action="store_true")
    args = parser.parse_args()
    rows = [run("published set-up", {"spacing": 0.5})]
    if not args.quick:
        rows.append(run("published set-up", {"spacing": 0.25}))
    if args.variants:
        for label, over in VARIANTS.items():
            rows.append(run(label, {"spacing": 0.5, **over}))
        for h in (0.5, 0.25):
            rows.append(run("nonlocal strain (1 m)", {"spacing": h, **NONLOCAL}))
    area = 0.5 * SLOPE["height"] * (2 * SLOPE["crest_length"] + SLOPE["height"])
    gamma = SLOPE["rho"] * GRAVITY
    toe = SLOPE["crest_length"] + SLOPE["height"]
    spread = {
        f"{c / 1e3:.2f} kPa": remoulded_spread(area, c, gamma) - toe
        for c in (RESIDUAL / TRIGGER, RESIDUAL)
    }
    lines = [
        "| case | spacing (m) | run-out (m) | retrogression (m) | blocks | at rest "
        "| wall (s) |",
        "|---|---|---|---|---|---|---|",
        f"| del Castillo et al. (2026), undrained SPH | 0.1 | "
        f"{PUBLISHED['runout']} | {PUBLISHED['retrogression']} | "
        f"{PUBLISHED['slides']} slides | yes | |",
    ]
    for r in rows:
        lines.append(
            f"| {r['label']} | {r['spacing']:g} | {r['runout']:.1f} | "
            f"{r['retrogression']:.1f} | {r['blocks']} | "
            f"{'yes' if r['at_rest'] else 'no (30 s)'} | {r['wall_s']:.0f} |"
        )
    lines += [
        "",
        "| remoulded strength | shortest run-out of the whole slope remoulded (m) |",
        "|---|---|",
        *(f"| {k} | {v:.1f} |" for k, v in spread.items()),
    ]
    text = "\n".join(lines) + "\n"
    report = {"published": PUBLISHED, "rows": rows, "remoulded_runout": spread}
    write_results(
        args.out / "retrogression.json", json.dumps(report, indent=1) + "\n", text
    )


if __name__ == "__main__":
    main()
