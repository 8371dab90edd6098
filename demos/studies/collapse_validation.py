"""Validation: 2D granular column collapse against the experimental laws.

Sweeps the aspect ratio ``a = H0/L0`` of the ``column-collapse`` scene (half
column against a smooth wall, plane strain, Mohr-Coulomb phi = 30 deg, psi = 0,
c = 0, floor friction = phi) and runs a mesh-refinement series at ``a = 2``.
Every case runs until the scene's at-rest rule stops it (kinetic energy below
``rest_fraction`` times its maximum, after ``2 sqrt(H0/g)``); ``t_end`` is a
safety cap that scales with the collapse time scale ``sqrt(H0/g)``.

Writes (under ``--out``, default ``docs/validation``):

* ``collapse_validation.json``: per case a, N, particles, steps, the normalised
  run-out (L_inf - L0)/L0, H_inf/L0, H_inf/H0, collapse time (s and in units of
  sqrt(H0/g)), volume change, wall time, median time per step and the solver
  statuses; the experimental laws; the fitted small-a slope and large-a
  exponent against the gates below;
* ``runout_vs_aspect.png``: run-out and final height against a (log-log);
* ``refinement_a2.png``: run-out and final height against N at a = 2;
* ``deposits.png``: the final deposits of the primary sweep;

and under ``--cases`` (default ``out/collapse_validation/cases``, not
committed) ``a<a>_N<N>[_<variant>].json``: the full scene summary of each case
(per-step history, final particle cloud, library commit and source hash).

Run-out measures stored: the scene's ``normalised_runout``, the primary
measure (the front of the main body until 2026-11, the 99 % mass front of the
scene's particles since), the main body (``runout_main_body_normalised``, when
the scene reports it), the 99 % mass front of all particles (x below which
99 % of the particle mass lies) and the farthest particle.  Per case the
stress roughness (at rest and its maximum) and the stabilisation factor and
volume correction the scene resolved are stored too.

Usage (from the repository root; the command below wrote
docs/validation/collapse_validation.json with the scene's defaults, about 15
minutes of wall time with two cases in parallel on two cores; the record with the
former defaults, run with the same command, is kept in compact form as
docs/validation/collapse_validation_before.json)::

    PYTHONPATH=. python demos/studies/collapse_validation.py \\
        --aspects 0.5,1,2,4,8 --particles-across 12,8,16,22 \\
        --refinement 8,10,12,14,16,19,22 --jobs 2 \\
        --variants "dt=0.01;dt=0.0025;dt=0.00125;alpha=1.6;E=1e8;\\
floor_friction=20;floor_friction=40;rest_fraction=0.0001"

The first ``--particles-across`` value is the primary sweep (tables, fits,
gates); the others are secondary sweeps, whose cases above ``--max-particles``
(1 500) are skipped.  ``--variants`` are sensitivity runs at the refinement
aspect and the primary N.

Cases whose ``--cases`` files already exist with the same parameters are not
run again (``--force`` reruns them); ``--plot-only`` only rebuilds the JSON and
the figures from the stored cases.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from _common import ROOT, WORK, benchmark, floats, ints
from _reporting import save_png

SCENE = "column-collapse"
G = 9.81

# ---------------------------------------------------------------------------
# Experimental laws and the gates of the run-out
# ---------------------------------------------------------------------------

#: Lube et al. (2005), 2D channel: 1.2 a for a <= 1.8, 1.9 a^(2/3) for a >= 2.8.
LUBE = {"slope": 1.2, "small_max": 1.8, "prefactor": 1.9, "large_min": 2.8}
#: Lajeunesse et al. (2005), as tabulated by Lagrée et al. (2011): 1.8 a and
#: 2.3 a^(2/3), crossover a0 ~ 3.
LAJEUNESSE = {"slope": 1.8, "prefactor": 2.3, "a0": 3.0}
#: Gates of the fitted small-a slope and large-a exponent.
GATE_SLOPE = (0.75 * 1.2, 1.25 * 1.8)  # within +-25 % of 1.2-1.8
GATE_EXPONENT = (0.55, 0.85)
GATE_VOLUME = 0.01
#: Sensitivity runs of docs/validation.md (a = 2, primary N).
DEFAULT_VARIANTS = (
    "dt=0.01;dt=0.0025;dt=0.00125;alpha=1.6;E=1e8;"
    "floor_friction=20;floor_friction=40;rest_fraction=0.0001"
)


def lube_linear(a):
    return 1.2 * np.asarray(a, float)


def lube_power(a):
    return 1.9 * np.asarray(a, float) ** (2.0 / 3.0)


def lajeunesse_linear(a):
    return 1.8 * np.asarray(a, float)


def lajeunesse_power(a):
    return 2.3 * np.asarray(a, float) ** (2.0 / 3.0)


def lube_law(a: float) -> dict:
    """Lube et al. value(s) at ``a``: one branch, or both inside the transition."""
    if a <= LUBE["small_max"]:
        return {"branch": "1.2a", "value": float(lube_linear(a)), "low": None}
    if a >= LUBE["large_min"]:
        return {"branch": "1.9a^(2/3)", "value": float(lube_power(a)), "low": None}
    # Inside the transition band: "value" is the branch with the break at
    # a = 2.3 (Staron & Hinch 2005, as in the scene's reference_runout_lube);
    # low/high are the two branches.
    lo, hi = float(lube_linear(a)), float(lube_power(a))
    return {
        "branch": "transition 1.8 < a < 2.8 (1.2a .. 1.9a^(2/3))",
        "value": lo if a < 2.3 else hi,
        "low": min(lo, hi),
        "high": max(lo, hi),
    }


def lajeunesse_law(a: float) -> dict:
    if a < LAJEUNESSE["a0"]:
        return {"branch": "1.8a", "value": float(lajeunesse_linear(a))}
    return {"branch": "2.3a^(2/3)", "value": float(lajeunesse_power(a))}


# ---------------------------------------------------------------------------
# One case (run in a subprocess)
# ---------------------------------------------------------------------------


def case_name(a: float, n: int) -> str:
    return f"a{a:g}_N{n}"


def case_params(a: float, n: int, args) -> dict:
    L0 = args.length
    H0 = a * L0
    t_scale = math.sqrt(H0 / G)
    params = {
        "aspect": a,
        "half_width": L0,
        "spacing": L0 / n,
        "dt": args.dt,
        "t_end": round(args.t_end_factor * t_scale, 6),
        "rest_fraction": args.rest_fraction,
        "alpha": args.alpha,
        "threads": args.threads,
    }
    if args.floor_friction is not None:
        params["floor_friction"] = args.floor_friction
    return params


def library_fingerprint() -> dict:
    """Commit and content hash of the library sources (to detect mixed versions).

    Other people edit the library while long sweeps run; every case stores the
    hash at its start and end so that a sweep run across a code change shows up.
    """
    from skfem_npfem.io.provenance import git, source_sha1

    # File names relative to the package folder (not to the repository as in
    # the benchmarks), so that the hashes stored with earlier cases match.
    head = git("rev-parse", "HEAD", timeout=10)
    return {"git_head": (head or "").strip() or None, "source_sha1": source_sha1()}


def run_case(
    a: float, n: int, params: dict, path: Path, variant: str | None = None
) -> None:
    """Run one case in this process and write its scene summary to ``path``.

    Builds the scene exactly as :func:`skfem_npfem.run_scene` does (same
    ``build``, ``run_kwargs`` and ``metrics``) but keeps the simulation, so that
    the final deposit (particle positions and displacements) and two extra,
    mesh-independent front measures can be stored:

    * ``front_q99`` / ``front_q95``: the x below which 99 % / 95 % of the
      particle mass lies (every step);
    * the final particle cloud (``deposit``), for the failure-wedge estimate.
    """
    from skfem_npfem import __version__
    from skfem_npfem.scenes import get_scene

    lib_start = library_fingerprint()
    scene = get_scene(SCENE)
    values = scene.resolve(params)
    start = time.perf_counter()
    srun = scene.build(values, out=None, progress=False)
    sim = srun.simulation
    x0 = sim.particles.x.copy()
    last: dict = {}  # the mesh of the last step (records keep scalars only)

    def mass_front(sim_, p, step) -> bool:
        order = np.argsort(p.x[:, 0])
        cm = np.cumsum(p.mass[order]) / p.mass.sum()
        xs = p.x[order, 0]
        last["active"] = step.active
        step.record.extra.update(
            front_q99=float(xs[np.searchsorted(cm, 0.99)]),
            front_q95=float(xs[np.searchsorted(cm, 0.95)]),
        )
        return False

    sim.callbacks.append(mass_front)
    sim.run(**srun.run_kwargs)
    p = sim.particles
    s = {
        "scene": SCENE,
        "parameters": dict(values),
        "metrics": srun.metrics(sim),
        "solver": sim.summary(),
        "wall_time_total": time.perf_counter() - start,
        "history": [r.as_dict() for r in sim.records],
        "version": __version__,
        "deposit": {
            "x0": x0.round(6).tolist(),
            "x": p.x.round(6).tolist(),
            "eps_p": p.eps_p.round(6).tolist(),
            "mass": p.mass.tolist(),
            "active": np.asarray(last["active"]).tolist(),
        },
    }
    s["case"] = {"aspect": a, "N": n, "params": params, "variant": variant}
    # The fidelity settings the scene resolved (None in "parameters" = derived).
    s["model"] = {
        "stabilisation": float(sim.model.stabilisation),
        "volume_correction": float(sim.model.volume_correction),
    }
    lib_end = library_fingerprint()
    s["library"] = {
        **lib_start,
        "source_sha1_end": lib_end["source_sha1"],
        "changed_during_run": lib_end["source_sha1"] != lib_start["source_sha1"],
    }
    s["wall_time_case"] = time.perf_counter() - start
    write_compact_json(path, s)


def write_compact_json(path: Path, obj: dict) -> None:
    """Write JSON without indentation, floats to 7 significant digits (NaN -> null)."""
    from skfem_npfem.io import to_jsonable, write_bytes

    def short(o):
        if isinstance(o, float):
            return float(f"{o:.7g}")
        if isinstance(o, dict):
            return {k: short(v) for k, v in o.items()}
        if isinstance(o, list):
            return [short(v) for v in o]
        return o

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(short(to_jsonable(obj)), separators=(",", ":"))
    write_bytes(path, text.encode())


def launch(
    a: float, n: int, params: dict, path: Path, log: Path, tag: str | None = None
) -> tuple:
    """Run one case in a subprocess (single-threaded BLAS); returns (rc, wall)."""
    env = dict(os.environ)
    root = str(ROOT)
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env.setdefault(var, "1")
    cmd = [
        sys.executable,
        str(Path(__file__).resolve()),
        "--run-case",
        json.dumps(
            {"aspect": a, "N": n, "params": params, "path": str(path), "variant": tag}
        ),
    ]
    t0 = time.perf_counter()
    with open(log, "w") as fh:
        rc = subprocess.call(cmd, env=env, stdout=fh, stderr=subprocess.STDOUT)
    if rc == 0 and log.stat().st_size == 0:
        log.unlink()  # keep logs only when they say something
    return rc, time.perf_counter() - t0


def launch_case(case: tuple) -> int:
    """One case on a Dask worker (skfem_npfem.sweeps.run_tasks): :func:`launch`."""
    from skfem_npfem.errors import NpfemError

    a, n, params, path, tag = case
    log = path.with_suffix(".log")
    rc, _ = launch(a, n, params, path, log, tag)
    if rc:
        raise NpfemError(f"case exited with code {rc}; see {log}")
    return rc


# ---------------------------------------------------------------------------
# Post-processing
# ---------------------------------------------------------------------------


def row_from_summary(s: dict) -> dict:
    """The per-case entry of collapse_validation.json."""
    a = float(s["case"]["aspect"])
    n = int(s["case"]["N"])
    m, sol, p = s["metrics"], s["solver"], s["parameters"]
    # The scene metric: the main body's front when the study began
    # (docs/validation/collapse_validation_before.json), the 99 % mass front since
    # (the main body is then runout_main_body, kept below).
    r = float(m["normalised_runout"])
    lube, laj = lube_law(a), lajeunesse_law(a)
    hist = s.get("history", [])
    L0 = p.get("half_width", p.get("length"))
    late = _late_range(hist, "runout", 0.1 * s["solver"]["time"])
    extra = {}
    if hist and "front_q99" in hist[-1]:
        extra["front_q99_normalised"] = (hist[-1]["front_q99"] - L0) / L0
        extra["front_q95_normalised"] = (hist[-1]["front_q95"] - L0) / L0
    if "deposit" in s:
        extra["wedge"] = wedge_angle(s["deposit"], L0, p["spacing"], 0.01)
        extra["wedge_angle_by_tol"] = {
            str(t): wedge_angle(s["deposit"], L0, p["spacing"], t)["angle_deg"]
            for t in (0.005, 0.01, 0.02, 0.05)
        }
    if "library" in s:
        extra["library"] = s["library"]
    if "model" in s:  # cases run before the stabilisation and the correction
        extra.update(s["model"])
    if m.get("runout_main_body") is not None:
        extra["runout_main_body_normalised"] = (m["runout_main_body"] - L0) / L0
    for key in ("stress_roughness", "stress_roughness_max"):
        if m.get(key) is not None:
            extra[key] = float(m[key])
    return {
        "aspect": a,
        "N": n,
        "variant": s["case"].get("variant"),
        "spacing": p["spacing"],
        "L0": L0,
        "H0": a * L0,
        "particles": int(m["n_particles"]),
        "steps": int(sol["steps"]),
        "end_time": float(sol["time"]),
        "t_end": p["t_end"],
        "at_rest": bool(m["at_rest"]),
        "normalised_runout": r,
        "normalised_runout_tip": (m["runout_tip"] - L0) / L0,
        "final_height_L0": float(m["final_height"]),
        "final_height_H0": float(m["height_ratio"]),
        "collapse_time": m["collapse_time"],
        "collapse_time_normalised": m["collapse_time_normalised"],
        "volume_change": float(m["volume_change"]),
        "mass_change": float(m["mass_change"]),
        "max_kinetic_energy": float(m["max_kinetic_energy"]),
        "n_inactive_final": int(m["n_inactive_final"]),
        "lube": lube,
        "lajeunesse": laj,
        "ratio_lube": r / lube["value"],
        "ratio_lube_range": (
            [r / lube["high"], r / lube["low"]] if lube.get("low") is not None else None
        ),
        "ratio_lajeunesse": r / laj["value"],
        "wall_time": float(s.get("wall_time_case", s.get("wall_time_total", 0.0))),
        "step_time_median": float(sol["step_time_median"]),
        "ipm_iterations_mean": float(sol["ipm_iterations_mean"]),
        "ipm_iterations_max": int(sol["ipm_iterations_max"]),
        "statuses": sol["statuses"],
        "status_counts": _count([h.get("status") for h in hist]),
        "retries": int(sol["retries"]),
        "dt_min": float(min((h["dt"] for h in hist), default=p["dt"])),
        "runout_late_range_normalised": [(v - L0) / L0 for v in late],
        **extra,
    }


def _late_range(hist: list, key: str, window: float) -> list:
    """(min, max) of ``key`` over the last ``window`` seconds of the run."""
    if not hist:
        return [float("nan"), float("nan")]
    t_last = hist[-1]["time"]
    vals = [h[key] for h in hist if h["time"] >= t_last - window - 1e-12]
    return [float(min(vals)), float(max(vals))]


def wedge_angle(dep: dict, L0: float, h: float, tol: float = 0.02) -> dict:
    """Failure-surface angle from the undisturbed region (initial positions).

    Particles that moved less than ``tol * L0`` are undisturbed.  In each row of
    the initial lattice the boundary is the largest initial x of an undisturbed
    particle; rows that are entirely undisturbed or entirely moved carry no
    boundary.  A line x_b = c - y / tan(theta) fitted to the boundary points
    gives the angle theta from horizontal (theory: 45 + phi/2 = 60 deg).
    """
    x0, x = np.asarray(dep["x0"]), np.asarray(dep["x"])
    moved = np.linalg.norm(x - x0, axis=1) > tol * L0
    rows = np.round(x0[:, 1] / h).astype(int)
    ys, xb = [], []
    for r in np.unique(rows):
        sel = rows == r
        still = sel & ~moved
        if still.any() and (sel & moved).any():
            ys.append(float(x0[sel, 1][0]))
            xb.append(float(x0[still, 0].max()))
    top_row = rows == rows.max()
    out = {
        "tol_displacement": tol * L0,
        "rows_used": len(ys),
        "top_undisturbed_fraction": float(np.mean(~moved[top_row])),
        "boundary_y": ys,
        "boundary_x": xb,
        "angle_deg": None,
    }
    if len(ys) >= 3 and np.ptp(xb) > 0:
        slope = np.polyfit(ys, xb, 1)[0]  # dx/dy
        if slope < 0:
            out["angle_deg"] = float(math.degrees(math.atan(-1.0 / slope)))
    return out


def _count(items) -> dict:
    out: dict = {}
    for it in items:
        out[it] = out.get(it, 0) + 1
    return out


def fit_slope_through_origin(a, y) -> float:
    a, y = np.asarray(a, float), np.asarray(y, float)
    return float(a @ y / (a @ a))


def fit_power(a, y) -> tuple[float, float]:
    """Least-squares y = k a^e in log-log; returns (k, e)."""
    la, ly = np.log(np.asarray(a, float)), np.log(np.asarray(y, float))
    e, lk = np.polyfit(la, ly, 1)
    return float(math.exp(lk)), float(e)


def fits(sweep: list[dict], key: str = "normalised_runout") -> dict:
    """Small-a slope, large-a exponent (run-out measure ``key``) and volume gate."""
    sweep = [
        {**r, "normalised_runout": r[key]} for r in sweep if r.get(key) is not None
    ]
    out: dict = {"measure": key}
    small = [r for r in sweep if r["aspect"] <= 1.0]
    large = [r for r in sweep if r["aspect"] >= 2.0]
    if small:
        a = [r["aspect"] for r in small]
        y = [r["normalised_runout"] for r in small]
        k = fit_slope_through_origin(a, y)
        out["small_a"] = {
            "aspects": a,
            "slope_through_origin": k,
            "gate": list(GATE_SLOPE),
            "pass": bool(GATE_SLOPE[0] <= k <= GATE_SLOPE[1]),
            "pointwise_slopes": [yi / ai for ai, yi in zip(a, y, strict=True)],
        }
        if len(small) >= 2:
            out["small_a"]["loglog_power"] = dict(
                zip(("k", "exponent"), fit_power(a, y), strict=True)
            )
    if len(large) >= 2:
        a = [r["aspect"] for r in large]
        y = [r["normalised_runout"] for r in large]
        k, e = fit_power(a, y)
        h = [r["final_height_L0"] for r in large]
        kh, eh = fit_power(a, h)
        out["large_a"] = {
            "aspects": a,
            "prefactor": k,
            "exponent": e,
            "gate": list(GATE_EXPONENT),
            "pass": bool(GATE_EXPONENT[0] <= e <= GATE_EXPONENT[1]),
            "height_prefactor": kh,
            "height_exponent": eh,
        }
        if len(large) >= 3:
            la = np.log(a)
            ly = np.log(y)
            out["large_a"]["local_exponents"] = [
                float((ly[i + 1] - ly[i]) / (la[i + 1] - la[i]))
                for i in range(len(a) - 1)
            ]
    vol = [abs(r["volume_change"]) for r in sweep]
    if vol:
        out["volume"] = {
            "max_abs_volume_change": max(vol),
            "gate": GATE_VOLUME,
            "pass": bool(max(vol) <= GATE_VOLUME),
        }
    return out


def _other_sweeps(ax, other: dict | None, key: str) -> None:
    """The secondary sweeps' ``key`` against a, open squares in colours C3, C4..."""
    for i, (nn, sw) in enumerate((other or {}).items()):
        ax.plot(
            [r["aspect"] for r in sw],
            [r[key] for r in sw],
            "s",
            mfc="none",
            mec=f"C{i + 3}",
            ms=7,
            label=f"N-PFEM (N = {nn})",
        )


