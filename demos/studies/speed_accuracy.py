#!/usr/bin/env python
"""The speed-accuracy trade: error against wall time for every method.

Two problems, each over particle spacings and time steps, each configuration in
its own process on Dask (``_study.run_cases``: the
tasks of :func:`skfem_npfem.sweeps.run_tasks` start ``python -m skfem_npfem
run ...``), recording wall time, peak memory, error and stress roughness:

* **Prandtl footing** (scene ``strip-footing``, Tresca, weightless, smooth,
  run to the detected load plateau): error ``|q/c / (2 + pi) - 1|``.  The
  "time step" of this quasi-static scene is the settlement increment:
  ``steps`` equal increments up to the minimum settlement (growing after it).
  Methods: N-PFEM with the solver presets ``accuracy=high`` (tol 1e-8) and
  ``fast`` (1e-6), FEM-remap P1 and P2.  SPFEM is explicit and dynamic and has
  no quasi-static run.
* **Column collapse** a = 2 (scene ``column-collapse``) to rest: error
  ``|R - R_ref| / R_ref`` of the normalised run-out ``R = (L_inf - L0)/L0``
  against the finest N-PFEM run (``--reference-n`` particles across L0,
  dt = 2.5 ms, accuracy high); the experimental band [1.2 a, 1.8 a] is drawn
  beside.  Methods: N-PFEM high/fast, FEM-remap P1/P2 (patch recovery),
  SPFEM (undamped; ``dt`` is its remeshing interval, the explicit substep is
  0.9 x the stable step of each mesh).  The reference is N-PFEM's own limit:
  the other methods' errors include the difference of their limits (see the
  run-out panel).

For each method the Pareto front (the configurations no other configuration
of that method beats in both wall time and error) is drawn on log-log axes.
The study writes ``speed_accuracy.json`` and ``speed_accuracy.png`` under
``--out`` and the page ``docs/choosing.md`` (``--page``) -- its tables and
recommendations are generated from the JSON (``--page-only`` rebuilds page
and figure from an existing JSON).

Runs live in ``--work`` (default ``out/comparison/speed_accuracy/<mode>``): a
rerun skips finished configurations and continues interrupted ones from their
checkpoints, as long as the library source is the same (after a change of the
package every configuration runs afresh).

Usage (from the repository root)::

    # the full study (109 runs; 46 min on 2 idle vCPUs: run it on a quiet machine)
    python demos/studies/speed_accuracy.py --workers 2
    # a moderate subset (37 runs) and the quick check of the tests
    python demos/studies/speed_accuracy.py --subset --workers 2
    python demos/studies/speed_accuracy.py --quick
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from _common import ROOT
from _reporting import (
    best_within,
    cheapest_within,
    markdown_table,
    pareto_front,
    save_png,
    write_result,
)
from _study import run_cases, study_arguments, study_folders

from skfem_npfem.io import write_bytes
from skfem_npfem.scenes.collapse.params import (
    COLLAPSE_STABILISATION,
    COLLAPSE_VOLUME_CORRECTION,
)

OUT = ROOT / "docs" / "validation" / "comparison"
PAGE = ROOT / "docs" / "choosing.md"
WORK = ROOT / "out" / "comparison" / "speed_accuracy"
PRANDTL = 2.0 + math.pi
ASPECT = 2.0
BAND = (1.2 * ASPECT, 1.8 * ASPECT)

#: Method settings: label -> scene parameters.
SETTINGS = {
    "N-PFEM high": {"method": "npfem", "accuracy": "high"},
    "N-PFEM fast": {"method": "npfem", "accuracy": "fast"},
    "FEM-remap P1": {"method": "fem-remap", "element": "p1", "transfer": "recovery"},
    "FEM-remap P2": {"method": "fem-remap", "element": "p2", "transfer": "recovery"},
    "SPFEM": {"method": "spfem"},
}
STYLE = {
    "N-PFEM high": ("C0", "o"),
    "N-PFEM fast": ("C9", "s"),
    "FEM-remap P1": ("C1", "v"),
    "FEM-remap P2": ("C2", "^"),
    "SPFEM": ("C3", "D"),
}

#: The settings with a quasi-static mode (SPFEM is explicit).
IMPLICIT = [label for label in SETTINGS if label != "SPFEM"]
#: Grids per mode: footing (b/h, steps), collapse (n across L0, dt), reference.
GRIDS = {
    "full": {
        "footing": ([4, 8, 12, 16], [2, 4, 8]),
        "collapse": ([8, 12, 16, 22], [1e-2, 5e-3, 2.5e-3]),
        "reference": (32, 2.5e-3),
        "footing_methods": IMPLICIT,
        "collapse_methods": list(SETTINGS),
    },
    "subset": {
        "footing": ([4, 8], [4, 8]),
        "collapse": ([8, 12], [1e-2, 5e-3]),
        "reference": (16, 5e-3),
        "footing_methods": IMPLICIT,
        "collapse_methods": list(SETTINGS),
    },
    "quick": {
        "footing": ([2], [2]),
        "collapse": ([4], [1e-2]),
        "reference": (6, 1e-2),
        "footing_methods": ["N-PFEM high", "FEM-remap P1"],
        "collapse_methods": ["N-PFEM high", "SPFEM"],
    },
}


def slug(text: str) -> str:
    return text.lower().replace(" ", "-")


def configurations(mode: str) -> dict:
    """name -> (scene, params, description) of every run of the study."""
    grid = GRIDS[mode]
    quick = mode == "quick"
    out = {}
    sizes, steps = grid["footing"]
    for label in grid["footing_methods"]:
        for n in sizes:
            for k in steps:
                params = {
                    "spacing": 1.0 / n,
                    "steps": k,
                    "threads": 1,
                    **SETTINGS[label],
                }
                if quick:
                    params["plateau_tol"] = 0.0
                info = {"problem": "footing", "setting": label, "n": n, "dt": k}
                out[f"footing_{slug(label)}_n{n}_s{k}"] = (
                    "strip-footing",
                    params,
                    info,
                )
    base = {"aspect": ASPECT, "output_every": 10**6, "threads": 1}
    if quick:
        base.update(t_end=0.1, rest_fraction=0.0)
    ns, dts = grid["collapse"]
    for label in grid["collapse_methods"]:
        for n in ns:
            for dt in dts:
                params = {**base, "spacing": 0.2 / n, "dt": dt, **SETTINGS[label]}
                info = {"problem": "collapse", "setting": label, "n": n, "dt": dt}
                out[f"collapse_{slug(label)}_n{n}_dt{dt:g}"] = (
                    "column-collapse",
                    params,
                    info,
                )
    n, dt = grid["reference"]
    params = {**base, "spacing": 0.2 / n, "dt": dt, **SETTINGS["N-PFEM high"]}
    info = {"problem": "reference", "setting": "N-PFEM high", "n": n, "dt": dt}
    out[f"reference_n{n}_dt{dt:g}"] = ("column-collapse", params, info)
    return out


def row(info: dict, s: dict | None) -> dict:
    """One configuration's numbers (None values for a failed run)."""
    r = {**info, "ok": s is not None}
    if s is None:
        return r
    m, sol = s["metrics"], s["solver"]
    r.update(
        wall_time=s["wall_time_total"],
        peak_memory_mb=sol["peak_memory_mb"],
        steps=sol["steps"],
        explicit_steps=m.get("explicit_steps"),
        step_time_median=sol["step_time_median"],
        n_particles=sol["n_particles"],
        roughness=m.get("stress_roughness"),
        roughness_max=m.get("stress_roughness_max"),
    )
    if info["problem"] == "footing":
        r["value"] = m["bearing_factor"]
        r["plateau_reached"] = m["plateau_reached"]
        r["error"] = abs(m["bearing_factor"] / PRANDTL - 1.0)
    else:
        r["value"] = m["normalised_runout"]
        r["final_height"] = m["final_height"]
        r["at_rest"] = m["at_rest"]
    return r


