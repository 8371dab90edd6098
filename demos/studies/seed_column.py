"""The reference paper's seed column in 3D, in axisymmetry and in plane strain.

The seed case: a cylindrical column r0 = 3.9 cm, h0 = 7.8 cm
(a = 2), rho = 1800 kg/m^3, E = 10 MPa, nu = 0.3, phi = 30 deg, psi = 0, c = 0,
floor friction phi, dt = 2 ms, theta1 = theta2 = 1, released at t = 0 and run
to t_bar = t / sqrt(h0/g) = 3 and on to rest (the scene's at-rest rule).  The
cases are ``column-collapse`` scene runs:

* ``3d-18``: 3D quarter cylinder at the seed's resolution (spacing r0/18,
  10 027 particles; the paper's mesh has 10 759 nodes);
* ``3d-12``: the same, coarser (r0/12, 3 075 particles);
* ``axi-12``, ``axi-18``, ``axi-36``: axisymmetric, at the spacings of the 3D
  runs and one finer;
* ``plane-18``: plane strain of the same section (half width r0, height h0,
  spacing r0/18, Mohr-Coulomb), for contrast;
* not run by default: ``3d-18-fast`` (the tolerance lever alone, at the
  paper's dt), ``3d-18-fast-dt4``, ``3d-12-fast-dt4``,
  ``axi-12-fast-dt4``, ``axi-18-fast-dt4``, the speed levers (solver preset
  ``accuracy=fast`` and dt = 4 ms); ``axi-12-stab``, ``axi-18-stab``,
  ``3d-12-stab`` and ``3d-12-stab-fast-dt4``, the cases with the stress
  stabilisation (``stabilisation=30``); ``3d-12-fast-dt4-vc`` and
  ``3d-12-stab-fast-dt4-vc``, the same with the opt-in volume correction
  (``volume_correction=0.1``).

Every case runs in its own process (its peak memory is its own) and writes its
own folder under ``--work`` (VTU series, checkpoints, ``summary.json``): a
killed or interrupted study continues from the checkpoints when started again,
and finished cases (a ``summary.json`` not marked ``interrupted``) are not run
again.  From the finished cases it writes under ``--out`` (default
``docs/seed_column``):

* ``seed_column.json``: per case the run-out radius and final height
  (normalised, with Lube et al. 2004), the run-out at t_bar = 3, the deposit
  profile, total wall time, time per step, IPM iterations, peak memory, stress
  roughness, statuses and the parameters;
* ``tables.md``: the tables of docs/seed_column.md;
* ``sigma_v.png``: the vertical stress at t_bar = 0, 1, 2, 3 (rows: cases), as
  in the paper's Figure 4: the 3D quarter mirrored about x = 0 and seen on its
  cut y = 0, the 2D sections mirrored about the axis, the floor drawn;
* ``profiles.png``: the deposits h(r) / r0 against r / r0.

Usage (from the repository root)::

    python demos/studies/seed_column.py                      # the six cases above
    python demos/studies/seed_column.py --cases 3d-12,axi-12,axi-18,axi-36,plane-18
    # one more case added to the committed results, its picture apart
    python demos/studies/seed_column.py --cases 3d-18-fast-dt4 --keep \\
        --picture sigma_v_3d.png
    python demos/studies/seed_column.py --quick --out /tmp/q --work /tmp/q  # smoke run

``--quick`` runs every case at a tiny resolution for a few steps (the test of
the default run).  ``--threads`` is passed to the linear solver.

``--partial`` reports cases as their work folders stand, without running or
continuing them: a run interrupted with Ctrl-C or ``kill -INT`` (its
``summary.json`` says ``"interrupted": true``) is reported to the step it
reached, its label says where it was cut off, the run-out "at t_bar = 3" is
left blank if it did not get there, its profile is the particles of its last
checkpoint, and its picture leaves the times it did not reach blank.  The same
command without ``--partial`` continues the run from that checkpoint.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
from _common import ROOT, benchmark
from _reporting import save_png

from skfem_npfem.laws import lube2004_runout
from skfem_npfem.scenes.collapse.geometry import QUARTER_FIXED
from skfem_npfem.scenes.collapse.runs import bare_method

R0, H0, G, RHO = 0.039, 0.078, 9.81, 1800.0
T_SCALE = math.sqrt(H0 / G)
SNAPSHOTS = (0.0, 1.0, 2.0, 3.0)
#: First line of tables.md (docs/seed_column.md includes the file after it).
TABLES_TITLE = "Seed-column study: tables"

#: The cases measured with the paper's bare method pin it
#: (:func:`skfem_npfem.scenes.collapse.runs.bare_method`: no stabilisation, no
#: volume correction, the alpha factor 1.3, in 3D the buried slivers dropped),
#: so that they reproduce their committed rows; a ``-stab`` case pins the
#: full residual, the stabilisation mode of that time.
FULL = {"stabilisation_mode": "full"}

#: Cases measured with the paper's bare method (scene overrides; the
#: cylindrical geometries default to the seed).
_PAPER_CASES: dict[str, dict] = {
    "3d-18": {"geometry": "quarter-cylinder", "spacing": R0 / 18},
    "3d-12": {"geometry": "quarter-cylinder", "spacing": R0 / 12},
    "axi-12": {"geometry": "axisymmetric", "spacing": R0 / 12},
    "axi-18": {"geometry": "axisymmetric", "spacing": R0 / 18},
    "axi-36": {"geometry": "axisymmetric", "spacing": R0 / 36},
    "plane-18": {
        "geometry": "plane-strain",
        "half_width": R0,
        "aspect": H0 / R0,
        "spacing": R0 / 18,
        "dt": 2e-3,
        # Measured before plane strain defaulted to the volume correction.
        "volume_correction": 0.0,
    },
    # The speed levers (solver preset accuracy=fast, tolerances
    # 1e-6 instead of 1e-8, and a 4 ms time step instead of the paper's 2 ms),
    # and their price at r0/12 in 3D and in axisymmetry.
    "3d-18-fast-dt4": {"geometry": "quarter-cylinder", "spacing": R0 / 18,
                       "accuracy": "fast", "dt": 4e-3},
    # The paper's resolution and time step with the tolerance lever only.
    "3d-18-fast": {"geometry": "quarter-cylinder", "spacing": R0 / 18,
                   "accuracy": "fast"},
    "3d-12-fast-dt4": {"geometry": "quarter-cylinder", "spacing": R0 / 12,
                       "accuracy": "fast", "dt": 4e-3},
    "axi-12-fast-dt4": {"geometry": "axisymmetric", "spacing": R0 / 12,
                        "accuracy": "fast", "dt": 4e-3},
    "axi-18-fast-dt4": {"geometry": "axisymmetric", "spacing": R0 / 18,
                        "accuracy": "fast", "dt": 4e-3},
    # Axisymmetric with the stress stabilisation (beta = 30, the
    # plane-strain default; the cylindrical geometries defaulted to 0 then).
    "axi-12-stab": {"geometry": "axisymmetric", "spacing": R0 / 12,
                    "stabilisation": 30.0},
    "axi-18-stab": {"geometry": "axisymmetric", "spacing": R0 / 18,
                    "stabilisation": 30.0},
    # The same in 3D (r0/12), at the paper's dt and with the speed levers.
    "3d-12-stab": {"geometry": "quarter-cylinder", "spacing": R0 / 12,
                   "stabilisation": 30.0},
    "3d-12-stab-fast-dt4": {"geometry": "quarter-cylinder", "spacing": R0 / 12,
                            "stabilisation": 30.0, "accuracy": "fast",
                            "dt": 4e-3},
    # With the opt-in volume correction (kappa = 0.1), without and
    # with the stabilisation, at the speed levers.
    "3d-12-fast-dt4-vc": {"geometry": "quarter-cylinder", "spacing": R0 / 12,
                          "accuracy": "fast", "dt": 4e-3,
                          "volume_correction": 0.1},
    "3d-12-stab-fast-dt4-vc": {"geometry": "quarter-cylinder",
                               "spacing": R0 / 12, "stabilisation": 30.0,
                               "accuracy": "fast", "dt": 4e-3,
                               "volume_correction": 0.1},
}  # fmt: skip
#: Every case: scene overrides.  The ``-default`` cases run the library's
#: current defaults of their geometry (stabilisation, its mode, volume
#: correction and alpha factor from ``CYLINDER_FIDELITY``; buried slivers
#: meshed).


def as_measured(case: dict) -> dict:
    """Scene overrides of a case measured with the paper's bare method: its
    settings pinned (plane strain keeps its own, given in the case)."""
    if case["geometry"] == "plane-strain":
        return case
    bare = bare_method(case["geometry"])
    slivers = {k: bare.pop(k) for k in ("buried_slivers",) if k in bare}
    return {**bare, **FULL, **case} | slivers


CASES: dict[str, dict] = {
    name: as_measured(v) for name, v in _PAPER_CASES.items()
} | {
    # The quarter's default before its speed defaults (QUARTER_FIXED: the
    # uniform lattice, tol 1e-8, the paper's fixed 2 ms), and with two levers.
    "3d-18-fixed": {"geometry": "quarter-cylinder", "spacing": R0 / 18,
                    **QUARTER_FIXED},
    "3d-18-default-fast-dt4": {"geometry": "quarter-cylinder",
                               "spacing": R0 / 18, "accuracy": "fast",
                               "dt": 4e-3, "refine": "none"},
    # Today's default: the three speed levers (QUARTER_SPEED) on.
    "3d-18-default": {"geometry": "quarter-cylinder", "spacing": R0 / 18},
    "3d-12-default": {"geometry": "quarter-cylinder", "spacing": R0 / 12},
    # The three speed levers of docs/performance.md on the default: a graded
    # lattice, the fast preset, steps of up to 6 ms limited to one spacing.
    "3d-18-levers": {"geometry": "quarter-cylinder", "spacing": R0 / 18,
                     "refine": "surface", "accuracy": "fast", "dt": 6e-3,
                     "max_displacement": 1.0},
}  # fmt: skip
#: The cases run when ``--cases`` is not given.
DEFAULT_CASES = ["3d-18", "3d-12", "axi-12", "axi-18", "axi-36", "plane-18"]
LABELS = {
    "3d-18": "3D quarter, r0/18",
    "3d-12": "3D quarter, r0/12",
    "axi-12": "axisymmetric, r0/12",
    "axi-18": "axisymmetric, r0/18",
    "axi-36": "axisymmetric, r0/36",
    "plane-18": "plane strain, r0/18",
    "3d-18-fast-dt4": "3D quarter, r0/18, fast, dt 4 ms",
    "3d-18-fast": "3D quarter, r0/18, fast",
    "3d-18-fixed": "3D quarter, r0/18, stabilised, uniform lattice, dt 2 ms",
    "3d-18-default-fast-dt4": "3D quarter, r0/18, stabilised, uniform, fast, dt 4 ms",
    "3d-18-default": "3D quarter, r0/18, defaults (graded, fast, dt <= 6 ms)",
    "3d-12-default": "3D quarter, r0/12, defaults (graded, fast, dt <= 6 ms)",
    "3d-18-levers": "3D quarter, r0/18, defaults, graded, fast, dt <= 6 ms",
    "3d-12-fast-dt4": "3D quarter, r0/12, fast, dt 4 ms",
    "axi-12-fast-dt4": "axisymmetric, r0/12, fast, dt 4 ms",
    "axi-18-fast-dt4": "axisymmetric, r0/18, fast, dt 4 ms",
    "axi-12-stab": "axisymmetric, r0/12, beta = 30",
    "axi-18-stab": "axisymmetric, r0/18, beta = 30",
    "3d-12-stab": "3D quarter, r0/12, beta = 30",
    "3d-12-stab-fast-dt4": "3D quarter, r0/12, beta = 30, fast, dt 4 ms",
    "3d-12-fast-dt4-vc": "3D quarter, r0/12, fast, dt 4 ms, kappa = 0.1",
    "3d-12-stab-fast-dt4-vc": "3D quarter, r0/12, beta = 30, fast, dt 4 ms, "
    "kappa = 0.1",
}
#: Quick mode: tiny spacings and a few steps (a smoke test of the whole study).
QUICK = {"spacing_divisions": 4, "steps": 4}


def case_overrides(name: str, quick: bool, threads: int) -> dict:
    """Scene overrides of a case (quick: r0/4 and a few steps)."""
    o = dict(CASES[name])
    o.update(output_every=1 if "3d" not in name else 5, checkpoint_every=10)
    if quick:
        o.update(
            spacing=R0 / QUICK["spacing_divisions"],
            t_end=QUICK["steps"] * 2e-3,
            output_every=1,
            rest_fraction=0.0,
        )
    if threads:
        o["threads"] = threads
    return o


def run_case(name: str, work: Path, quick: bool, threads: int) -> dict:
    """Run (or continue, or skip) one case in its own process; its summary."""
    folder = work / name
    summary = folder / "summary.json"
    if summary.exists():
        done = stored_summary(name, work)
        # An interrupted run (Ctrl-C, kill -INT) writes its summary too, with
        # "interrupted": true; it is continued from its checkpoints, not used.
        if not done.get("interrupted"):
            return done
    resume = any(folder.glob("checkpoint_*.npz"))
    argv = [sys.executable, "-m", "skfem_npfem", "run", "column-collapse"]
    argv += ["--out", str(folder), "--summary", str(summary), "--quiet"]
    for k, v in case_overrides(name, quick, threads).items():
        argv += ["--set", f"{k}={v!r}" if isinstance(v, float) else f"{k}={v}"]
    if resume:
        argv.append("--resume")
    print(f"{name}: {'resuming' if resume else 'running'}", flush=True)
    note_start(folder, continued=resume)
    t0 = time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, cwd=ROOT)
    if proc.returncode != 0:
        raise RuntimeError(f"{name} failed:\n{proc.stderr.strip()}")
    print(f"{name}: done in {time.perf_counter() - t0:.0f} s", flush=True)
    return stored_summary(name, work)


# ------------------------------------------------------------- analysis ----
def _radius(x: np.ndarray) -> np.ndarray:
    return x[:, 0] if x.shape[1] == 2 else np.hypot(x[:, 0], x[:, 1])


def deposit_profile(x: np.ndarray, spacing: float) -> dict:
    """Free-surface height h(r): the highest particle per radial bin of 1 spacing."""
    r, z = _radius(x), x[:, -1]
    edges = np.arange(0.0, r.max() + spacing, spacing)
    idx = np.clip(np.digitize(r, edges) - 1, 0, edges.size - 2)
    h = np.full(edges.size - 1, np.nan)
    np.fmax.at(h, idx, z)
    centre = 0.5 * (edges[1:] + edges[:-1])
    keep = np.isfinite(h)
    return {"r": centre[keep].tolist(), "h": h[keep].tolist()}


def load_step(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points (N, d), cells and full-Voigt stresses of one written step."""
    from skfem_npfem.io import read_step

    m = read_step(path)
    cells = np.vstack([c.data for c in m.cells if c.type in ("triangle", "tetra")])
    dim = cells.shape[1] - 1
    return m.points[:, :dim], cells, np.asarray(m.point_data["stress"])