def _large_a_fit(ax, la: dict, prefactor: str, exponent: str) -> None:
    """The large-a power fit ``la[prefactor] a^la[exponent]``, dashed."""
    xx = np.geomspace(min(la["aspects"]), max(la["aspects"]), 20)
    ax.plot(
        xx,
        la[prefactor] * xx ** la[exponent],
        "k--",
        lw=1,
        label=f"fit a ≥ 2: {la[prefactor]:.2f}a$^{{{la[exponent]:.2f}}}$",
    )


def plot_aspect(
    sweep: list[dict], fit: dict, path: Path, n_label: str, other: dict | None = None
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    a = np.array([r["aspect"] for r in sweep])
    y = np.array([r["normalised_runout"] for r in sweep])
    h = np.array([r["final_height_L0"] for r in sweep])
    amin, amax = 0.3, 12.0
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.6))

    s1 = np.geomspace(amin, LUBE["small_max"], 50)
    s2 = np.geomspace(LUBE["large_min"], amax, 50)
    tr = np.geomspace(LUBE["small_max"], LUBE["large_min"], 20)
    ax1.plot(s1, lube_linear(s1), "C0-", label="Lube et al. 2005: 1.2a (a ≤ 1.8)")
    ax1.plot(
        s2, lube_power(s2), "C0-.", label="Lube et al. 2005: 1.9a$^{2/3}$ (a ≥ 2.8)"
    )
    ax1.plot(tr, lube_linear(tr), "C0:", lw=1)
    ax1.plot(tr, lube_power(tr), "C0:", lw=1)
    l1 = np.geomspace(amin, LAJEUNESSE["a0"], 50)
    l2 = np.geomspace(LAJEUNESSE["a0"], amax, 50)
    ax1.plot(l1, lajeunesse_linear(l1), "C1-", label="Lajeunesse et al. 2005: 1.8a")
    ax1.plot(
        l2, lajeunesse_power(l2), "C1-.", label="Lajeunesse et al. 2005: 2.3a$^{2/3}$"
    )
    ax1.plot(a, y, "ks", ms=7, label=f"N-PFEM ({n_label}), scene run-out")
    if all("front_q99_normalised" in r for r in sweep):
        ax1.plot(
            a,
            [r["front_q99_normalised"] for r in sweep],
            "x",
            color="0.4",
            ms=7,
            label="N-PFEM, 99 % mass front",
        )
    _other_sweeps(ax1, other, "normalised_runout")
    if "large_a" in fit:
        _large_a_fit(ax1, fit["large_a"], "prefactor", "exponent")
    if "small_a" in fit:
        k = fit["small_a"]["slope_through_origin"]
        xx = np.geomspace(amin, 1.0, 10)
        ax1.plot(xx, k * xx, "k:", lw=1, label=f"fit a ≤ 1: {k:.2f}a")
    ax1.set_xscale("log")
    ax1.set_yscale("log")
    ax1.set_xlim(amin, amax)
    ax1.set_xlabel("aspect ratio a = H0/L0")
    ax1.set_ylabel("(L∞ − L0)/L0")
    ax1.set_title("Run-out")
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=7, loc="lower right")

    x1 = np.geomspace(amin, 1.0, 20)
    x2 = np.geomspace(1.0, amax, 20)
    ax2.plot(x1, x1, "C0-", label="H∞/L0 = a (top undisturbed, a ≲ 1)")
    ax2.plot(x2, x2**0.4, "C0--", label="H∞/L0 ≈ a$^{0.4}$ (large a, approximate)")
    ax2.plot(a, h, "ks", ms=7, label=f"N-PFEM ({n_label})")
    _other_sweeps(ax2, other, "final_height_L0")
    if "large_a" in fit:
        _large_a_fit(ax2, fit["large_a"], "height_prefactor", "height_exponent")
    ax2.set_xscale("log")
    ax2.set_yscale("log")
    ax2.set_xlim(amin, amax)
    ax2.set_xlabel("aspect ratio a = H0/L0")
    ax2.set_ylabel("H∞/L0")
    ax2.set_title("Final height")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=7, loc="lower right")
    fig.suptitle(
        "2D column collapse (plane strain, MC φ = 30°, ψ = 0, floor friction φ)",
        fontsize=10,
    )
    fig.tight_layout()
    save_png(fig, path, dpi=130)


