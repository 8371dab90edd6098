#!/usr/bin/env python
"""The seed granular column (r0 = 3.9 cm, h0 = 7.8 cm), axisymmetric or 3D, per step.

Builds the column with :func:`skfem_npfem.scenes.collapse.cylinder.cylinder_column` and
writes one JSON line per step: time, normalised time t / sqrt(h0 / g), status,
IPM iterations, step wall time, the radial 99 % mass front, the top height,
kinetic energy, mass and mesh-volume change, and the Lode parameter of the
yielding nodes (mu = (2 s2 - s1 - s3) / (s1 - s3), s1 >= s2 >= s3 tension
positive: +1 on the triaxial-compression meridian, -1 on the extension one).

Usage::

    PYTHONPATH=. python benchmarks/cylinder_seed_run.py --geometry axisymmetric \
        --divisions 12 --steps 400 --rest 1e-4
    PYTHONPATH=. python benchmarks/cylinder_seed_run.py --geometry quarter-cylinder \
        --divisions 12 --steps 20
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from skfem_npfem.run.simulation import Simulation, voigt_to_tensor
from skfem_npfem.scenes.collapse.cylinder import SEED, cylinder_column, radial_front

HERE = Path(__file__).resolve().parent


def lode(stress: np.ndarray) -> np.ndarray:
    """Lode parameter of full-Voigt stresses (N, 4|6), tension positive."""
    s = np.sort(np.linalg.eigvalsh(voigt_to_tensor(stress)), axis=1)[:, ::-1]
    span = s[:, 0] - s[:, 2]
    out = np.full(s.shape[0], np.nan)
    ok = span > 1e-12 * np.abs(s).max(initial=1.0)
    out[ok] = (2 * s[ok, 1] - s[ok, 0] - s[ok, 2]) / span[ok]
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--geometry", default="axisymmetric")
    ap.add_argument("--divisions", type=float, default=12.0, help="r0 / spacing")
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--rest", type=float, default=0.0, help="stop at KE < rest*max")
    ap.add_argument("--out", default=None, help="JSON-lines file")
    args = ap.parse_args(argv)
    col = cylinder_column(args.geometry, SEED["radius"] / args.divisions)
    tag = f"seed_{args.geometry}_{args.divisions:g}"
    out = Path(args.out or HERE / "results" / f"{tag}.jsonl")
    out.parent.mkdir(parents=True, exist_ok=True)
    sim = Simulation(col.particles, col.model, col.mesher, col.dt)
    t_scale = math.sqrt(SEED["height"] / SEED["gravity"])
    print(f"{tag}: {col.n_particles} particles", flush=True)
    t0 = time.perf_counter()
    with open(out, "w") as log:
        for k in range(args.steps):
            ts = time.perf_counter()
            sim.run(steps=1)
            r = sim.records[-1]
            p = sim.particles
            sol = r.solution
            plastic = np.linalg.norm(sol.deps_p, axis=1) > 1e-12
            mu = lode(sol.sigma[plastic]) if plastic.any() else np.zeros(0)
            mu = mu[np.isfinite(mu)]
            rec = {
                "step": k + 1,
                "t": sim.time,
                "t_norm": sim.time / t_scale,
                "status": r.status,
                "it": r.iterations,
                "step_s": time.perf_counter() - ts,
                "wall": time.perf_counter() - t0,
                "n_active": int(r.n_active),
                "front": radial_front(p.x, p.mass),
                "top": float(p.x[:, -1].max()),
                "ke": r.kinetic_energy,
                "mass_change": r.mass / sim.initial["mass"] - 1.0,
                "volume_change": r.volume_change,
                "n_plastic": int(plastic.sum()),
                "lode_mean": float(mu.mean()) if mu.size else None,
                "lode_above_half": float(np.mean(mu > 0.5)) if mu.size else None,
            }
            log.write(json.dumps(rec) + "\n")
            log.flush()
            if k % 10 == 0:
                print(rec, flush=True)
            ke_max = max(q.kinetic_energy for q in sim.records)
            if args.rest > 0 and k > 10 and r.kinetic_energy < args.rest * ke_max:
                break
    print(
        f"done: {sim.step} steps, t = {sim.time:.3f} s, "
        f"{time.perf_counter() - t0:.1f} s",
        flush=True,
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
