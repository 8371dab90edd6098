"""Command-line interface: scene catalogue, a run with output, error handling."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skfem_npfem import SCENES, __version__
from skfem_npfem.cli import main
from skfem_npfem.errors import ParameterError
from skfem_npfem.io import read_pvd, read_step

ROOT = Path(__file__).resolve().parents[1]


def test_scenes_lists_every_parameter_with_unit_and_default(capsys):
    assert main(["scenes"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert len(SCENES) >= 2
    for name, scene in SCENES.items():
        assert any(line.startswith(f"{name}:") for line in lines), name
        start = next(i for i, line in enumerate(lines) if line.startswith(f"{name}:"))
        block = []
        for line in lines[start + 1 :]:
            if not line.strip():
                break
            block.append(line.split())
        rows = {words[0]: words for words in block if words}
        for p in scene.params:
            assert p.name in rows, (name, p.name)
            default = "(derived)" if p.default is None else str(p.default).lower()
            # Columns: name, default, unit, ...
            assert rows[p.name][1].lower() == default, (name, p.name)
            assert rows[p.name][2] == p.unit, (name, p.name)
        for metric in scene.metrics_doc:
            assert f"{metric}:" in out


def test_scenes_json_is_valid_and_complete(capsys):
    assert main(["scenes", "--json"]) == 0
    cat = json.loads(capsys.readouterr().out)
    assert set(cat) == set(SCENES)
    for name, scene in SCENES.items():
        params = cat[name]["parameters"]
        assert list(params) == [p.name for p in scene.params]
        for p in scene.params:
            assert params[p.name]["unit"] == p.unit
            assert params[p.name]["default"] == p.default
        assert cat[name]["metrics"] == scene.metrics_doc


def test_run_writes_vtu_series_and_summary(tmp_path, capsys):
    out = tmp_path / "res"
    summary = tmp_path / "s.json"
    code = main(
        [
            "run",
            "elastic-column",
            "--set",
            "spacing=0.5",
            "--out",
            str(out),
            "--summary",
            str(summary),
            "--quiet",
        ]
    )
    assert code == 0
    assert capsys.readouterr().out == ""  # --quiet: nothing on stdout
    pvd = out / "result.pvd"
    assert pvd.is_file()
    steps = read_pvd(pvd)
    assert len(steps) >= 2  # initial state and the static step
    for _, vtu in steps:
        assert Path(vtu).is_file()
    mesh = read_step(steps[-1][1])
    n = mesh.points.shape[0]
    assert n == 3 * 9  # 2 x 8 cells at spacing 0.5 on the 1 x 4 column
    pd = mesh.point_data
    for key in ("displacement", "velocity", "stress", "plastic_strain_eq"):
        assert key in pd, key
    assert pd["stress"].shape == (n, 4)
    assert pd["displacement"].shape[0] == n
    # Elastic: plastic strain is round-off only (< 1e-12; total strain ~ 6e-3).
    assert np.max(np.abs(pd["plastic_strain_eq"])) < 1e-12
    # Physics in the file: top settlement vs ρgH²/(2M) (0.5 %, measured 0.10 %)
    # and the base vertical stress vs -ρgH (2 %, measured 0.40 %, 27 nodes).
    E, nu, rho, g, H = 1e7, 0.3, 2000.0, 9.81, 4.0
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    z0 = mesh.points[:, 1] - pd["displacement"][:, 1]
    top = np.isclose(z0, H)
    settle = -pd["displacement"][top, 1].mean()
    assert settle == pytest.approx(rho * g * H**2 / (2 * M), rel=5e-3)
    base = np.isclose(z0, 0.0)
    assert pd["stress"][base, 1].mean() == pytest.approx(-rho * g * H, rel=2e-2)

    res = json.loads(summary.read_text())
    for key in ("scene", "parameters", "metrics", "solver", "history"):
        assert key in res, key
    assert res["scene"] == "elastic-column"
    assert res["parameters"]["spacing"] == 0.5
    assert res["metrics"]["settlement"] == pytest.approx(settle, rel=1e-12)
    solver = res["solver"]
    assert solver["steps"] == 1
    assert solver["ipm_iterations_total"] == 0  # elastic: one KKT solve
    phases = solver["wall_time"]
    assert isinstance(phases, dict)
    assert {"solve", "setup", "assembly"} <= set(phases)
    assert all(v >= 0 for v in phases.values())
    assert len(res["history"]) == 1


@pytest.mark.parametrize(
    ("argv", "name"),
    [
        (["run", "elastic-column", "--set", "nu=0.7"], "nu"),
        (["run", "elastic-column", "--set", "spacingg=0.5"], "spacingg"),
        (["run", "no-such-scene"], "no-such-scene"),
        (["run", "elastic-column", "--set", "foo"], "--set"),
        (["run", "elastic-column", "--set", "steps=1.5"], "steps"),
    ],
)
def test_bad_input_exits_2_with_one_line_error(argv, name, capsys):
    code = main([*argv, "--quiet"])
    assert code == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: ")
    assert name in lines[0]
    assert "Traceback" not in err


def test_the_footing_says_it_stopped_on_its_plateau(tmp_path, capsys):
    # The default strip footing ends on its load plateau (a few steps, 1 s):
    # the progress report's last line names that reason, as the summary does.
    summary = tmp_path / "s.json"
    assert main(["run", "strip-footing", "--summary", str(summary)]) == 0
    last = capsys.readouterr().err.strip().splitlines()[-1]
    steps = json.loads(summary.read_text())["solver"]["steps"]
    assert json.loads(summary.read_text())["metrics"]["stopped_by"] == "plateau"
    assert last.startswith(f"step {steps:5d}  ") and "stopped: plateau  wall" in last


def test_debug_reraises():
    with pytest.raises(ParameterError) as info:
        main(["run", "elastic-column", "--set", "nu=0.7", "--quiet", "--debug"])
    assert info.value.name == "nu"


def test_top_level_debug_reraises():
    with pytest.raises(ParameterError):
        main(["--debug", "run", "elastic-column", "--set", "nu=0.7", "--quiet"])


def test_python_m_version():
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run(
        [sys.executable, "-m", "skfem_npfem", "--version"],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 0
    assert proc.stdout.strip() == __version__


@pytest.mark.parametrize("name", ["footing-penetration", "slope"])
def test_one_scene_help(name, capsys):
    """`scenes NAME` and `run NAME --help` list that scene's parameters only."""
    scene = SCENES[name]
    assert main(["scenes", name]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"{name}: ")
    for p in scene.params:
        assert f"  {p.name} " in out
    for metric in scene.metrics_doc:
        assert f"    {metric}: " in out
    others = [s for s in SCENES if s != name]
    assert not any(out.count(f"{s}: ") for s in others if s not in name)
    with pytest.raises(SystemExit) as done:
        main(["run", name, "--help"])
    assert done.value.code == 0
    help_text = capsys.readouterr().out
    assert "--set NAME=VALUE" in help_text
    for p in scene.params:
        assert f"  {p.name} " in help_text
    assert main(["scenes", name, "--json"]) == 0
    assert list(json.loads(capsys.readouterr().out)) == [name]


def test_one_scene_help_refuses_an_unknown_scene(capsys):
    assert main(["scenes", "no-such-scene"]) == 2
    err = capsys.readouterr().err
    assert "invalid scene='no-such-scene'" in err and "footing-penetration" in err
    with pytest.raises(SystemExit):  # the generic help: no scene, no listing
        main(["run", "--help"])
    assert "parameter  " not in capsys.readouterr().out


def test_run_help_finds_the_scene_after_options(capsys):
    with pytest.raises(SystemExit):
        main(["run", "--set", "spacing=0.1", "--out", "x", "cone-penetration", "-h"])
    assert "cone-penetration: " in capsys.readouterr().out