def vtu_roughness(folder: Path) -> list[float]:
    """Stress roughness of every written step (skfem_npfem.metrics)."""
    from skfem_npfem.io import read_pvd
    from skfem_npfem.metrics import stress_roughness

    out = []
    for _, path in read_pvd(folder / "result.pvd")[1:]:
        _, cells, stress = load_step(path)
        out.append(stress_roughness(cells, stress))
    return out


def at_time(history: list[dict], t: float) -> dict:
    """The step record nearest to time ``t``."""
    times = np.array([h["time"] for h in history])
    return history[int(np.argmin(np.abs(times - t)))]


def reached(t_bar: float, time_end: float, dt: float, partial: bool) -> bool:
    """Whether a run got to ``t_bar`` (to within half its last step): a
    finished run did, a run cut off (``partial``) only if it ran that far."""
    return not partial or time_end >= t_bar * T_SCALE - 0.5 * dt


def stored_summary(name: str, work: Path) -> dict:
    """The summary a case's work folder holds (finished or interrupted)."""
    path = work / name / "summary.json"
    if not path.exists():
        raise FileNotFoundError(
            f"{name}: no {path}; --partial reports a run that has written its "
            "summary (a finished run, or one interrupted with Ctrl-C or kill -INT)"
        )
    return json.loads(path.read_text())


