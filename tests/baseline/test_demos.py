"""The comparison demos in reduced form (full runs: docs/validation/comparison).

References (docs/verification.md, "The reference cases"; docs/baselines.md,
"Comparison (a)"): Cook's membrane at nu = 0.4999 (Taylor-Hood 7.7286 at
n = 32, independent NS-FEM 7.273 / 7.626 at n = 8 / 16 and FEM-T3 2.085 / 2.125,
converged 7.77 +- 0.01; locking index >= 0.97), remesh idempotence (N-PFEM
< 1e-10; FEM+remapping drift reported, nonzero); undamped sudden loading of an
elastic column doubles the static settlement (dynamic amplification factor 2,
SPFEM without damping) while the implicit backward-Euler methods settle to
the static value; the Prandtl factor 2 + pi; exact mass conservation.
"""

from __future__ import annotations

import importlib
import json
import math
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def load(name: str):
    """A study of demos/studies (on sys.path through tests/conftest.py)."""
    return importlib.import_module(name)


def test_locking_demo_quick_matches_the_published_values():
    res = load("compare_locking").main(["--quick"])
    case = res["cases"][0]
    assert case["nu"] == 0.4999
    # Our Taylor-Hood reference reproduces the published n = 32 value.
    assert abs(case["reference"]["values"][0] - 7.7286) < 5e-4
    m = case["methods"]
    converged = 7.77  # Cook's membrane at nu = 0.4999, +- 0.01
    # N-PFEM is NS-FEM: the independent NS-FEM values, 7.273 and 7.626.
    assert abs(m["N-PFEM"]["u_C"][0] - 7.273) < 2e-3
    assert abs(m["N-PFEM"]["u_C"][1] - 7.626) < 2e-3
    assert m["N-PFEM"]["u_C"][1] / converged >= 0.97  # locking index
    # FEM P1 locks (independent FEM-T3: 2.085, 2.125).
    assert abs(m["FEM P1"]["u_C"][0] - 2.085) < 2e-3
    assert m["FEM P1"]["u_C"][1] / converged < 0.35
    # FEM P2 does not lock (measured 0.965 of 7.77 at n = 16).
    assert m["FEM P2"]["u_C"][1] / converged >= 0.95


def test_mapping_demo_quick_remesh_idempotence(capsys):
    res = load("compare_mapping").main(["--quick"])
    rest, rigid = res["at_rest"], res["rigid_motion"]
    assert rest["n_remesh"] == 100
    # Remesh idempotence: N-PFEM maps nothing; 100 re-solves on rebuilt meshes
    # change the stresses by < 1e-10 (measured 2e-14).
    assert rest["npfem"]["drift"] < 1e-10
    # FEM-remap drifts (printed for the record; measured 3.3e-2 P1 nearest,
    # 8.0e-3 P2 nearest, 3.5e-2 P1 recovery, 8e-13 P2 recovery: the P2 state
    # is the exact linear field, which recovery transfers exactly).
    for key in ("fem-p1-nearest", "fem-p2-nearest", "fem-p1-recovery"):
        assert rest[key]["drift"] > 1e-3, key
    assert rest["fem-p2-recovery"]["drift"] < 1e-10
    assert 0.2 < rest["changed_element_fraction"] < 0.8
    # Rigid motion: N-PFEM only rotates its particles' stresses (round-off);
    # every FEM transfer changes the invariants.
    assert rigid["npfem"]["q_drift"] < 1e-12
    for key in (
        "fem-p1-nearest",
        "fem-p2-nearest",
        "fem-p1-recovery",
        "fem-p2-recovery",
    ):
        assert rigid[key]["q_drift"] > 1e-4, key
    # Bands (10 x 10 lattice, 20 steps), against sigma0 at the exact material
    # points: the shear band adds no particle at this size, so N-PFEM is exact;
    # the opening band's gap is filled by particles interpolated once each
    # (measured q drift 1.7e-3 against 6.9e-2 for P1 recovery, 6.3e-4 for P1
    # nearest on the 66 % of the block FEM-remap still meshes).
    shear, opening = res["shear_band"], res["opening_band"]
    assert shear["npfem"]["inserted"] == 0 and shear["npfem"]["q_drift"] < 1e-12
    assert opening["npfem"]["inserted"] > 0
    assert opening["npfem"]["area_ratio"] > 0.99  # the gap is soil
    for key in ("fem-p1-nearest", "fem-p1-recovery", "fem-p2-recovery"):
        assert shear[key]["q_drift"] > 1e-3, key
        assert opening[key]["area_ratio"] < 0.8, key  # the gap is dropped
    assert opening["npfem"]["q_drift"] < 0.1 * opening["fem-p1-recovery"]["q_drift"]
    out = capsys.readouterr().out
    assert "N-PFEM" in out


@pytest.mark.slow
def test_demos_full(tmp_path):
    lock = load("compare_locking").main(["--out", str(tmp_path)])
    for case in lock["cases"]:
        assert case["methods"]["N-PFEM"]["ratio"][-1] > 0.97
        assert case["methods"]["FEM P2"]["ratio"][-1] > 0.97
    assert abs(lock["cases"][-1]["reference"]["value"] - 7.77) < 0.01
    mapping = load("compare_mapping").main(["--out", str(tmp_path)])
    assert mapping["rigid_motion"]["npfem"]["q_drift"] < 1e-12
    # Insertion's error is second order: 1.7e-3 at 10 x 10, 4.0e-4 at 20 x 20.
    assert mapping["opening_band"]["npfem"]["q_drift"] < 1e-3
    assert (tmp_path / "locking.png").exists() and (tmp_path / "mapping.json").exists()


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
    assert "predate" not in text and "Measured before" not in text  # today's defaults
    assert f"{npfem['value']:.4g}" in text  # the tables come from the JSON
    saved = json.loads((tmp_path / "quick" / "speed_accuracy.json").read_text())
    assert saved["rows"].keys() == rows.keys()


@pytest.mark.slow
def test_comparison_demos_full(tmp_path):
    pytest.importorskip("distributed", reason="needs the sweep extra (Dask)")
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


def test_speed_accuracy_page_says_which_defaults_it_predates():
    """A study recorded before the volume-correction default says so on its page.

    The committed record (rerun on 2026-12-03) has today's defaults: its page
    has no warning.  The same record without ``volume_correction`` among its
    defaults (as the record of 2026-12-01 was: node masses from the cells and
    beta = 30 but no volume correction) warns about that (not about the
    stabilisation), and the study line stays above the summary sections.
    """
    demo = load("speed_accuracy")
    record = json.loads(
        (ROOT / "docs/validation/comparison/speed_accuracy.json").read_text()
    )
    assert record["npfem_defaults"] == dict(demo.NPFEM_DEFAULTS)
    assert "predate" not in demo.write_page(record, None)
    del record["npfem_defaults"]["volume_correction"]
    text = demo.write_page(record, None)
    assert "predate the volume correction" in text
    assert "Measured before" not in text
    assert text.index("Study: mode") < text.index("## Which method to pick")
    record["npfem_defaults"] = dict(demo.NPFEM_DEFAULTS)
    text = demo.write_page(record, None)
    assert "predate" not in text
    assert text.index("Study: mode") < text.index("## Which method to pick")
    record["npfem_defaults"] = {"nodal_mass": "particle", "stabilisation": 0.0}
    assert "Measured before" in demo.write_page(record, None)