def plot_refinement(ref: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = np.array([r["N"] for r in ref])
    y = np.array([r["normalised_runout"] for r in ref])
    yt = np.array([r["normalised_runout_tip"] for r in ref])
    h = np.array([r["final_height_L0"] for r in ref])
    a = ref[0]["aspect"]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4.2))
    ax1.plot(n, y, "ks-", label="N-PFEM, scene run-out")
    ax1.plot(n, yt, "o:", color="0.5", label="N-PFEM, farthest particle")
    if all("front_q99_normalised" in r for r in ref):
        ax1.plot(
            n,
            [r["front_q99_normalised"] for r in ref],
            "x--",
            color="0.3",
            label="N-PFEM, 99 % mass front",
        )
    ax1.axhspan(1.2 * a, 1.8 * a, color="C0", alpha=0.12, label="1.2a – 1.8a")
    ax1.axhline(1.2 * a, color="C0", lw=1, label=f"Lube 1.2a = {1.2 * a:.2f}")
    ax1.axhline(1.8 * a, color="C1", lw=1, label=f"Lajeunesse 1.8a = {1.8 * a:.2f}")
    ax1.axhline(
        float(lube_power(a)),
        color="C0",
        ls="-.",
        lw=1,
        label=f"Lube 1.9a$^{{2/3}}$ = {float(lube_power(a)):.2f}",
    )
    ax1.set_xlabel("particles across L0 (N = L0/spacing)")
    ax1.set_ylabel("(L∞ − L0)/L0")
    ax1.set_title(f"Run-out, a = {a:g}")
    ax1.grid(True, alpha=0.3)
    ax1.legend(fontsize=7.5)
    ax2.plot(n, h, "ks-", label="N-PFEM")
    ax2.axhline(
        a**0.4,
        color="C0",
        ls="--",
        lw=1,
        label=f"≈ a$^{{0.4}}$ = {a**0.4:.2f} (approx.)",
    )
    ax2.set_xlabel("particles across L0 (N = L0/spacing)")
    ax2.set_ylabel("H∞/L0")
    ax2.set_title(f"Final height, a = {a:g}")
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=7.5)
    fig.tight_layout()
    save_png(fig, path, dpi=130)


