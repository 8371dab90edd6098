"""Pictures of a run with pore water: its pore-pressure fields and water table.

Reference: below a water table at rest the pore pressure is hydrostatic,
``rho_w g (z_w - z)``: the largest one drawn is at the base of the column,
``rho_w g z_w``, and none is negative.
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from skfem import MeshTet, MeshTri

pytest.importorskip("matplotlib")
pytest.importorskip("PIL")

import skfem_npfem as npfem
from skfem_npfem.constants import GRAVITY
from skfem_npfem.errors import ParameterError
from skfem_npfem.io import ResultWriter, read_pvd
from skfem_npfem.scenes.scenery import Scenery
from skfem_npfem.viz.colours import _style
from skfem_npfem.viz.figures import Frames2D, crop
from skfem_npfem.viz.loading import FIELDS, _load
from skfem_npfem.viz.plot import plot_results
from skfem_npfem.viz.render import Renderer, check_rendering
from skfem_npfem.viz.scenery import scenery

pytestmark = pytest.mark.viz

G, RHO_W, LEVEL = 10.0, 1000.0, 1.5
SIZE = (480, 400)


def _run(folder: Path, water, parameters: dict) -> Path:
    """One drained load step of a 1 m x 2 m column, with its scene.json."""
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 2, 7))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = x[:, 1] == 0.0
    fixed[:, 0] = (x[:, 0] == 0.0) | (x[:, 0] == 1.0)
    soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=2000.0)
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    model = npfem.Model(dim=2, materials=[soil], mode="static", gravity=G, water=water)
    sim = npfem.Simulation(
        p, model, mesh, dt=1.0, progress=False, writer=ResultWriter(folder)
    )
    sim.run(steps=1)
    scene = {"scene": "wet-column", "parameters": parameters}
    (folder / "scene.json").write_text(json.dumps(scene))
    return folder


@pytest.fixture(scope="module")
def wet(tmp_path_factory) -> Path:
    water = npfem.Water("drained", npfem.WaterTable(level=LEVEL), rho_w=RHO_W)
    params = {"drainage": "drained", "water_level": LEVEL, "gravity": G}
    return _run(tmp_path_factory.mktemp("wet"), water, params)


def _frames(folder: Path, name: str, sc: Scenery | None = None) -> Frames2D:
    sc = scenery(folder) if sc is None else sc
    entries = read_pvd(folder / "result.pvd")
    loaded = _load(entries, [name], set(range(len(entries))))
    style = _style(name, *loaded.ranges[name])
    view = crop(list(loaded.kept.values()), sc, None)
    return Frames2D(loaded.kept, name, style, name, name, sc, view)


def _legend(frames: Frames2D) -> list[str]:
    legend = frames.ax.get_legend()
    return [] if legend is None else [t.get_text() for t in legend.get_texts()]


def test_pore_pressure_pictures_are_drawn(wet, tmp_path):
    assert {"pore_pressure", "excess_pore_pressure"} <= set(FIELDS)
    paths = plot_results(
        wet,
        field=["pore_pressure", "excess_pore_pressure"],
        times=[0.0, 1.0],
        normalised=False,
        animation="none",
        out_dir=tmp_path,
        window_size=SIZE,
    )
    fields = ("excess_pore_pressure", "pore_pressure")
    expected = [f"{name}_t{t}.png" for name in fields for t in (0, 1)]
    assert sorted(p.name for p in paths) == expected
    assert all(p.stat().st_size > 0 for p in paths)


def test_pore_pressure_colours_span_the_hydrostatic_range(wet):
    entries = read_pvd(wet / "result.pvd")
    loaded = _load(entries, ["pore_pressure"], set())
    lo, hi = loaded.extremes["pore_pressure"]
    assert lo == 0.0  # above the table
    assert hi == pytest.approx(RHO_W * G * LEVEL, rel=1e-14)  # at the base
    style = _style("pore_pressure", *loaded.ranges["pore_pressure"])
    assert style.clim[0] == 0.0 and style.unit == "kPa"  # 0..max, compression +


def test_the_water_level_is_drawn_across_the_picture(wet):
    sc = scenery(wet)
    assert sc.water_level == LEVEL and sc.water_line is None
    frames = _frames(wet, "pore_pressure", sc)
    frames.draw(0)
    assert f"water table ({LEVEL:.3g} m)" in _legend(frames)
    line = next(ln for ln in frames.ax.get_lines() if "water" in ln.get_label())
    assert np.all(np.asarray(line.get_ydata(), float) == LEVEL)
    frames.close()


def test_a_water_level_above_the_ground_is_in_the_frame(wet):
    sc = Scenery(water_level=3.0)  # a metre of free water over the column
    frames = _frames(wet, "pore_pressure", sc)
    assert frames.view.ylim[1] > 3.0
    frames.close()


def test_a_section_water_line_is_drawn_instead_of_a_level(wet):
    line = np.array([[0.0, 1.8], [0.5, 1.2], [1.0, 1.0]])
    sc = Scenery(water_line=line, water_level=LEVEL)
    frames = _frames(wet, "pore_pressure", sc)
    frames.draw(0)
    assert "water table" in _legend(frames)
    drawn = next(ln for ln in frames.ax.get_lines() if ln.get_label() == "water table")
    np.testing.assert_array_equal(np.c_[drawn.get_xdata(), drawn.get_ydata()], line)
    assert not any("m)" in text for text in _legend(frames) if "water" in text)
    frames.close()


def test_a_dry_result_has_no_water_and_refuses_its_fields(tmp_path):
    dry = _run(tmp_path / "dry", None, {"drainage": "dry"})
    assert scenery(dry).water_level is None
    frames = _frames(dry, "stress_yy")
    frames.draw(0)
    assert not any("water" in text for text in _legend(frames))
    frames.close()
    with pytest.raises(ParameterError, match="pore water"):
        plot_results(dry, field="pore_pressure", animation="none", out_dir=tmp_path)


def test_a_cross_section_water_line_comes_before_the_level(tmp_path, monkeypatch):
    # A section file whose reader gives a phreatic line: the picture draws
    # that line, not a horizontal level.
    line = [[0.0, 1.8], [1.0, 1.0]]
    section = tmp_path / "section.json"
    section.write_text("{}")
    monkeypatch.setattr(
        "skfem_npfem.viz.scenery.read_cross_section",
        lambda path: SimpleNamespace(water=line),
    )
    params = {"drainage": "drained", "geometry": str(section), "water_level": 1.0}
    (tmp_path / "scene.json").write_text(json.dumps({"parameters": params}))
    sc = scenery(tmp_path)
    np.testing.assert_array_equal(sc.water_line, line)
    assert sc.water_level is None
    params["geometry"] = str(tmp_path / "gone.json")  # no such file: the level
    (tmp_path / "scene.json").write_text(json.dumps({"parameters": params}))
    assert scenery(tmp_path).water_level == 1.0


def test_a_3d_result_shows_its_water_level_as_a_plane(tmp_path):
    pv = pytest.importorskip("pyvista")
    check_rendering()
    mesh = MeshTet.init_tensor(*(np.linspace(0, 1, 3),) * 2, np.linspace(0, 2, 5))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[:, 2] = x[:, 2] == 0.0
    for k in (0, 1):
        fixed[:, k] = (x[:, k] == 0.0) | (x[:, k] == 1.0)
    soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=2000.0)
    water = npfem.Water("drained", npfem.WaterTable(level=LEVEL), rho_w=RHO_W)
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    model = npfem.Model(dim=3, materials=[soil], mode="static", water=water)
    sim = npfem.Simulation(p, model, mesh, dt=1.0, progress=False)
    sim.writer = ResultWriter(tmp_path)
    sim.run(steps=1)
    params = {"drainage": "drained", "water_level": LEVEL}
    (tmp_path / "scene.json").write_text(json.dumps({"parameters": params}))
    paths = plot_results(
        tmp_path, field="pore_pressure", animation="none", window_size=SIZE
    )
    assert [q.name for q in paths] == ["pore_pressure_t0.png", "pore_pressure_t1.png"]
    entries = read_pvd(tmp_path / "result.pvd")
    loaded = _load(entries, ["pore_pressure"], {1})
    assert loaded.extremes["pore_pressure"][1] == pytest.approx(RHO_W * GRAVITY * LEVEL)
    style = _style("pore_pressure", *loaded.ranges["pore_pressure"])
    images, args = [], (pv, loaded.kept, 3, "pore_pressure", style, "", None, SIZE)
    for level in (None, LEVEL):
        r = Renderer(*args, water=level)
        assert (r.water_actor is None) == (level is None)
        r.draw(1)
        images.append(r.image().astype(int))
        r.close()
    assert np.abs(images[1] - images[0]).max() > 40  # the plane is seen