def last_positions(summ: dict, folder: Path) -> np.ndarray:
    """Particle positions where the run stands: the checkpoint an interrupted
    run wrote on stopping, else the last written step."""
    from skfem_npfem.io import read_pvd
    from skfem_npfem.io.checkpoints import load_checkpoint

    ckpt = summ.get("checkpoint") if summ.get("interrupted") else None
    if ckpt and Path(ckpt).exists():
        arrays, _ = load_checkpoint(ckpt)
        return np.asarray(arrays["x"])
    return load_step(read_pvd(folder / "result.pvd")[-1][1])[0]


def analyse(name: str, summ: dict, work: Path) -> dict:
    """The study's numbers of one finished (or, marked so, interrupted) case."""

    p, m, hist = summ["parameters"], summ["metrics"], summ["history"]
    solver = summ["solver"]
    geo = p["geometry"]
    r0 = p["radius"] if geo != "plane-strain" else p.get("half_width", p.get("length"))
    h0 = (
        p["height"]
        if geo != "plane-strain"
        else p["aspect"] * p.get("half_width", p.get("length"))
    )
    key = "runout_radius" if geo != "plane-strain" else "runout"
    step_s = [sum(h["timings"].values()) for h in hist]
    t3 = at_time(hist, 3.0 * T_SCALE)
    i3 = hist.index(t3)
    partial = bool(summ.get("interrupted"))
    t_bar_end = solver["time"] / T_SCALE
    # A run cut off before t_bar = 3 has no run-out there (its last step is not).
    shown = [reached(tb, solver["time"], hist[-1]["dt"], partial) for tb in SNAPSHOTS]
    reached_t3 = shown[SNAPSHOTS.index(3.0)]
    last = last_positions(summ, work / name)
    rough = [h.get("stress_roughness") for h in hist]
    rough = [v for v in rough if v is not None and math.isfinite(v)]
    rough_end = m.get("stress_roughness")
    if not rough:  # a scene without the per-step index: from the written steps
        rough = vtu_roughness(work / name)
        rough_end = rough[-1] if rough else None
        rough = [v for v in rough if math.isfinite(v)]
    label = LABELS.get(name, name)
    if partial:
        label += f" (cut off at t_bar = {t_bar_end:.2f})"
    return {
        "label": label,
        "partial": partial,
        "snapshots_reached": shown,
        "geometry": geo,
        "spacing": p["spacing"],
        "n_particles": m["n_particles"],
        "steps": len(hist),
        "time_end": solver["time"],
        "t_bar_end": t_bar_end,
        "at_rest": m["at_rest"],
        "runout": m[key],
        "normalised_runout": m["normalised_runout"],
        "normalised_runout_t3": t3[key] / r0 - 1.0 if reached_t3 else None,
        "t_bar_t3": t3["time"] / T_SCALE if reached_t3 else None,
        "final_height": m["final_height"],
        "height_ratio": m["height_ratio"],
        "reference_runout_lube2004": lube2004_runout(h0 / r0),
        "volume_change": m["volume_change"],
        "mass_change": m["mass_change"],
        "stress_roughness": rough_end,
        "stress_roughness_max": max(rough) if rough else None,
        "phases_s": {
            k: float(sum(h["timings"].get(k, 0.0) for h in hist))
            for k in sorted({k for h in hist for k in h["timings"]})
        },
        "wall_time_s": float(sum(step_s)),
        "wall_time_t3_s": float(sum(step_s[: i3 + 1])) if reached_t3 else None,
        "step_time_median_s": float(np.median(step_s)),
        "step_time_mean_s": float(np.mean(step_s)),
        "ipm_iterations_total": solver["ipm_iterations_total"],
        "ipm_iterations_mean": solver["ipm_iterations_mean"],
        "ipm_iterations_max": solver["ipm_iterations_max"],
        "statuses": solver["statuses"],
        "retries": solver["retries"],
        "peak_memory_mb": solver["peak_memory_mb"],
        "linear_solvers": solver["linear_solvers"],
        "profile": deposit_profile(last, p["spacing"]),
        "r0": r0,
        "h0": h0,
        "measured_on": stored_measured_on(work / name),
    }