def plot_deposits(sweep: list[dict], cases_dir: Path, path: Path) -> None:
    """Final particle clouds of the sweep (x/L0, y/L0), coloured by eps_p."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    deps = []
    for r in sweep:
        s = json.loads(
            (cases_dir / f"{case_name(r['aspect'], r['N'])}.json").read_text()
        )
        deps.append((r, s["deposit"]))
    xmax = max(np.max(np.asarray(d["x"])[:, 0]) / r["L0"] for r, d in deps)
    ytop = max(np.max(np.asarray(d["x"])[:, 1]) / r["L0"] for r, d in deps)
    ytop = min(max(ytop, 1.0) + 0.2, 2.2)
    fig, axes = plt.subplots(
        len(deps),
        1,
        figsize=(11, 0.9 + 0.2 + len(deps) * 11 * (ytop + 0.1) / (xmax + 0.4)),
        sharex=True,
        layout="constrained",
    )
    axes = np.atleast_1d(axes)
    for ax, (r, d) in zip(axes, deps, strict=True):
        L0 = r["L0"]
        x = np.asarray(d["x"]) / L0
        ax.plot([0, 1, 1], [r["aspect"], r["aspect"], 0], color="0.6", lw=0.8)
        sc = ax.scatter(
            x[:, 0],
            x[:, 1],
            c=np.asarray(d["eps_p"]),
            s=4,
            cmap="viridis",
            vmin=0,
            vmax=2,
        )
        ax.axvline(1 + r["normalised_runout"], color="r", lw=0.8, ls="--")
        ax.set_aspect("equal")
        ax.set_xlim(-0.1, xmax + 0.3)
        ax.set_ylim(-0.1, ytop)
        ax.set_ylabel("y/L0")
        ax.text(
            0.99,
            0.85,
            f"a = {r['aspect']:g}, N = {r['N']}",
            transform=ax.transAxes,
            ha="right",
            fontsize=8,
        )
    axes[-1].set_xlabel(
        "x/L0 (red dashed: main-body run-out; grey: initial column, clipped)"
    )
    fig.colorbar(
        sc,
        ax=axes.tolist(),
        label="equivalent plastic strain (clipped at 2)",
        shrink=0.8,
        pad=0.01,
    )
    save_png(fig, path, dpi=120)


def print_tables(sweep: list[dict], ref: list[dict], fit: dict) -> None:
    print("\naspect sweep")
    print(
        f"{'a':>4} {'N':>3} {'part':>5} {'steps':>5} {'runout':>7} {'Lube':>12} "
        f"{'Laj':>6} {'r/Lube':>6} {'r/Laj':>6} {'Hinf/L0':>7} {'Hinf/H0':>7} "
        f"{'t_c':>6} {'t_c*':>5} {'dV':>7} {'wall':>6} {'med':>5} rest"
    )
    for r in [*sweep, None, *ref]:
        if r is None:
            print("refinement")
            continue
        lube = r["lube"]
        lt = (
            f"{lube['low']:.2f}-{lube['high']:.2f}"
            if lube.get("low") is not None
            else f"{lube['value']:.2f}"
        )
        print(
            f"{r['aspect']:>4g} {r['N']:>3d} {r['particles']:>5d} {r['steps']:>5d} "
            f"{r['normalised_runout']:>7.3f} {lt:>12} {r['lajeunesse']['value']:>6.2f} "
            f"{r['ratio_lube']:>6.2f} {r['ratio_lajeunesse']:>6.2f} "
            f"{r['final_height_L0']:>7.3f} {r['final_height_H0']:>7.3f} "
            f"{r['collapse_time']:>6.3f} {r['collapse_time_normalised']:>5.2f} "
            f"{r['volume_change']:>7.3%} {r['wall_time']:>6.0f} "
            f"{r['step_time_median']:>5.2f} {r['at_rest']}"
            f" q99={r.get('front_q99_normalised', float('nan')):.3f}"
            f" tip={r['normalised_runout_tip']:.3f}"
            + " late=[{:.2f}, {:.2f}]".format(*r["runout_late_range_normalised"])
            + (f" wedge={r['wedge']['angle_deg']}" if r.get("wedge") else "")
            + (
                f" top_undisturbed={r['wedge']['top_undisturbed_fraction']:.2f}"
                if r.get("wedge")
                else ""
            )
            + (f" [{r['variant']}]" if r.get("variant") else "")
        )
    print("\nfits:", json.dumps(fit, indent=1))


# ---------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------


def parser() -> argparse.ArgumentParser:
    """The command line of the study."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--aspects", type=floats, default=floats("0.5,1,2,4,8"))
    ap.add_argument(
        "--particles-across",
        type=ints,
        default=ints("12,8,16,22"),
        help="particles across L0 in the aspect sweep (spacing = L0/N); a list "
        "runs one sweep per N, the first is the primary one (tables, fits, gates)",
    )
    ap.add_argument(
        "--refinement",
        type=ints,
        default=ints("8,10,12,14,16,19,22"),
        help="N values of the refinement series (empty: none)",
    )
    ap.add_argument("--refinement-aspect", type=float, default=2.0)
    ap.add_argument("--out", type=Path, default=Path("docs/validation"))
    ap.add_argument(
        "--cases",
        type=Path,
        default=WORK / "collapse_validation" / "cases",
        help="folder of the per-case scene summaries (full records, not committed)",
    )
    ap.add_argument(
        "--jobs", type=int, default=2, help="cases run in parallel (local Dask workers)"
    )
    ap.add_argument(
        "--scheduler",
        default=None,
        help="run the cases on this Dask scheduler (tcp://HOST:PORT) instead",
    )
    ap.add_argument(
        "--t-end-factor",
        type=float,
        default=15.0,
        help="t_end = factor * sqrt(H0/g) (a cap; the at-rest rule stops earlier)",
    )
    ap.add_argument("--rest-fraction", type=float, default=1e-3)
    ap.add_argument("--length", type=float, default=0.2, help="L0, m")
    ap.add_argument("--dt", type=float, default=5e-3, help="time step, s")
    ap.add_argument("--alpha", type=float, default=1.3, help="alpha-shape factor")
    ap.add_argument(
        "--floor-friction", type=float, default=None, help="deg (default phi)"
    )
    ap.add_argument(
        "--threads",
        type=int,
        default=None,
        help="solver threads per case (default: 1 if jobs > 1, else 0 = automatic)",
    )
    ap.add_argument(
        "--max-particles",
        type=int,
        default=1500,
        help="refuse sweep cases above this many particles",
    )
    ap.add_argument(
        "--variants",
        default=DEFAULT_VARIANTS,
        help="sensitivity runs at the refinement aspect and the primary N, "
        "';'-separated 'name=value[,name=value]' scene overrides, e.g. "
        "'dt=0.0025;alpha=1.6;E=1e8;floor_friction=40'",
    )
    ap.add_argument("--force", action="store_true", help="rerun existing cases")
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--run-case", help=argparse.SUPPRESS)
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    return ap


