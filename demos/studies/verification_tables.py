#!/usr/bin/env python
"""Verification tables: the elastic column and the Prandtl footing, measured.

Runs the verification cases of docs/verification.md through the scenes (the
same cases the tests assert, plus the refinements they do not all run) and
writes their measured errors to ``docs/validation/verification.json``; the
documentation builds the tables of docs/verification.md from that file.

* **Elastic column** (scene ``elastic-column``, oedometric, H = 4 m, W = 1 m,
  rho = 2000 kg/m^3, nu = 0.3, static): relative L2 errors of the vertical and
  horizontal stress against sigma_v = -rho g (H - z), sigma_h = nu/(1-nu)
  sigma_v, and of the top settlement against rho g H^2 / (2M), in 2D at
  spacings 0.25, 0.125, 0.0625 m and in 3D at 0.25, 0.125 m.
* **Sudden gravity** (the same column, dynamic, E = 100 MPa, theta1 = theta2 =
  1/2, dt = T/40, 100 steps): the top's period against the first oedometric
  period T = 4H/c_p.
* **Prandtl footing** (scene ``strip-footing``, weightless Tresca soil, run to
  the load plateau): q/c against 2 + pi for 8, 16 and 32 elements across the
  half-footing (smooth), Drucker-Prager with the plane-strain match at phi = 0,
  and the rough footing at 8 and 16.

About two minutes on one core.  Usage (from the repository root)::

    python demos/studies/verification_tables.py [--out docs/validation]
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import platform
import time
from pathlib import Path

from _common import ROOT

import skfem_npfem as npfem

COLUMNS = [
    {"dim": 2, "spacing": 0.25},
    {"dim": 2, "spacing": 0.125},
    {"dim": 2, "spacing": 0.0625},
    {"dim": 3, "spacing": 0.25},
    {"dim": 3, "spacing": 0.125},
]
FOOTINGS = [
    {"spacing": 0.125},
    {"spacing": 0.0625},
    {"spacing": 0.03125},
    {"spacing": 0.125, "material": "drucker-prager"},
    {"spacing": 0.125, "footing": "rough"},
    {"spacing": 0.0625, "footing": "rough"},
]


def column_case(overrides: dict) -> dict:
    """One static elastic column: stress errors and settlement error."""
    t0 = time.perf_counter()
    s = npfem.run_scene("elastic-column", overrides)
    m = s["metrics"]
    return {
        "overrides": overrides,
        "n_particles": m["n_particles"],
        "sigma_v_rel_l2": m["sigma_v_rel_l2"],
        "sigma_h_rel_l2": m["sigma_h_rel_l2"],
        "settlement": m["settlement"],
        "settlement_exact": m["settlement_exact"],
        "settlement_error": m["settlement"] / m["settlement_exact"] - 1,
        "ipm_iterations_max": s["solver"]["ipm_iterations_max"],
        "wall_time": time.perf_counter() - t0,
    }


def period_case() -> dict:
    """Sudden gravity on the column: the top's period against 4H/c_p."""
    E, nu, rho, H = 1.0e8, 0.3, 2000.0, 4.0
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    T = 4 * H / math.sqrt(M / rho)
    overrides = {
        "E": E,
        "mode": "dynamic",
        "theta1": 0.5,
        "theta2": 0.5,
        "dt": T / 40,
        "steps": 100,
    }
    t0 = time.perf_counter()
    m = npfem.run_scene("elastic-column", overrides)["metrics"]
    h = 2 * math.pi / 40  # the trapezoidal rule's own elongation, h / (2 atan(h/2))
    return {
        "overrides": overrides,
        "period": m["period"],
        "period_exact": m["period_exact"],
        "period_error": m["period"] / m["period_exact"] - 1,
        "trapezoidal_elongation": h / (2 * math.atan(h / 2)) - 1,
        "wall_time": time.perf_counter() - t0,
    }


def footing_case(overrides: dict) -> dict:
    """One footing to its plateau: q/c against 2 + pi."""
    t0 = time.perf_counter()
    s = npfem.run_scene("strip-footing", overrides)
    m = s["metrics"]
    return {
        "overrides": overrides,
        "elements_across": round(1.0 / overrides["spacing"]),
        "n_particles": m["n_particles"],
        "bearing_factor": m["bearing_factor"],
        "reference": 2 + math.pi,
        "relative_error": m["bearing_factor"] / (2 + math.pi) - 1,
        "plateau_reached": m["plateau_reached"],
        "steps": s["solver"]["steps"],
        "wall_time": time.perf_counter() - t0,
    }


def main(argv: list[str] | None = None) -> int:
    """Run every case and write the JSON."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "validation")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    report = {
        "meta": {
            "date": datetime.date.today().isoformat(),
            "skfem_npfem": npfem.__version__,
            "python": platform.python_version(),
        },
        "columns": [column_case(o) for o in COLUMNS],
        "period": period_case(),
        "footings": [footing_case(o) for o in FOOTINGS],
    }
    report["meta"]["wall_time"] = time.perf_counter() - t0
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "verification.json"
    path.write_text(json.dumps(report, indent=1) + "\n")
    print(f"wrote {path} ({report['meta']['wall_time']:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
