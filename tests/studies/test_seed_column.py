"""``demos/studies/seed_column.py --quick``: the whole study at a tiny resolution.

References: lattice counts by enumeration, exact mass conservation, the seed
case's parameters, and a resumed study that repeats the finished one.
"""

from __future__ import annotations

import importlib
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def load_demo():
    """demos/studies/seed_column.py (on sys.path through tests/conftest.py)."""
    return importlib.import_module("seed_column")


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    demo = load_demo()
    out = tmp_path_factory.mktemp("seed_column")
    assert demo.main(["--quick", "--out", str(out), "--work", str(out)]) == 0
    return demo, out, json.loads((out / "seed_column.json").read_text())


def test_quick_study_runs_every_case(quick):
    demo, out, rep = quick
    cases = rep["cases"]
    assert rep["quick"] and list(cases) == demo.DEFAULT_CASES
    # Spacing r0/4: the quarter disc has 17 lattice points per level
    # (i^2 + j^2 <= 16), 9 levels; the sections 5 x 9.
    per_level = sum(1 for i in range(5) for j in range(5) if i * i + j * j <= 16)
    expected = {"quarter-cylinder": 9 * per_level, "axisymmetric": 45}
    expected["plane-strain"] = 45
    for res in cases.values():
        assert res["n_particles"] == expected[res["geometry"]]
        assert res["steps"] == demo.QUICK["steps"]
        assert res["statuses"] == ["Solved"] and res["retries"] == 0
        assert res["mass_change"] == 0.0
        # The seed column: a = 2, Lube et al. 2004 at a = 2: 1.6 sqrt(2).
        assert res["h0"] / res["r0"] == pytest.approx(2.0)
        assert res["reference_runout_lube2004"] == pytest.approx(2.2627417, 1e-7)
        # Four steps of 2 ms: the column has barely started to move.
        assert 0.0 <= res["normalised_runout"] < 0.05
        assert res["profile"]["r"] and res["wall_time_s"] > 0
        # The phases of the steps add up to the wall time of the steps.
        assert sum(res["phases_s"].values()) == pytest.approx(res["wall_time_s"])
    assert (out / "tables.md").read_text().count("\n|") >= 3 * len(cases)
    assert (out / "profiles.png").stat().st_size > 1000


def test_quick_study_resumes_from_checkpoints(quick):
    # A case whose summary is lost continues from its checkpoint (the last
    # step) and reports the same run.
    demo, out, _ = quick
    summary = out / "axi-12" / "summary.json"
    before = json.loads(summary.read_text())
    summary.unlink()
    after = demo.run_case("axi-12", out, quick=True, threads=0)
    assert after["metrics"] == before["metrics"]
    assert len(after["history"]) == len(before["history"])


def test_an_interrupted_case_is_continued_not_reported(quick):
    # An interrupted run writes its summary with "interrupted": true (the CLI
    # keeps every finished step).  The study continues such a case from its
    # checkpoint instead of reporting the partial run: the result is the
    # finished run's (the quick run has QUICK["steps"] steps).
    demo, out, _ = quick
    summary = out / "axi-12" / "summary.json"
    before = json.loads(summary.read_text())
    partial = {**before, "interrupted": True, "history": before["history"][:1]}
    summary.write_text(json.dumps(partial))
    after = demo.run_case("axi-12", out, quick=True, threads=0)
    assert not after.get("interrupted")
    assert len(after["history"]) == demo.QUICK["steps"]
    assert after["metrics"] == before["metrics"]