def _variants(text: str) -> dict[str, dict]:
    """``--variants``: tag -> scene overrides (';'-separated 'name=value,...')."""
    variants: dict[str, dict] = {}
    for spec in filter(None, (v.strip() for v in text.split(";"))):
        over = {}
        for item in spec.split(","):
            k, v = item.split("=", 1)
            over[k.strip()] = float(v)
        variants[spec.replace(",", "_")] = over
    return variants


def _particles(a: float, n: int) -> int:
    """Particles of the column a = H0/L0 with N across L0 (the lattice)."""
    return (n + 1) * (round(a * n) + 1)


def wanted_cases(args, ap) -> tuple[dict[tuple[float, int], dict], list[str]]:
    """(a, N) -> parameters of the sweeps and the refinement; skipped case names."""
    n_sweeps = args.particles_across
    n0 = n_sweeps[0]
    wanted: dict[tuple[float, int], dict] = {}
    skipped = []
    for nn in n_sweeps:
        for a in args.aspects:
            if nn != n0 and _particles(a, nn) > args.max_particles:
                skipped.append(case_name(a, nn))  # secondary sweeps: skip, say so
                continue
            wanted[(a, nn)] = case_params(a, nn, args)
    if skipped:
        print("skipped (above --max-particles):", ", ".join(skipped))
    for n in args.refinement:
        wanted[(args.refinement_aspect, n)] = case_params(
            args.refinement_aspect, n, args
        )
    for a, n in wanted:
        npart = _particles(a, n)
        if a in args.aspects and n == n0 and npart > args.max_particles:
            ap.error(f"a = {a:g}, N = {n}: {npart} particles > --max-particles")
    return wanted, skipped


def _up_to_date(path: Path, params: dict) -> bool:
    """True if the stored case at ``path`` ran with ``params`` (threads aside)."""
    old = json.loads(path.read_text())
    return all(
        old["case"]["params"].get(k) == v for k, v in params.items() if k != "threads"
    )