def note_start(folder: Path, continued: bool) -> None:
    """Record the date, CPU and load as a run (or a continuation) starts.

    The load is read before the run's own process adds to it; each piece of a
    run continued from its checkpoint adds its own record.
    """
    path = folder / "measured_on.json"
    pieces = json.loads(path.read_text()) if continued and path.exists() else []
    folder.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps([*pieces, measured_on()]))


def stored_measured_on(folder: Path) -> dict:
    """Where and how loaded a case's run was measured: its pieces' records
    (:func:`note_start`), else (a folder older than them) the moment now."""
    path = folder / "measured_on.json"
    if not path.exists():
        return measured_on()
    pieces = json.loads(path.read_text())
    cpus = list(dict.fromkeys(p["cpu"] for p in pieces))
    busy = [p["load"] for p in pieces if p["load"] != "idle"]
    return {
        "date": pieces[0]["date"],
        "cpu": " and ".join(cpus),
        "load": busy[0] if busy else "idle",
    }


def measured_on() -> dict:
    """Date, CPU and load of this measurement (shown beside the wall times)."""
    import datetime
    import os
    import platform

    cpu = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    busy = cores_busy()
    load = busy if busy is not None else os.getloadavg()[0]
    return {
        "date": datetime.date.today().isoformat(),
        "cpu": f"{cpu}, {os.cpu_count()} cores",
        "load": "idle" if load / (os.cpu_count() or 1) < 0.25 else "shared",
    }