def test_partial_reports_an_interrupted_run_where_it_stands(quick, tmp_path):
    # --partial: a case cut off by Ctrl-C is reported to the step it reached,
    # not run or continued.  Reference: its t_bar is the steps times dt over
    # sqrt(h0/g) of the seed case (2 steps of 2 ms, h0 = 7.8 cm).
    import math
    import shutil

    demo, out, _ = quick
    work = tmp_path / "work"
    shutil.copytree(out / "axi-12", work / "axi-12")
    summary = work / "axi-12" / "summary.json"
    before = json.loads(summary.read_text())
    hist = before["history"][:2]
    # The checkpoint written on stopping holds where the particles are: here
    # the last written step's particles stretched 1.5x radially, so that the
    # profile shows which of the two it was built from.
    from skfem_npfem.io import read_pvd
    from skfem_npfem.io.checkpoints import save_checkpoint

    x = demo.load_step(read_pvd(work / "axi-12" / "result.pvd")[-1][1])[0]
    x = x * [1.5, 1.0]
    ckpt = save_checkpoint(work / "axi-12" / "stopped.npz", {"x": x}, {})
    cut = {
        **before,
        "interrupted": True,
        "history": hist,
        "solver": {**before["solver"], "time": hist[-1]["time"]},
        "checkpoint": str(ckpt),
    }
    summary.write_text(json.dumps(cut))
    argv = ["--quick", "--partial", "--cases", "axi-12", "--work", str(work)]
    assert demo.main([*argv, "--out", str(tmp_path), "--no-pictures"]) == 0
    assert json.loads(summary.read_text()) == cut  # not continued
    res = json.loads((tmp_path / "seed_column.json").read_text())["cases"]["axi-12"]
    t_bar = 2 * 2e-3 / math.sqrt(0.078 / 9.81)
    assert res["partial"] and res["steps"] == 2
    assert res["t_bar_end"] == pytest.approx(t_bar, rel=1e-12)
    assert res["label"].endswith(f"(cut off at t_bar = {t_bar:.2f})")
    # It never got to t_bar = 3: no run-out or wall time there.
    assert res["normalised_runout_t3"] is None and res["wall_time_t3_s"] is None
    # Of the picture's times t_bar = 0, 1, 2, 3 it reached only the first.
    assert t_bar < 1.0 - 0.5 * 2e-3 / math.sqrt(0.078 / 9.81)
    assert res["snapshots_reached"] == [True, False, False, False]
    assert res["profile"] == demo.deposit_profile(x, res["spacing"])
    row = [
        r for r in (tmp_path / "tables.md").read_text().splitlines() if "cut off" in r
    ]
    assert row and " | - | " in row[0]
    # A case with no summary yet is refused with the reason, not run.
    argv = ["--quick", "--partial", "--cases", "axi-18", "--work", str(work)]
    assert demo.main([*argv, "--out", str(tmp_path), "--no-pictures"]) == 2


def test_keep_adds_a_case_to_the_results_of_an_earlier_study(quick):
    # --keep: the cases of the existing seed_column.json stay (same order,
    # same numbers); the case run now replaces its own entry.
    demo, out, rep = quick
    argv = ["--quick", "--out", str(out), "--work", str(out)]
    picture = ["--keep", "--picture", "kept.png"]
    assert demo.main([*argv, "--cases", "axi-18", *picture]) == 0
    kept = json.loads((out / "seed_column.json").read_text())
    assert list(kept["cases"]) == list(rep["cases"])
    assert kept["cases"]["3d-12"] == rep["cases"]["3d-12"]
    assert kept["cases"]["axi-18"]["n_particles"] == 45
    # The picture of the cases run, under its own name (when pyvista renders).
    assert (out / "kept.png").exists() == (out / "sigma_v.png").exists()
    argv.append("--no-pictures")
    # Without --keep the file holds only the cases run.
    assert demo.main([*argv, "--cases", "axi-18"]) == 0
    alone = json.loads((out / "seed_column.json").read_text())
    assert list(alone["cases"]) == ["axi-18"]


def test_3d_volume_budget_of_a_short_run(tmp_path, monkeypatch):
    # demos/studies/seed_3d_volume.py on the quarter at r0/4 for 3 steps: the
    # masses are rho times the initial mesh's cells, so the first step's mesh
    # holds exactly what the particles carry, and the budget's parts agree
    # with the run's own volume change.
    from skfem_npfem.scenes.collapse.geometry import QUARTER_FIXED

    study = importlib.import_module("seed_3d_volume")
    tiny = {
        "geometry": "quarter-cylinder",
        "spacing": study.R0 / 4,
        "t_end": 0.006,
        "rest_fraction": 0.0,
        "threads": 1,
        **QUARTER_FIXED,  # three fixed steps on the uniform lattice
    }
    monkeypatch.setitem(study.CASES, "tiny", tiny)
    rec = study.run_case("tiny", tmp_path)
    rows = json.loads((tmp_path / "tiny" / "budget.json").read_text())
    assert len(rows) == rec["steps"] == 3
    assert rows[0]["mesh"] == pytest.approx(1.0, rel=1e-12)
    last = rec["budget_at_rest"]
    assert last["mesh"] == pytest.approx(1.0 + rec["volume_change"], abs=1e-4)
    # The scene's 3D default (alpha 2.0: the lattice at rest is meshed whole).
    assert rec["settings"]["alpha"] == 2.0 and last["inactive"] == 0.0
    assert rec["settings"]["stabilisation_mode"] == "vertical"