def cases_to_run(
    args, wanted: dict, variants: dict, cases_dir: Path
) -> list[tuple[float, int, dict, Path, str | None]]:
    """The cases to (re)run, largest first: (a, N, params, path, variant)."""
    todo = []
    for (a, n), params in wanted.items():
        path = cases_dir / f"{case_name(a, n)}.json"
        if path.exists() and not args.force:
            if args.plot_only or _up_to_date(path, params):
                continue
        if args.plot_only:
            print(f"missing case {case_name(a, n)} (skipped, --plot-only)")
            continue
        todo.append((a, n, params, path, None))
    a, n = args.refinement_aspect, args.particles_across[0]
    for tag, over in variants.items():
        params = {**case_params(a, n, args), **over}
        path = cases_dir / f"{case_name(a, n)}_{tag}.json"
        if path.exists() and not args.force:
            if args.plot_only or _up_to_date(path, params):
                continue
        if not args.plot_only:
            todo.append((a, n, params, path, tag))
    # Largest first (load balance).
    todo.sort(key=lambda c: -_particles(c[0], c[1]) * math.sqrt(c[0]))
    return todo


def run_all(todo: list, args, cases_dir: Path) -> float:
    """Run ``todo`` on Dask (local --jobs workers or --scheduler); wall time."""
    t0 = time.perf_counter()
    if todo:  # on Dask: a local cluster of --jobs workers or --scheduler
        from skfem_npfem.sweeps import run_tasks

        outcomes = run_tasks(
            launch_case,
            {c[3].stem: (c,) for c in todo},
            workers=None if args.scheduler else max(1, args.jobs),
            scheduler=args.scheduler,
        )
        if not all(o.ok for o in outcomes.values()):
            print("some cases failed; see the logs in", cases_dir)
    return time.perf_counter() - t0


def _fits_of(sweep: list[dict]) -> tuple[dict, dict]:
    """Fits of the primary run-out measure and of the alternative ones."""
    alt = {k: fits(sweep, k) for k in ("front_q99_normalised", "normalised_runout_tip")}
    return fits(sweep), alt


def collect(args, wanted: dict, variants: dict, cases_dir: Path) -> dict:
    """Rows of the stored cases: sweeps by N, refinement, variants, fits."""
    n0 = args.particles_across[0]
    rows = {}
    for a, n in wanted:
        path = cases_dir / f"{case_name(a, n)}.json"
        if path.exists():
            rows[(a, n)] = row_from_summary(json.loads(path.read_text()))
    sweeps = {
        nn: [rows[(a, nn)] for a in sorted(args.aspects) if (a, nn) in rows]
        for nn in args.particles_across
    }
    ref = [
        rows[(args.refinement_aspect, n)]
        for n in sorted(args.refinement)
        if (args.refinement_aspect, n) in rows
    ]
    var_rows = []
    for tag in variants:
        path = cases_dir / f"{case_name(args.refinement_aspect, n0)}_{tag}.json"
        if path.exists():
            var_rows.append(row_from_summary(json.loads(path.read_text())))
    fit, fit_alt = _fits_of(sweeps[n0])
    other = {}
    for nn, sw in sweeps.items():
        if nn != n0:
            f, f_alt = _fits_of(sw)
            other[str(nn)] = {"sweep": sw, "fits": f, "fits_alternative": f_alt}
    return {
        "rows": list(rows.values()) + var_rows,
        "sweep": sweeps[n0],
        "refinement": ref,
        "variants": var_rows,
        "fits": fit,
        "fits_alternative_measures": fit_alt,
        "other_sweeps": other,
    }


def setup(args) -> dict:
    """The ``setup`` entry of collapse_validation.json."""
    return {
        "phi_deg": 30.0,
        "psi_deg": 0.0,
        "c": 0.0,
        "floor_friction_deg": args.floor_friction
        if args.floor_friction is not None
        else 30.0,
        "E": 1.0e7,
        "nu": 0.3,
        "rho": 1800.0,
        "K0": 0.5,
        "dt": args.dt,
        "alpha": args.alpha,
        "theta1": 1.0,
        "theta2": 1.0,
        "L0": args.length,
        "plane_strain": True,
        "symmetric_half_column_smooth_wall": True,
        "rest_fraction": args.rest_fraction,
        "t_end_factor": args.t_end_factor,
        "particles_across_sweep": args.particles_across[0],
        "refinement_aspect": args.refinement_aspect,
    }


def record(args, got: dict, skipped: list[str], wall_all: float) -> dict:
    """collapse_validation.json: setup, laws, rows, fits and the library versions."""
    all_rows = got["rows"]
    libs = sorted({(r.get("library") or {}).get("source_sha1", "?") for r in all_rows})
    return {
        "benchmark": "2D column collapse against the experimental laws",
        "scene": SCENE,
        "setup": setup(args),
        "laws": {
            "lube_2005": "1.2a for a <= 1.8; 1.9a^(2/3) for a >= 2.8 "
            "(transition between)",
            "lajeunesse_2005": "1.8a; 2.3a^(2/3) (a0 ~ 3)",
            "final_height": "H_inf/L0 = a for a <~ 1; ~ a^0.4 for large a "
            "[approximate]",
        },
        "sweep": got["sweep"],
        "refinement": got["refinement"],
        "fits": got["fits"],
        "fits_alternative_measures": got["fits_alternative_measures"],
        "other_sweeps": got["other_sweeps"],
        "skipped_above_max_particles": skipped,
        "library_versions": libs,
        "library_changed_during_a_case": [
            case_name(r["aspect"], r["N"])
            + (f"_{r['variant']}" if r.get("variant") else "")
            for r in all_rows
            if (r.get("library") or {}).get("changed_during_run")
        ],
        "variants": got["variants"],
        "wall_time_this_invocation": wall_all,
    }


def write_figures(result: dict, out: Path, cases_dir: Path, n0: int) -> None:
    """runout_vs_aspect.png, refinement_a2.png and deposits.png under ``out``."""
    sweep, ref = result["sweep"], result["refinement"]
    if sweep:
        plot_aspect(
            sweep,
            result["fits"],
            out / "runout_vs_aspect.png",
            f"N = {n0} across L0",
            {nn: v["sweep"] for nn, v in result["other_sweeps"].items()},
        )
    if len(ref) >= 2:
        plot_refinement(ref, out / "refinement_a2.png")
    if any(
        "deposit"
        in json.loads(
            (cases_dir / f"{case_name(r['aspect'], r['N'])}.json").read_text()
        )
        for r in sweep[:1]
    ):
        plot_deposits(sweep, cases_dir, out / "deposits.png")


def print_summary(result: dict, refinement_aspect: float, n0: int) -> None:
    """The tables, the alternative fits and the library versions, printed."""
    print_tables(result["sweep"], result["refinement"], result["fits"])
    print(
        "alternative measures:",
        json.dumps(
            {
                k: {kk: v.get(kk) for kk in ("small_a", "large_a")}
                for k, v in result["fits_alternative_measures"].items()
            },
            indent=1,
        ),
    )
    print(
        "library versions:",
        result["library_versions"],
        result["library_changed_during_a_case"],
    )
    for nn, v in result["other_sweeps"].items():
        print(f"\nsweep N = {nn}")
        print_tables(v["sweep"], [], v["fits"])
    if result["variants"]:
        print(f"\nvariants (a = {refinement_aspect:g}, N = {n0})")
        print_tables(result["variants"], [], {})


# ---------------------------------------------------------------------------
# The tables of the docs pages, rendered from the committed JSON (--tables).