def cores_busy(window: float = 0.5) -> float | None:
    """Cores in use over the next ``window`` seconds (the benchmarks' harness
    reads ``/proc/stat``; None without it).  Called while no run of the study
    is going, it is the load of other processes, which the load average would
    mix with the last run's."""
    harness = benchmark("_harness")
    b0, t0 = harness.cpu_busy_s(), time.perf_counter()
    time.sleep(window)
    busy = (harness.cpu_busy_s() - b0) / (time.perf_counter() - t0)
    return None if math.isnan(busy) else busy


# ------------------------------------------------------------- pictures ----
def _section_mesh(pv, points: np.ndarray, cells: np.ndarray, sv: np.ndarray):
    """A pyvista mesh of one result mirrored about x = 0, in the x-z plane (3D:
    the quarter mirrored, a half cylinder whose cut y = 0 faces the camera)."""
    if points.shape[1] == 2:
        p3 = np.column_stack([points[:, 0], np.zeros(len(points)), points[:, 1]])
        kind = pv.CellType.TRIANGLE
    else:
        p3 = points
        kind = pv.CellType.TETRA
    k = cells.shape[1]
    cell_arr = np.hstack([np.full((len(cells), 1), k), cells]).ravel()
    grid = pv.UnstructuredGrid(cell_arr, np.full(len(cells), kind), p3)
    grid.point_data["sv"] = sv / 1e3
    mirror = grid.copy()
    mirror.points[:, 0] *= -1.0
    return grid.merge(mirror)


