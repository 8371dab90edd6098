"""The comparison studies: one process per configuration, and the demos reduced.

References: a configuration run in its own process (on Dask) gives the same
summary as the same scene run here (same code, same numbers to round-off);
undamped sudden loading of an elastic column doubles the static settlement
(dynamic amplification factor 2, SPFEM without damping) while the implicit
backward-Euler methods settle to the static value; the Prandtl factor 2 + pi;
exact mass conservation.  The full demos (docs/validation/comparison) run
under ``-m slow``.
"""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest

from skfem_npfem.baseline.study import run_cases
from skfem_npfem.scenes import run_scene

ROOT = Path(__file__).resolve().parent.parent


def load(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "demos" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_each_case_in_its_own_process_on_dask(tmp_path):
    params = {"spacing": 0.5, "method": "fem-remap", "element": "p2", "nu": 0.25}
    cases = {"p2": ("elastic-column", params)}
    first = run_cases(cases, tmp_path, workers=1, progress=False)["p2"]
    here = run_scene("elastic-column", params)
    for key in ("sigma_v_rel_l2", "settlement", "base_sigma_v"):
        assert first["metrics"][key] == pytest.approx(here["metrics"][key], rel=1e-12)
    assert first["solver"]["peak_memory_mb"] > 0
    assert (tmp_path / "p2" / "result.pvd").is_file()
    # A rerun finds the finished summary and starts nothing.
    stamp = (tmp_path / "p2" / "summary.json").stat().st_mtime_ns
    again = run_cases(cases, tmp_path, workers=1, progress=False)["p2"]
    assert again == first
    assert (tmp_path / "p2" / "summary.json").stat().st_mtime_ns == stamp
    # A failing case is reported as None with its log.
    bad = run_cases(
        {"bad": ("elastic-column", {"method": "spfem"})},
        tmp_path,
        workers=1,
        progress=False,
    )
    assert bad["bad"] is None
    assert "spfem" in (tmp_path / "bad" / "log.txt").read_text()


def test_oscillation_demo_quick(tmp_path):
    res = load("compare_oscillation").main(["--quick", "--work", str(tmp_path)])
    col = res["column"]
    # Undamped SPFEM: the top swings to twice the static settlement (measured
    # 2.00); backward Euler (N-PFEM, FEM) settles near the static value.
    sp = np.array([v for v in col["SPFEM"]["settlement"] if v is not None])
    assert sp.max() / col["SPFEM"]["settlement_exact"] == pytest.approx(2.0, rel=0.05)
    for label in ("N-PFEM", "FEM-remap P1", "FEM-remap P2"):
        end = col[label]["settlement"][-1] / col[label]["settlement_exact"]
        assert abs(end - 1) < 0.05, label
    for label, entry in res["collapse"].items():
        assert entry["steps"] == 50, label  # t_end 0.25 s in steps of 5 ms
        assert res["pictures_t_bar"][label][0] == pytest.approx(1.0, abs=0.03)
    assert (tmp_path / "quick" / "oscillation_sigma_v.png").is_file()


def test_results_demo_quick(tmp_path):
    res = load("compare_results").main(["--quick", "--work", str(tmp_path)])
    tresca = res["footing"]["Tresca"]
    assert tresca["reference"] == pytest.approx(2 + math.pi)
    m = tresca["methods"]
    # b/h = 4: N-PFEM +2.0 %, FEM P2 +6.0 % (from above), FEM P1 locks.
    assert 0 < m["N-PFEM"]["relative_error"] < 0.03
    assert 0 < m["FEM-remap P2"]["relative_error"] < 0.08
    assert m["FEM-remap P1"]["relative_error"] > 0.10
    for label, r in res["collapse"].items():
        assert r["n_particles"] == 91, label
        assert abs(r["volume_change"]) < 0.1, label
    assert (
        res["collapse"]["SPFEM"]["explicit_steps"] > res["collapse"]["SPFEM"]["steps"]
    )


def test_speed_accuracy_quick(tmp_path):
    page = tmp_path / "choosing.md"
    res = load("speed_accuracy").main(
        ["--quick", "--workers", "0", "--work", str(tmp_path), "--page", str(page)]
    )
    rows = res["rows"]
    assert all(r["ok"] for r in rows.values())
    for r in rows.values():
        if r["problem"] == "footing":
            assert r["error"] == pytest.approx(abs(r["value"] / (2 + math.pi) - 1))
        if r["problem"] == "collapse":
            ref = res["reference"]["collapse"]
            assert r["error"] == pytest.approx(abs(r["value"] - ref) / ref)
    # b/h = 2 and two steps: N-PFEM +7.7 %, FEM P1 locks (+66 %).
    npfem = rows["footing_n-pfem-high_n2_s2"]
    assert npfem["error"] < 0.1
    assert rows["footing_fem-remap-p1_n2_s2"]["error"] > 0.3
    # Each Pareto front runs from cheap and rough to costly and accurate.
    for problem in res["fronts"].values():
        for names in problem.values():
            walls = [rows[n]["wall_time"] for n in names]
            errors = [rows[n]["error"] for n in names]
            assert walls == sorted(walls) and errors == sorted(errors, reverse=True)
    text = page.read_text()
    assert "## Where N-PFEM does not pay off" in text
    assert f"{npfem['value']:.4g}" in text  # the tables come from the JSON
    saved = json.loads((tmp_path / "quick" / "speed_accuracy.json").read_text())
    assert saved["rows"].keys() == rows.keys()


@pytest.mark.slow
def test_comparison_demos_full(tmp_path):
    osc = load("compare_oscillation").main(
        ["--work", str(tmp_path), "--out", str(tmp_path), "--workers", "2"]
    )
    assert all(osc["collapse"][k]["at_rest"] for k in osc["collapse"])
    res = load("compare_results").main(
        ["--work", str(tmp_path), "--out", str(tmp_path), "--workers", "2"]
    )
    assert abs(res["footing"]["Tresca"]["methods"]["N-PFEM"]["relative_error"]) < 0.02
    sa = load("speed_accuracy").main(
        [
            "--subset",
            "--work",
            str(tmp_path),
            "--out",
            str(tmp_path),
            "--page",
            str(tmp_path / "choosing.md"),
            "--workers",
            "2",
        ]
    )
    assert sum(r["ok"] for r in sa["rows"].values()) >= 0.9 * len(sa["rows"])