docs_tables = benchmark("_tables")
TABLES: docs_tables.Tables = {}
docs_table = docs_tables.registry(TABLES)


#: The record before the stabilisation (particle masses, beta = 0), compact:
#: the summary rows of the study, without its per-case records.
COLLAPSE = "docs/validation/collapse_validation_before.json"


#: The study with today's defaults (stabilisation beta = 30, volume
#: correction kappa = 0.05), as the study writes it.
COLLAPSE_NOW = "docs/validation/collapse_validation.json"


def _measures(path: str) -> tuple[str, str, str]:
    """Labels of the primary and the second run-out measure, and the second's key.

    The scene's run-out was the main body's front when COLLAPSE was measured
    and is the 99 % mass front since; the other one is the second measure.
    """
    if path == COLLAPSE:
        return "main body", "99 % mass front", "front_q99_normalised"
    return "99 % mass front (scene)", "main body", "runout_main_body_normalised"


def _lube(r: dict) -> tuple[str, str]:
    lube = r["lube"]
    if lube.get("low") is not None and lube.get("high") is not None:
        law = f"{lube['low']:.2f}–{lube['high']:.2f}"
        lo, hi = r["ratio_lube_range"]
        return law, f"{lo:.2f}–{hi:.2f}"
    return f"{lube['value']:.2f}", f"{r['ratio_lube']:.2f}"


@docs_table(COLLAPSE)
def collapse_sweep(path: str = COLLAPSE) -> str:
    """The primary aspect-ratio sweep against the experimental laws."""
    first, second, key = _measures(path)

    def rough(r: dict) -> list[str]:  # measured since the stabilisation
        if path == COLLAPSE:
            return []
        return [
            docs_tables.num(r.get("stress_roughness_max")),
            docs_tables.num(r.get("stress_roughness")),
        ]

    out = []
    for r in docs_tables.load(path)["sweep"]:
        law, ratio = _lube(r)
        out.append(
            [
                f"{r['aspect']:g}",
                r["N"],
                docs_tables.count(r["particles"]),
                r["steps"],
                f"**{docs_tables.num(r['normalised_runout'])}**",
                docs_tables.num(r.get(key)),
                docs_tables.num(r["normalised_runout_tip"]),
                law,
                docs_tables.num(r["lajeunesse"]["value"], 2),
                ratio,
                docs_tables.num(r["ratio_lajeunesse"], 2),
                docs_tables.num(r["final_height_L0"]),
                docs_tables.num(r["final_height_H0"]),
                docs_tables.num(r["collapse_time"]),
                docs_tables.num(r["collapse_time_normalised"], 2),
                docs_tables.pct(r["volume_change"]),
                f"{r['wall_time']:.0f}",
                docs_tables.num(r["step_time_median"], 2),
                *rough(r),
            ]
        )
    return docs_tables.md(
        [
            "a",
            "N",
            "particles",
            "steps",
            f"(L∞−L0)/L0 {first}",
            second,
            "farthest particle",
            "Lube law",
            "Lajeunesse law",
            "ratio to Lube",
            "ratio to Lajeunesse",
            "H∞/L0",
            "H∞/H0",
            "t_c (s)",
            "t_c/√(H0/g)",
            "mesh-area change",
            "wall (s)",
            "median s/step",
            *([] if path == COLLAPSE else ["R max", "R at rest"]),
        ],
        out,
    )


@docs_table(COLLAPSE)
def collapse_other_resolutions(path: str = COLLAPSE) -> str:
    """The sweeps at the other resolutions (a = 2 is the refinement table)."""
    first, second, key = _measures(path)
    data = docs_tables.load(path)
    rows = [r for s in data["other_sweeps"].values() for r in s["sweep"]]
    rows.sort(key=lambda r: (r["aspect"], r["N"]))
    out, done2 = [], False
    for r in rows:
        if r["aspect"] == 2:
            if not done2:
                ns = sorted(int(k) for k in data["other_sweeps"])
                ns = " / ".join(str(n) for n in ns)
                out.append(["2", ns, "see refinement", "", "", "", "", ""])
                done2 = True
            continue
        out.append(
            [
                f"{r['aspect']:g}",
                r["N"],
                docs_tables.count(r["particles"]),
                docs_tables.num(r["normalised_runout"]),
                docs_tables.num(r.get(key)),
                docs_tables.num(r["normalised_runout_tip"]),
                docs_tables.num(r["final_height_L0"]),
                docs_tables.pct(r["volume_change"]),
            ]
        )
    return docs_tables.md(
        [
            "a",
            "N",
            "particles",
            first,
            second,
            "farthest particle",
            "H∞/L0",
            "mesh-area change",
        ],
        out,
    )


@docs_table(COLLAPSE)
def collapse_refinement(path: str = COLLAPSE) -> str:
    """The refinement series at a = 2."""
    first = _measures(path)[0]
    out = []
    for r in docs_tables.load(path)["refinement"]:
        lo, hi = r["runout_late_range_normalised"]
        out.append(
            [
                r["N"],
                docs_tables.num(1e3 * r["spacing"], 2),
                docs_tables.count(r["particles"]),
                r["steps"],
                docs_tables.num(r["normalised_runout"]),
                f"{lo:.2f}–{hi:.2f}",
                docs_tables.num(r["front_q99_normalised"]),
                docs_tables.num(r["front_q95_normalised"]),
                docs_tables.num(r["normalised_runout_tip"]),
                docs_tables.num(r["final_height_L0"]),
                docs_tables.num(r["collapse_time_normalised"], 2),
                docs_tables.pct(r["volume_change"]),
                f"{r['wall_time']:.0f}",
                docs_tables.num(r["step_time_median"], 2),
            ]
        )
    return docs_tables.md(
        [
            "N",
            "spacing (mm)",
            "particles",
            "steps",
            first,
            f"{first} over the last 10 % of the run",
            "99 % mass front",
            "95 % mass front",
            "farthest particle",
            "H∞/L0",
            "t_c/√(H0/g)",
            "mesh-area change",
            "wall (s)",
            "median s/step",
        ],
        out,
    )


def _variant(label: str) -> str:
    key, _, value = label.partition("=")
    v = float(value)
    names = {
        "dt": f"Δt = {1e3 * v:g} ms",
        "alpha": f"α = {v:g}",
        "E": f"E = {v / 1e6:g} MPa",
        "floor_friction": f"floor friction {v:g}°",
        "rest_fraction": f"rest fraction {v:g} (run longer)",
    }
    return names.get(key, label)


@docs_table(COLLAPSE)
def collapse_sensitivity(path: str = COLLAPSE) -> str:
    """The N = 12, a = 2 case against its variants."""
    first, second, key = _measures(path)
    data = docs_tables.load(path)
    base = next(r for r in data["sweep"] if r["aspect"] == 2)
    s = data["setup"]
    label = (
        f"baseline (Δt = {1e3 * s['dt']:g} ms, α = {s['alpha']:g}, "
        f"E = {s['E'] / 1e6:g} MPa, floor {s['floor_friction_deg']:g}°)"
    )
    out = []
    variants = [(_variant(v["variant"]), v) for v in data["variants"]]
    for name, r in [(label, base), *variants]:
        out.append(
            [
                name,
                r["steps"],
                docs_tables.num(r["normalised_runout"]),
                docs_tables.num(r.get(key)),
                docs_tables.num(r["normalised_runout_tip"]),
                docs_tables.num(r["final_height_L0"]),
                docs_tables.pct(r["volume_change"]),
                docs_tables.statuses(r["status_counts"]),
            ]
        )
    return docs_tables.md(
        [
            "variant",
            "steps",
            first,
            second,
            "farthest particle",
            "H∞/L0",
            "mesh-area change",
            "statuses",
        ],
        out,
    )