def render_panels(
    results: dict, work: Path, out: Path, filename: str = "sigma_v.png"
) -> Path | None:
    """sigma_v at t_bar = 0, 1, 2, 3 for every finished case (one PNG)."""
    try:
        from skfem_npfem.viz.render import check_rendering, import_pyvista

        check_rendering()
        pv = import_pyvista()
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except Exception as err:  # pictures are optional
        print(f"no pictures: {err}", flush=True)
        return None
    from skfem_npfem.io import read_pvd

    names = list(results)
    fig, axes = plt.subplots(
        len(names), len(SNAPSHOTS), figsize=(3.6 * len(SNAPSHOTS), 1.5 * len(names)),
        squeeze=False,
    )  # fmt: skip
    lo = -RHO * G * H0 / 1e3
    for i, name in enumerate(names):
        entries = read_pvd(work / name / "result.pvd")
        times = np.array([t for t, _ in entries])
        for j, tb in enumerate(SNAPSHOTS):
            k = int(np.argmin(np.abs(times - tb * T_SCALE)))
            ax = axes[i, j]
            shown = results[name].get("snapshots_reached", [True] * len(SNAPSHOTS))
            if not shown[j]:
                ax.set_axis_off()  # a run cut off before this time
                if i == 0:
                    ax.set_title(f"t/sqrt(h0/g) = {tb:.2f}")
                ax.text(0.5, 0.5, f"not reached\n(cut off at t_bar = "
                        f"{results[name]['t_bar_end']:.2f})", ha="center",
                        va="center", fontsize=8, transform=ax.transAxes)  # fmt: skip
                continue
            points, cells, stress = load_step(entries[k][1])
            sv = stress[:, points.shape[1] - 1]
            mesh = _section_mesh(pv, points, cells, sv)
            pl = pv.Plotter(off_screen=True, window_size=(960, 320))
            pl.add_mesh(mesh, scalars="sv", cmap="viridis", clim=(lo, 0.0),
                        show_scalar_bar=False)  # fmt: skip
            floor = pv.Plane(center=(0, 0.02, -0.0005), direction=(0, 0, 1),
                             i_size=0.36, j_size=0.1)  # fmt: skip
            pl.add_mesh(floor, color="lightgray")
            pl.camera_position = [(0.02, -0.5, 0.12), (0.0, 0.0, 0.037), (0, 0, 1)]
            pl.camera.parallel_projection = True
            pl.camera.parallel_scale = 0.046
            img = pl.screenshot(return_img=True)
            pl.close()
            ax.imshow(img)
            ax.set_xticks([])
            ax.set_yticks([])
            if i == 0:
                ax.set_title(f"t/sqrt(h0/g) = {times[k] / T_SCALE:.2f}")
            if j == 0:
                # Horizontal and wrapped: vertical labels of long case names
                # ran into the next row.
                label = textwrap.fill(results[name]["label"], 24)
                ax.set_ylabel(label, fontsize=8, rotation=0, ha="right",
                              va="center", labelpad=6)  # fmt: skip
    fig.subplots_adjust(left=0.14)
    sm = plt.cm.ScalarMappable(cmap="viridis", norm=plt.Normalize(lo, 0.0))
    fig.colorbar(sm, ax=axes, shrink=0.6, label="sigma_v (kPa)")
    path = out / filename
    save_png(fig, path, dpi=110)
    return path