def collect(mode: str, summaries: dict) -> dict:
    confs = configurations(mode)
    rows = {
        name: row(info, summaries.get(name)) for name, (_, _, info) in confs.items()
    }
    ref = next((r for r in rows.values() if r["problem"] == "reference"), None)
    ref_value = ref["value"] if ref and ref["ok"] else None
    for r in rows.values():
        if r["problem"] == "collapse" and r["ok"]:
            r["error"] = (
                abs(r["value"] - ref_value) / abs(ref_value) if ref_value else None
            )
            r["in_band"] = BAND[0] <= r["value"] <= BAND[1]
    result = {
        "mode": mode,
        "grids": GRIDS[mode],
        # N-PFEM's collapse defaults the runs used (the stabilisation changed them).
        "npfem_defaults": NPFEM_DEFAULTS,
        "reference": {
            "footing": PRANDTL,
            "collapse": ref_value,
            "collapse_run": ref,
            "band": list(BAND),
        },
        "rows": rows,
    }
    result["fronts"] = fronts(result)
    return result


def usable(result: dict, problem: str) -> list[tuple[str, dict]]:
    """Finished configurations of a problem with a finite error."""
    return [
        (name, r)
        for name, r in result["rows"].items()
        if r["problem"] == problem
        and r["ok"]
        and r.get("error") is not None
        and math.isfinite(r["error"])
    ]