def _fit_row(label: str, measure: str, fit: dict | None, primary: bool) -> list[str]:
    def gate(ok: bool) -> str:
        return "pass" if ok else "**fail**"

    small, large = (fit or {}).get("small_a"), (fit or {}).get("large_a")
    cells = [label, measure]
    if small:
        cells += [
            f"{small['slope_through_origin']:.2f} ({gate(small['pass'])})",
            " / ".join(f"{x:.2f}" for x in small["pointwise_slopes"]),
        ]
    else:
        cells += ["—", "—"]
    if large and len(large["aspects"]) >= 3:
        loc = large.get("local_exponents")
        cells += [
            f"{large['exponent']:.3f} ({gate(large['pass'])})",
            " / ".join(f"{x:.2f}" for x in loc) if loc else "—",
            f"{large['prefactor']:.2f}",
        ]
    elif large:
        only = ", ".join(f"{a:g}" for a in large["aspects"])
        cells += [
            f"{large['exponent']:.2f} from a = {only} only ({gate(large['pass'])})",
            "—",
            f"{large['prefactor']:.2f}",
        ]
    else:
        cells += ["— (too few aspect ratios)", "—", "—"]
    if primary:
        cells = [f"**{c}**" if i < 2 or "pass" in c else c for i, c in enumerate(cells)]
    return cells


@docs_table(COLLAPSE)
def collapse_fits(path: str = COLLAPSE) -> str:
    """Small-a slope and large-a exponent per resolution and run-out measure."""
    data = docs_tables.load(path)
    n0 = data["setup"]["particles_across_sweep"]
    sweeps = [(n0, data["fits"], data["fits_alternative_measures"])]
    for n, s in sorted(data["other_sweeps"].items(), key=lambda kv: int(kv[0])):
        sweeps.append((int(n), s["fits"], s.get("fits_alternative", {})))
    out = []
    for n, fits, alt in sweeps:
        out.append(_fit_row(f"N = {n}", _measures(path)[0], fits, n == n0))
        for key, measure in (
            ("front_q99_normalised", "99 % mass front"),
            ("normalised_runout_tip", "farthest particle"),
        ):
            if key in alt:
                out.append(_fit_row(f"N = {n}", measure, alt[key], False))
    return docs_tables.md(
        [
            "sweep",
            "measure",
            "small-a slope (gate 0.90–2.25)",
            "point slopes a = 0.5 / 1",
            "large-a exponent, a = 2–8 (gate 0.55–0.85)",
            "local exponent 2→4 / 4→8",
            "prefactor",
        ],
        out,
    )


# The rerun with today's defaults: the same tables from COLLAPSE_NOW (named
# collapse-now-sweep, ...), and what changed against COLLAPSE.
for _builder in (
    collapse_sweep,
    collapse_other_resolutions,
    collapse_refinement,
    collapse_sensitivity,
    collapse_fits,
):
    _name = _builder.__name__.replace("collapse_", "collapse-now-").replace("_", "-")
    _rel = f"docs/validation/{_name}.inc"
    TABLES[_rel] = (functools.partial(_builder, COLLAPSE_NOW), (COLLAPSE_NOW,))


def _all_rows(data: dict) -> dict[tuple[float, int, str | None], dict]:
    """Every case of a collapse study by (aspect, N, variant)."""
    rows = list(data["sweep"]) + list(data["refinement"]) + list(data["variants"])
    rows += [r for s in data["other_sweeps"].values() for r in s["sweep"]]
    return {(r["aspect"], r["N"], r.get("variant")): r for r in rows}


@docs_table(COLLAPSE, COLLAPSE_NOW)
def collapse_before_after() -> str:
    """Each case of the primary sweep and the refinement, before -> now."""
    before, now = (
        _all_rows(docs_tables.load(COLLAPSE)),
        _all_rows(docs_tables.load(COLLAPSE_NOW)),
    )
    keys = sorted(k for k in now if k in before and k[2] is None)

    def pair(a, b, f) -> str:
        return f"{f(a)} → {f(b)}"

    out = []
    for key in keys:
        b, n = before[key], now[key]
        lube = b["lube"]["value"]  # Lube's value at this aspect (1.2a to a = 2.3)
        out.append(
            [
                f"{key[0]:g}",
                key[1],
                docs_tables.count(n["particles"]),
                pair(
                    b["normalised_runout"],
                    n.get("runout_main_body_normalised"),
                    docs_tables.num,
                ),
                pair(
                    b["front_q99_normalised"],
                    n["front_q99_normalised"],
                    docs_tables.num,
                ),
                pair(
                    b["front_q99_normalised"] / lube,
                    n["front_q99_normalised"] / lube,
                    lambda x: docs_tables.num(x, 2),
                ),
                pair(b["final_height_L0"], n["final_height_L0"], docs_tables.num),
                pair(b["volume_change"], n["volume_change"], docs_tables.pct),
                docs_tables.num(n.get("stress_roughness_max")),
                docs_tables.num(n.get("stress_roughness")),
                pair(
                    b["step_time_median"],
                    n["step_time_median"],
                    lambda x: docs_tables.num(x, 3),
                ),
                pair(
                    b["ipm_iterations_mean"],
                    n["ipm_iterations_mean"],
                    lambda x: docs_tables.num(x, 1),
                ),
            ]
        )
    return docs_tables.md(
        [
            "a",
            "N",
            "particles",
            "main body",
            "99 % mass front",
            "99 % front / Lube",
            "H∞/L0",
            "mesh-area change",
            "R max (now)",
            "R at rest (now)",
            "median s/step",
            "IPM it. (mean)",
        ],
        out,
    )


def main(argv=None) -> int:
    ap = parser()
    args = ap.parse_args(argv)
    if args.tables:
        return docs_tables.write(TABLES)
    if args.run_case:
        spec = json.loads(args.run_case)
        run_case(
            spec["aspect"],
            spec["N"],
            spec["params"],
            Path(spec["path"]),
            spec.get("variant"),
        )
        return 0
    if args.threads is None:
        args.threads = 1 if args.jobs > 1 else 0
    out = args.out
    cases_dir = args.cases
    cases_dir.mkdir(parents=True, exist_ok=True)
    n0 = args.particles_across[0]
    wanted, skipped = wanted_cases(args, ap)
    variants = _variants(args.variants)
    todo = cases_to_run(args, wanted, variants, cases_dir)
    wall_all = run_all(todo, args, cases_dir)
    result = record(args, collect(args, wanted, variants, cases_dir), skipped, wall_all)
    from skfem_npfem.io import write_json

    write_json(out / "collapse_validation.json", result)
    write_figures(result, out, cases_dir, n0)
    print_summary(result, args.refinement_aspect, n0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