def test_3d_volume_record_is_consistent():
    # docs/seed_column/volume_3d.json: the mesh at rest over sum(m)/rho is the
    # run's volume change (the same record, rounded to 4 digits), and the
    # r0/12 cases ran with the scene's 3D default and the one before.
    from skfem_npfem.scenes.collapse.cylinder import GEOMETRY_ALPHA
    from skfem_npfem.scenes.collapse.runs import CYLINDER_FIDELITY

    path = ROOT / "docs" / "seed_column" / "volume_3d.json"
    cases = json.loads(path.read_text())["cases"]
    for case in cases.values():
        mesh = case["budget_at_rest"]["mesh"]
        assert mesh == pytest.approx(1.0 + case["volume_change"], abs=1e-4)
        assert case["at_rest"]
    beta, mode, kappa = CYLINDER_FIDELITY["quarter-cylinder"]
    default = {
        "alpha": GEOMETRY_ALPHA["quarter-cylinder"],
        "stabilisation": beta,
        "stabilisation_mode": mode,
        "volume_correction": kappa,
        "buried_slivers": "keep",
    }
    assert cases["r12-slivers-beta-1000"]["settings"] == default
    # the default before: factor 30, buried slivers dropped
    before = default | {"stabilisation": 30.0, "buried_slivers": "drop"}
    assert cases["r12-default"]["settings"] == before


@pytest.mark.parametrize("geometry", ["axisymmetric", "quarter-cylinder"])
def test_bare_method_switches_the_cylindrical_defaults_off(geometry):
    # The overrides that studies and benchmarks pin to repeat what they
    # measured before the cylindrical defaults: the built run has no
    # stabilisation, no volume correction, the alpha factor 1.3 and (3D) drops
    # the buried slivers -- while the same scene without them has the
    # defaults of CYLINDER_FIDELITY.
    from skfem_npfem.scenes import get_scene
    from skfem_npfem.scenes.collapse.runs import CYLINDER_FIDELITY, bare_method

    scene = get_scene("column-collapse")
    base = {"geometry": geometry, "spacing": 0.039 / 4}
    bare = scene.build(scene.resolve(base | bare_method(geometry)), out=None)
    default = scene.build(scene.resolve(base), out=None)
    b, d = bare.simulation, default.simulation
    assert (b.model.stabilisation, b.model.volume_correction) == (0.0, 0.0)
    assert b.mesh_source.alpha == 1.3 and not b.mesh_source.keep_buried_slivers
    beta, mode, kappa = CYLINDER_FIDELITY[geometry]
    assert (d.model.stabilisation, d.model.stabilisation_mode) == (beta, mode)
    assert d.model.volume_correction == kappa
    if geometry == "quarter-cylinder":  # (a 2D mesh has no buried slivers)
        assert d.mesh_source.keep_buried_slivers is True
    assert bare_method("plane-strain") == {} == bare_method("box")


def test_measured_on_is_read_before_each_piece_of_a_run(quick, tmp_path):
    # The study's "measured on" column: every case folder records the CPU
    # and the load of other processes as its run starts (before the run adds
    # its own), and a run continued from its checkpoint adds a record; the
    # table joins them (any shared piece makes the run shared).
    import os

    demo, out, rep = quick
    for name, res in rep["cases"].items():
        pieces = json.loads((out / name / "measured_on.json").read_text())
        # (tests above continue some cases: a piece more each)
        assert res["measured_on"] == pieces[0]
    busy = demo.cores_busy(0.2)
    # /proc/stat counts whole clock ticks (1/100 s) per core, read at both ends
    # of the 0.2 s window: up to two ticks a core either way, 0.1 core each.
    ticks = 2 * os.cpu_count() / (0.2 * os.sysconf("SC_CLK_TCK"))
    assert busy is None or -ticks <= busy <= os.cpu_count() + ticks
    folder = tmp_path / "case"
    demo.note_start(folder, continued=False)
    first = json.loads((folder / "measured_on.json").read_text())
    other = {"date": "2000-01-01", "cpu": "another CPU", "load": "shared"}
    (folder / "measured_on.json").write_text(json.dumps([*first, other]))
    joined = demo.stored_measured_on(folder)
    assert joined["date"] == first[0]["date"] and joined["load"] == "shared"
    assert joined["cpu"] == f"{first[0]['cpu']} and another CPU"
    demo.note_start(folder, continued=True)  # a third piece
    assert len(json.loads((folder / "measured_on.json").read_text())) == 3
    demo.note_start(folder, continued=False)  # a fresh run starts over
    assert len(json.loads((folder / "measured_on.json").read_text())) == 1