def fronts(result: dict) -> dict:
    """Per problem and setting: the names on its Pareto front, cheapest first."""
    out = {}
    for problem in ("footing", "collapse"):
        rows = usable(result, problem)
        out[problem] = {}
        for label in SETTINGS:
            mine = [(n, r) for n, r in rows if r["setting"] == label]
            if mine:
                pts = [(r["wall_time"], max(r["error"], 1e-16)) for _, r in mine]
                out[problem][label] = [mine[i][0] for i in pareto_front(pts)]
    return out


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6))
    titles = {
        "footing": "Prandtl footing: |q/c / (2+pi) - 1|",
        "collapse": "collapse a = 2: run-out error vs finest N-PFEM",
    }
    for ax, problem in zip(axes[:2], ("footing", "collapse"), strict=True):
        rows = dict(usable(result, problem))
        for label, names in result["fronts"][problem].items():
            color, marker = STYLE[label]
            mine = [r for r in rows.values() if r["setting"] == label]
            ax.scatter(
                [r["wall_time"] for r in mine],
                [max(r["error"], 1e-6) for r in mine],
                color=color,
                marker=marker,
                alpha=0.45,
                s=22,
            )
            ax.plot(
                [rows[n]["wall_time"] for n in names],
                [max(rows[n]["error"], 1e-6) for n in names],
                color=color,
                marker=marker,
                label=label,
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time per run (s)")
        ax.set_ylabel("relative error")
        ax.set_title(titles[problem], fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    ax = axes[2]
    ax.axhspan(*BAND, color="0.88", label="experiments 1.2a..1.8a")
    if result["reference"]["collapse"] is not None:
        ax.axhline(
            result["reference"]["collapse"], color="k", ls="--", label="finest N-PFEM"
        )
    for label in SETTINGS:
        mine = [
            r
            for r in result["rows"].values()
            if r["problem"] == "collapse" and r["ok"] and r["setting"] == label
        ]
        if mine:
            color, marker = STYLE[label]
            ax.scatter(
                [r["wall_time"] for r in mine],
                [r["value"] for r in mine],
                color=color,
                marker=marker,
                label=label,
                s=22,
            )
    ax.set_xscale("log")
    ax.set_xlabel("wall time per run (s)")
    ax.set_ylabel("(L∞ - L0)/L0")
    ax.set_title("collapse a = 2: run-out", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save_png(fig, path)


# ---------------------------------------------------------------------------
# The docs page (docs/choosing.md), generated from the JSON
# ---------------------------------------------------------------------------

#: N-PFEM collapse defaults recorded with a study (a page made from a study
#: with other defaults says so), taken from the scene's constants.  The volume
#: correction became a plane-strain collapse default after the first record
#: of this study was made, which lacks it.
NPFEM_DEFAULTS = {
    "nodal_mass": "mesh",
    "stabilisation": COLLAPSE_STABILISATION,
    "volume_correction": COLLAPSE_VOLUME_CORRECTION,
}

PAGE_HEAD = """# Choosing a method: N-PFEM, FEM with remapping or the explicit SPFEM

<!-- Generated by demos/studies/speed_accuracy.py from
docs/validation/comparison/speed_accuracy.json: do not edit by hand; rerun
`python demos/studies/speed_accuracy.py --page-only` after changing the generator. -->

Which method and setting reaches an accuracy in the least wall time, and which is
the most accurate within a wall-time budget, on a limit load and on a granular
flow. Every number on this page comes from `demos/studies/speed_accuracy.py`.
"""

METHODS_TEXT = """The methods, each through the same scene (`skfem-npfem run SCENE --set
method=...`):

* **N-PFEM** (`method=npfem`): nodal integration, one cone program per step;
  `accuracy=high` (interior-point tolerance 1e-8) or `fast` (1e-6).
* **FEM-remap** (`method=fem-remap`): the classical PFEM: stresses at the Gauss
  points of P1 or P2 elements, transferred to every new mesh by patch recovery,
  the same cone program ([baselines.md](baselines.md)).
* **SPFEM** (`method=spfem`): nodal integration with explicit central
  differences and a closed-form return mapping, substeps at 0.9 x the stable
  step. It is explicit and dynamic, so the quasi-static footing has no SPFEM run.

Each configuration runs in its own process (so that wall time and peak memory
are its own), on a Dask cluster (`skfem_npfem.sweeps.run_tasks`). `R` is the
stress roughness of the final state ([scenes.md](scenes.md),
`stress_roughness`). Wall times are per run, on the machine and at the load of
the study (the study line under "Results").
"""


def _ints(values) -> str:
    """``[4, 8, 12]`` -> ``4, 8 and 12``."""
    text = [f"{v:g}" for v in values]
    return text[0] if len(text) == 1 else ", ".join(text[:-1]) + " and " + text[-1]


def _cases(result: dict) -> str:
    """The two problems, their references and the grid of the study."""
    grids, ref = result["grids"], result["reference"]
    (fn, fs), (cn, cdt) = grids["footing"], grids["collapse"]
    band = ref.get("band") or list(BAND)
    return (
        "## The cases and their references\n\n"
        "* **Prandtl footing** (scene `strip-footing`: Tresca, weightless soil, "
        "smooth footing, run to the detected load plateau). Reference: "
        f"Prandtl's limit load q/c = 2 + pi = {_fmt(ref['footing'], 5)} (exact, "
        "limit analysis; [verification](verification.md)). Error: "
        "`|q/c / (2 + pi) - 1|` at the plateau. Grid: b/h = "
        f"{_ints(fn)} (footing half-width over element size), {_ints(fs)} equal "
        "settlement increments up to the minimum settlement.\n"
        "* **Column collapse, a = 2** (scene `column-collapse`, to rest). "
        "Reference: the normalised run-out `(L_inf - L0)/L0` of the finest "
        "N-PFEM run (accuracy high, L0/h = "
        f"{grids['reference'][0]}, dt = {grids['reference'][1]:g} s), "
        "N-PFEM's own converged answer; the error is the relative difference "
        "from it. Another method's error also contains the difference between "
        "its converged answer and N-PFEM's, which is why the run-out itself is "
        "shown beside the experimental band, 1.2 a (Lube et al. 2005) to 1.8 a "
        f"(Lajeunesse et al. 2005): [{band[0]:g}, {band[1]:g}] at a = 2. Grid: "
        f"L0/h = {_ints(cn)}, dt = {_ints(cdt)} s.\n\n" + METHODS_TEXT
    )


def _fmt(v, digits: int = 3) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        if not math.isfinite(v):
            return "–"
        return f"{v:.{digits}g}"
    return str(v)


def _setting(r: dict) -> str:
    step = f"{r['dt']} steps" if r["problem"] == "footing" else f"dt {r['dt']:g} s"
    size = f"b/h {r['n']}" if r["problem"] == "footing" else f"L0/h {r['n']}"
    return f"{r['setting']}, {size}, {step}"


def _runs_table(result: dict, problem: str) -> str:
    on_front = {n for names in result["fronts"][problem].values() for n in names}
    rows = []
    for name, r in result["rows"].items():
        if r["problem"] != problem:
            continue
        if not r["ok"]:
            rows.append([r["setting"], r["n"], r["dt"]] + ["failed"] + [None] * 7)
            continue
        explicit = r.get("explicit_steps")
        steps = r["steps"] if explicit is None else f"{r['steps']} ({explicit})"
        rows.append(
            [
                r["setting"],
                r["n"],
                r["dt"],
                r["n_particles"],
                steps,
                _fmt(r["wall_time"]),
                _fmt(r["peak_memory_mb"]),
                _fmt(r["value"], 4),
                _fmt(r.get("error")),
                _fmt(r.get("roughness"), 2),
                "yes" if name in on_front else "",
            ]
        )
    size = "b/h" if problem == "footing" else "L0/h"
    step = "steps to s_min" if problem == "footing" else "dt (s)"
    value = "q/c" if problem == "footing" else "(L∞−L0)/L0"
    head = [
        "setting",
        size,
        step,
        "particles",
        "steps (explicit)",
        "wall (s)",
        "peak memory (MB)",
        value,
        "error",
        "R",
        "Pareto",
    ]
    return markdown_table(head, rows)


def _pick_row(kind: str, limit: float, best: dict, nbest: dict | None):
    """Table row and sentence for one accuracy target or wall-time budget."""
    if kind == "acc":
        nb = _fmt(nbest["wall_time"]) if nbest else "not reached"
        tail = (
            f"N-PFEM needs {nb} s ({_setting(nbest)})"
            if nbest
            else "N-PFEM does not reach it in this study"
        )
        row = [f"{100 * limit:g} %", _setting(best), _fmt(best["wall_time"]), nb]
        note = (
            f"for an error of {100 * limit:g} %, {_setting(best)} takes "
            f"{_fmt(best['wall_time'])} s; {tail}"
        )
        return row, note
    nb = _fmt(nbest["error"]) if nbest else "none that fast"
    tail = f"N-PFEM's best within it is {nb}" if nbest else "no N-PFEM run is that fast"
    row = [f"{limit} s", _setting(best), _fmt(best["error"]), nb]
    note = (
        f"within {limit} s the most accurate run is {_setting(best)} "
        f"(error {_fmt(best['error'])}); {tail}"
    )
    return row, note


def _choices(result: dict, problem: str) -> tuple[str, list[str], list[str]]:
    """Accuracy and budget tables, where N-PFEM loses, and the short advice."""
    rows = usable(result, problem)
    if not rows:
        return "(no finished runs)", [], []
    pts = [(r["wall_time"], r["error"]) for _, r in rows]
    npf = [i for i, (_, r) in enumerate(rows) if r["setting"].startswith("N-PFEM")]
    npts = [pts[i] for i in npf]
    notes: list[str] = []
    lo, hi = min(p[0] for p in pts), max(p[0] for p in pts)
    picks = {
        "acc": (cheapest_within, (0.3, 0.1, 0.03, 0.01, 0.003, 0.001)),
        "budget": (
            best_within,
            [b for b in (1, 3, 10, 30, 100, 300, 1000, 3000) if lo <= b <= 3 * hi],
        ),
    }
    tables: dict[str, list] = {"acc": [], "budget": []}
    for kind, (select, limits) in picks.items():
        for limit in limits:
            i, j = select(pts, limit), select(npts, limit)
            if i is None:
                continue
            best = rows[i][1]
            nbest = rows[npf[j]][1] if j is not None else None
            row, note = _pick_row(kind, limit, best, nbest)
            tables[kind].append(row)
            if not best["setting"].startswith("N-PFEM"):
                notes.append(note)
    acc, budgets = tables["acc"], tables["budget"]
    short = []
    if acc:
        short.append(
            f"for an error up to {acc[0][0]}: {acc[0][1]} ({acc[0][2]} s); for "
            f"the smallest error reached, {acc[-1][0]}: {acc[-1][1]} ({acc[-1][2]} s)"
        )
    if budgets:
        short.append(
            f"with {budgets[0][0]}: {budgets[0][1]} (error {budgets[0][2]}); with "
            f"{budgets[-1][0]}: {budgets[-1][1]} (error {budgets[-1][2]})"
        )
    text = (
        "Cheapest run reaching an error:\n\n"
        + markdown_table(
            ["error at most", "cheapest run", "wall (s)", "cheapest N-PFEM (s)"], acc
        )
        + "\n\nMost accurate run within a wall-time budget:\n\n"
        + markdown_table(
            ["budget", "most accurate run", "error", "best N-PFEM error"], budgets
        )
    )
    return text, notes, short


def _median_by_setting(result: dict, problem: str, value) -> dict:
    """Median of ``value(row)`` over a problem's finished runs, per setting."""
    import statistics

    med = {}
    for label in SETTINGS:
        vals = [
            value(r)
            for r in result["rows"].values()
            if r["problem"] == problem and r["ok"] and r["setting"] == label
        ]
        vals = [v for v in vals if v is not None and math.isfinite(v)]
        if vals:
            med[label] = statistics.median(vals)
    return med


def _roughness_notes(result: dict) -> list[str]:
    """Settings whose final stresses are smoother than N-PFEM's (median R)."""
    out = []
    for problem in ("footing", "collapse"):
        med = _median_by_setting(result, problem, lambda r: r.get("roughness"))
        ref = med.get("N-PFEM high")
        for label, value in med.items():
            if ref is None or label.startswith("N-PFEM") or value >= ref:
                continue
            why = (
                " (its particle stresses are recovered, i.e. patch-averaged, from "
                "the Gauss points)"
                if label.startswith("FEM")
                else ""
            )
            out.append(
                f"{problem}: {label}'s final stresses are smoother than N-PFEM's, "
                f"median R {value:.3g} against {ref:.3g}{why}"
            )
    return out


def _step_cost(result: dict) -> tuple[str, list[str]]:
    """Median wall time per step and particle per setting; where it beats N-PFEM."""
    rows, notes = [], []
    for problem in ("footing", "collapse"):
        med = _median_by_setting(
            result,
            problem,
            lambda r: 1e3 * r["wall_time"] / max(r["steps"], 1) / r["n_particles"],
        )
        ref = med.get("N-PFEM high")
        for label, value in med.items():
            rows.append([problem, label, _fmt(1e3 * value), _fmt(value / ref)])
            if ref and not label.startswith("N-PFEM") and value < ref:
                notes.append(
                    f"{problem}: {label}'s steps are cheaper, {value / ref:.2g} times "
                    "N-PFEM's per particle (whether that pays depends on its error, "
                    "in the tables under Results)"
                )
    head = [
        "problem",
        "setting",
        "wall per step and 1000 particles (ms)",
        "relative to N-PFEM high",
    ]
    return markdown_table(head, rows), notes


def _noise_floor(result: dict) -> str:
    """The spread of N-PFEM's collapse run-out over its runs (resolution noise)."""
    vals = [
        r["value"]
        for r in result["rows"].values()
        if r["problem"] == "collapse" and r["ok"] and r["setting"].startswith("N-PFEM")
    ]
    if len(vals) < 2:
        return ""
    mean = sum(vals) / len(vals)
    spread = (max(vals) - min(vals)) / mean
    return (
        f"N-PFEM's run-out varies by {100 * spread:.2g} % (max - min over mean) "
        f"across its {len(vals)} runs of this study: differences of the collapse "
        "error below that are within the scatter of the run-out itself (the "
        "front of a granular deposit moves by a particle spacing between "
        "resolutions and time steps), not a ranking.\n"
    )


def _defaults_note(recorded: dict) -> str:
    """The page's warning when the study ran with other N-PFEM defaults ('' if not)."""
    if recorded.get("stabilisation") != NPFEM_DEFAULTS["stabilisation"]:
        return (
            "**Measured before N-PFEM's current collapse defaults** (node masses "
            "from the cells and the stress stabilisation, beta = 30: "
            "[validation/stabilisation.md](validation/stabilisation.md)). Its "
            "collapse rows are the unstabilised method: since then its stresses "
            "are smoother (R max 0.36 -> 0.06 at the default resolution) and a "
            "collapse step costs 1.5-2 times more. Rerun the study to update.\n"
        )
    if recorded.get("volume_correction", 0.0) != NPFEM_DEFAULTS["volume_correction"]:
        return (
            "**The N-PFEM collapse rows predate the volume correction** "
            f"(`volume_correction` = {NPFEM_DEFAULTS['volume_correction']:g}, the "
            'plane-strain collapse default since: [theory](theory.md), "Volume '
            'correction"); they ran with none. In the comparison of '
            "[baselines](baselines.md) at L0/h = 16 it moved N-PFEM's run-out from "
            "3.40 to 3.56 and its area change from -12.9 % to -2.9 %, with R max "
            "0.084 -> 0.109. Rerun the study to update.\n"
        )
    return ""


def write_page(result: dict, path: Path | None) -> str:
    """The Markdown of docs/choosing.md from a study's JSON.

    In reference order: the cases and their references, the results (tables
    and the figure), what they mean for a user's choice, the command.
    """
    rows = result["rows"]
    n_ok = sum(r["ok"] for r in rows.values())
    ref = result["reference"]
    parts = [PAGE_HEAD, _cases(result), "## Results\n"]
    note = _defaults_note(result.get("npfem_defaults") or {})
    if note:
        parts.append(note)
    parts.append(
        f"Study: mode `{result['mode']}`, {len(rows)} runs ({n_ok} finished), "
        f"{_fmt(result.get('wall_time'))} s of wall time in all. "
        + (
            "**This page was generated from the reduced study**; the full study "
            "(`python demos/studies/speed_accuracy.py --workers 2`) replaces it. "
            if result["mode"] != "full"
            else ""
        )
        + "The machine is shared: timings are indicative.\n"
    )
    notes, advice = [], []
    for problem, title in (
        ("footing", "Prandtl footing"),
        ("collapse", "Column collapse, a = 2"),
    ):
        text, loses, short = _choices(result, problem)
        notes += [f"{title}: {s}" for s in loses]
        advice += [f"{title}, {s}" for s in short]
        parts.append(f"### {title}\n")
        if problem == "collapse":
            cr = ref.get("collapse_run") or {}
            parts.append(
                f"Reference: N-PFEM high, L0/h = {cr.get('n')}, dt = {cr.get('dt')} "
                f"s: (L∞−L0)/L0 = {_fmt(ref['collapse'], 4)} "
                f"(wall {_fmt(cr.get('wall_time'))} s).\n"
            )
            text = _noise_floor(result) + "\n" + text
        parts.append(text + "\n")
        parts.append("All runs (Pareto: on its setting's front):\n")
        parts.append(_runs_table(result, problem) + "\n")
    notes += _roughness_notes(result)
    cost_table, cost_notes = _step_cost(result)
    notes += cost_notes
    parts.append("### Cost per step\n\n" + cost_table + "\n")
    parts.append(
        "### Figure\n\n![error against wall time per method, with each method's "
        "Pareto front; collapse run-out against the experimental band]"
        "(validation/comparison/speed_accuracy.png)\n"
    )
    pick = ["## What this means for your choice\n", "### Which method to pick\n"]
    pick += [f"* {s}." for s in advice]
    pick.append(
        '\nThe tables under "Results" give every accuracy target and budget; '
        "the runs behind them are listed per problem."
    )
    parts.append("\n".join(pick) + "\n")
    summary = ["### Where N-PFEM does not pay off\n"]
    if notes:
        summary += [f"* {s}." for s in notes]
    else:
        summary.append(
            "In this study N-PFEM was the cheapest run for every error "
            "reached and the most accurate within every budget."
        )
    parts.append("\n".join(summary) + "\n")
    parts.append(
        "## Reproduce\n\n```\npython demos/studies/speed_accuracy.py --workers 2   "
        "# full study, resumable\n```\n\nThe runs live in "
        "`out/comparison/speed_accuracy/` (`--work`); a rerun continues "
        "interrupted runs and reuses finished ones of the same library source. "
        "`--subset` runs a reduced grid; `--page-only` rebuilds this page and "
        "its figure from the committed JSON.\n"
    )
    text = "\n".join(parts)
    if path is not None:
        write_bytes(path, text.encode())
    return text


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    study_arguments(ap, OUT, WORK)
    ap.add_argument("--subset", action="store_true", help="moderate subset")
    ap.add_argument(
        "--page",
        type=Path,
        default=None,
        help=f"generated docs page (default {PAGE}; --quick: none)",
    )
    ap.add_argument(
        "--page-only",
        action="store_true",
        help="rebuild figure and page from the existing JSON",
    )
    args = ap.parse_args(argv)
    if args.quick and args.subset:
        ap.error("--quick and --subset exclude each other")
    name = "quick" if args.quick else "subset" if args.subset else "full"
    work, out, workers = study_folders(args, OUT, name)
    page = args.page or (None if args.quick else PAGE)
    if args.page_only:
        import json

        result = json.loads((out / "speed_accuracy.json").read_text())
    else:
        start = time.perf_counter()
        confs = configurations(name)
        summaries = run_cases(
            {k: (c[0], c[1]) for k, c in confs.items()},
            work,
            workers=workers,
            scheduler=args.scheduler,
        )
        result = collect(name, summaries)
        result["wall_time"] = time.perf_counter() - start
        write_result(out / "speed_accuracy.json", result)
    plot(result, out / "speed_accuracy.png")
    text = write_page(result, None)
    if page is not None:
        write_bytes(page, text.encode())
    print(text)
    return result


if __name__ == "__main__":
    main()