def plot_profiles(results: dict, out: Path) -> Path | None:
    """Deposit profiles h(r)/r0 against r/r0, with Lube et al. 2004's run-out."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    fig, ax = plt.subplots(figsize=(7, 3.2))
    for res in results.values():
        prof, r0 = res["profile"], res["r0"]
        ax.plot(np.array(prof["r"]) / r0, np.array(prof["h"]) / r0, label=res["label"])
    ref = 1.0 + lube2004_runout(H0 / R0)
    ax.axvline(ref, color="k", ls="--", lw=0.8, label="Lube et al. 2004 run-out")
    ax.set_xlabel("r / r0")
    ax.set_ylabel("h / r0")
    ax.legend(fontsize=7)
    fig.tight_layout()
    path = out / "profiles.png"
    save_png(fig, path, dpi=110)
    return path


# --------------------------------------------------------------- tables ----
def _on(res: dict) -> str:
    """The "measured on" cell: date, CPU and load of the run."""
    on = res.get("measured_on")
    return f"{on['date']}, {on['cpu']}, {on['load']}" if on else "-"


def _num(value: float | None, fmt: str = ".3f") -> str:
    """A table cell: the number, or '-' where a cut-off run has none."""
    return "-" if value is None else format(value, fmt)


def tables(results: dict) -> str:
    """The Markdown tables of docs/seed_column.md (a page of their own, too)."""
    lines = [
        f"# {TABLES_TITLE}",
        "",
        "| case | particles | steps | t/sqrt(h0/g) at end | at rest | (r_inf - r0)/r0 "
        "| at t_bar = 3 | h_inf/r0 | h_inf/h0 | volume change |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for res in results.values():
        lines.append(
            f"| {res['label']} | {res['n_particles']} | {res['steps']} | "
            f"{res['t_bar_end']:.2f} | {res['at_rest']} | "
            f"{res['normalised_runout']:.3f} | {_num(res['normalised_runout_t3'])} | "
            f"{res['final_height']:.3f} | {res['height_ratio']:.3f} | "
            f"{100 * res['volume_change']:+.1f} % |"
        )
    ref = lube2004_runout(H0 / R0)
    lines += ["", f"Lube et al. (2004): (r_inf - r0)/r0 = {ref:.3f} at a = 2.", ""]
    lines += [
        "Wall times compare only between runs measured on the same CPU under the "
        "same load (last column); compare IPM iterations otherwise. The load is "
        "that of other processes as the run (and each continuation of it) "
        "started: idle below a quarter of the cores (rows measured before the "
        "study recorded it: the load average when the study read the run, with "
        "notes added by hand).",
        "",
        "| case | wall time (s) | to t_bar = 3 (s) | s/step (median) | IPM it. "
        "(mean, max) | peak memory (MB) | stress roughness (end, max) | statuses "
        "| measured on |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for res in results.values():
        sr, srm = res["stress_roughness"], res["stress_roughness_max"]
        lines.append(
            f"| {res['label']} | {res['wall_time_s']:.0f} | "
            f"{_num(res['wall_time_t3_s'], '.0f')} | {res['step_time_median_s']:.3g} | "
            f"{res['ipm_iterations_mean']:.1f}, {res['ipm_iterations_max']} | "
            f"{res['peak_memory_mb']:.0f} | "
            f"{'-' if sr is None else f'{sr:.3f}'}, "
            f"{'-' if srm is None else f'{srm:.3f}'} | "
            f"{', '.join(res['statuses'])} | {_on(res)} |"
        )
    phases = sorted({k for res in results.values() for k in res.get("phases_s", {})})
    if phases:
        lines += [
            "",
            "Where the time goes (share of the summed step time, per phase of "
            "the step: `mesh` remeshing and smoothing cells, `setup` building "
            "Clarabel's solver incl. the ordering, `solve` its iterations):",
            "",
            "| case | " + " | ".join(phases) + " |",
            "|---|" + "---|" * len(phases),
        ]
        for res in results.values():
            ph = res.get("phases_s")
            if not ph:
                continue
            total = sum(ph.values()) or 1.0
            cells = " | ".join(f"{100 * ph.get(k, 0.0) / total:.1f} %" for k in phases)
            lines.append(f"| {res['label']} | {cells} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--cases",
        default=",".join(DEFAULT_CASES),
        help=f"comma-separated, from {', '.join(CASES)}",
    )
    ap.add_argument(
        "--keep",
        action="store_true",
        help="keep the other cases of an existing seed_column.json in --out "
        "(tables and profiles show them all; the picture only the cases run)",
    )
    ap.add_argument(
        "--picture",
        default="sigma_v.png",
        help="file name of the sigma_v picture in --out (default sigma_v.png)",
    )
    ap.add_argument("--out", default=str(ROOT / "docs" / "seed_column"))
    ap.add_argument("--work", default=str(ROOT / "out" / "seed_column"))
    ap.add_argument("--quick", action="store_true", help="tiny smoke run")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--no-pictures", action="store_true")
    ap.add_argument(
        "--partial",
        action="store_true",
        help="report the cases as their work folders stand, without running or "
        "continuing them (an interrupted run to the step it reached)",
    )
    args = ap.parse_args(argv)
    names = [c.strip() for c in args.cases.split(",") if c.strip()]
    unknown = [c for c in names if c not in CASES]
    if unknown:
        print(f"error: unknown case(s) {unknown}; choose from {list(CASES)}")
        return 2
    work, out = Path(args.work), Path(args.out)
    work.mkdir(parents=True, exist_ok=True)
    out.mkdir(parents=True, exist_ok=True)
    ran = {}
    for name in names:
        if args.partial:
            try:
                summ = stored_summary(name, work)
            except FileNotFoundError as err:
                print(f"error: {err}")
                return 2
        else:
            summ = run_case(name, work, args.quick, args.threads)
        ran[name] = analyse(name, summ, work)
    results = dict(ran)
    previous = out / "seed_column.json"
    if args.keep and previous.exists():
        old = json.loads(previous.read_text())
        if old.get("quick") != args.quick:
            print("error: --keep mixes a quick study with a full one")
            return 2
        results = {k: ran.get(k, v) for k, v in old["cases"].items()} | ran
    from skfem_npfem.io import write_json

    write_json(previous, {"quick": args.quick, "cases": results})
    (out / "tables.md").write_text(tables(results))
    plot_profiles(results, out)
    if not args.no_pictures:
        render_panels(ran, work, out, args.picture)
    print(tables(results))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
