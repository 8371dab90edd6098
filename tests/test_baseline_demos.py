"""The comparison demos in reduced form (full runs: docs/validation/comparison).

References: benchmarks.md E4 (Cook's membrane, case (c): Taylor-Hood 7.7286 at
n = 32, NS-FEM 7.273 / 7.626 at n = 8 / 16, FEM-T3 2.085 / 2.125, converged
7.77 +- 0.01; locking index >= 0.97) and T12 (remesh idempotence: N-PFEM
< 1e-10; FEM+remapping drift reported, nonzero).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def load(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "demos" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_locking_demo_quick_matches_the_catalogue():
    res = load("compare_locking").main(["--quick"])
    case = res["cases"][0]
    assert case["nu"] == 0.4999
    # Our Taylor-Hood reference reproduces the catalogue's n = 32 value.
    assert abs(case["reference"]["values"][0] - 7.7286) < 5e-4
    m = case["methods"]
    converged = 7.77  # catalogue E4(c), +- 0.01
    # N-PFEM is NS-FEM: the catalogue's own values, 7.273 and 7.626.
    assert abs(m["N-PFEM"]["u_C"][0] - 7.273) < 2e-3
    assert abs(m["N-PFEM"]["u_C"][1] - 7.626) < 2e-3
    assert m["N-PFEM"]["u_C"][1] / converged >= 0.97  # locking index
    # FEM P1 locks (catalogue FEM-T3: 2.085, 2.125).
    assert abs(m["FEM P1"]["u_C"][0] - 2.085) < 2e-3
    assert m["FEM P1"]["u_C"][1] / converged < 0.35
    # FEM P2 does not lock (measured 0.965 of 7.77 at n = 16).
    assert m["FEM P2"]["u_C"][1] / converged >= 0.95


def test_mapping_demo_quick_remesh_idempotence(capsys):
    res = load("compare_mapping").main(["--quick"])
    rest, rigid = res["at_rest"], res["rigid_motion"]
    assert rest["n_remesh"] == 100
    # T12: N-PFEM maps nothing; 100 re-solves on rebuilt meshes change the
    # stresses by < 1e-10 (measured 2e-14).
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
    assert (tmp_path / "locking.png").exists() and (tmp_path / "mapping.json").exists()
