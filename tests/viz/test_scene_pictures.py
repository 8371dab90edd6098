"""What the cone's and the slope's pictures show (what is drawn, not pixels).

The cone: a window a few D around the tip's path (said in the title), its
N_c-w/D curve beside the field and on its own, file names and ``--times`` in
w/D.  The slope: the section's initial outline, side rollers and the
boundaries between its layers, in the field pictures and on the mechanism.
"""

from __future__ import annotations

import io
import json
import math
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")
pytest.importorskip("PIL")

from skfem_npfem.cli import main
from skfem_npfem.io import latest_checkpoint, load_checkpoint, read_pvd
from skfem_npfem.scenes.scenery import section_lines
from skfem_npfem.viz.colours import _style
from skfem_npfem.viz.figures import Frames2D, crop
from skfem_npfem.viz.loading import _load
from skfem_npfem.viz.mechanism import mechanism_figure
from skfem_npfem.viz.plot import plot_results
from skfem_npfem.viz.scenery import scenery

ROOT = Path(__file__).resolve().parents[2]
D, SPEED = 0.0357, 0.02  # the cone's default diameter and speed
SU, SIGMA0 = 1.0e4, 5.0e4  # its default s_u and sigma_0


def _run(scene: str, folder: Path, **sets: object) -> Path:
    """``skfem-npfem run SCENE --set k=v ... --out folder``; the folder."""
    args = [a for k, v in sets.items() for a in ("--set", f"{k}={v}")]
    with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
        assert main(["run", scene, *args, "--out", str(folder)]) == 0
    return folder


@pytest.fixture(scope="module")
def cone_run(tmp_path_factory) -> Path:
    """A coarse cone pushed about one diameter (ten steps, a few seconds)."""
    folder = tmp_path_factory.mktemp("cone") / "run"
    return _run("cone-penetration", folder, spacing=0.0089, penetration=0.036)


def _legend(frames: Frames2D) -> list[str]:
    return [t.get_text() for t in frames.ax.get_legend().get_texts()]


def _frames(folder: Path, name: str = "plastic_strain_eq"):
    sc = scenery(folder)
    entries = read_pvd(folder / "result.pvd")
    loaded = _load(entries, [name], set(range(len(entries))))
    style = _style(name, *loaded.ranges[name])
    view = crop(list(loaded.kept.values()), sc, None)
    frames = Frames2D(loaded.kept, name, style, name, name, sc, view)
    return sc, loaded, frames


def test_cone_pictures_zoom_on_the_tip_and_say_so(cone_run):
    _, loaded, frames = _frames(cone_run)
    radius = 30 * D  # the default domain_radius, in D
    x0, x1 = frames.ax.get_xlim()
    y0, y1 = frames.ax.get_ylim()
    assert x1 - x0 < 5 * D < radius / 5  # the window, not the whole domain
    # the tip starts 8 D + w above the base and ends 8 D above it: 3 D either side
    z_start = 8 * D + 0.036
    assert y0 < 8 * D - 2.5 * D and y1 > z_start + 2.5 * D
    assert y1 - y0 < 1.25 * (0.036 + 6 * D)  # the path and 3 D either side, padded
    last = max(loaded.kept)
    frames.draw(last)
    title = frames.fig._suptitle.get_text()
    assert "window: r \u2264 4 D" in title and "w/D = " in title
    assert "cone" in _legend(frames)
    # the fixed base and the far rollers are outside the window: not named
    assert "fixed base" not in _legend(frames) and "rollers" not in _legend(frames)


def test_cone_factor_curve_is_drawn_from_the_step_records(cone_run):
    _, loaded, frames = _frames(cone_run)
    _, meta = load_checkpoint(latest_checkpoint(cone_run))
    rec = [r for r in meta["records"] if "cone_force_y" in r]
    area = math.pi * D**2 / 4
    w_d = [-r["cone_y"] / D for r in rec]
    n_c = [(r["cone_force_y"] / area - SIGMA0) / SU for r in rec]
    last = max(loaded.kept)
    frames.draw(last)
    ax = frames.curve_ax
    assert ax.get_xlabel() == "penetration w/D"
    assert ax.get_ylabel().startswith("cone factor N_c")
    x, y = ax.get_lines()[0].get_data()
    np.testing.assert_allclose(x, w_d, rtol=1e-12)
    np.testing.assert_allclose(y, n_c, rtol=1e-12)
    # Teh & Houlsby at the default I_r = 100: 1.25 + 1.84 ln 100
    ref = 1.25 + 1.84 * math.log(100.0)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert f"Teh & Houlsby N_c = {ref:.3g}" in texts
    marker = next(ln for ln in ax.get_lines() if ln.get_label() == "this picture")
    t = loaded.kept[last].time
    assert marker.get_data()[0][0] == pytest.approx(SPEED * t / D)
    depth = ax.child_axes[0]  # the depth pushed, in m, on top
    assert depth.get_xlabel() == "depth pushed w [m]"


def test_cone_files_and_times_are_in_w_over_d(cone_run, tmp_path):
    with pytest.warns(UserWarning, match="w/D = 3 is outside"):
        paths = plot_results(
            cone_run,
            times=[0.5, 1, 3],
            field=["stress_yy"],
            animation="none",
            out_dir=tmp_path,
        )
    names = [p.name for p in paths]
    # --times 1 is w/D = 1 (in seconds it would be w = 0.02 m = 0.56 D)
    assert names[:2] == ["stress_yy_wD0.5.png", "stress_yy_wD1.png"]
    assert names[2].startswith("stress_yy_wD1.0")  # the last step, w/D ~ 1.008
    assert names[-1] == "cone_factor.png"
    cli = cone_run / "plots"
    with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
        code = main(["plot", str(cone_run), "--times", "1", "--animation", "none"])
    assert code == 0
    assert (cli / "stress_yy_wD1.png").is_file()
    assert not list(cli.glob("*_t*.png"))


def test_section_lines_split_the_outline_from_the_layer_boundaries():
    sec = json.loads((ROOT / "docs/examples/two_layer_slope.json").read_text())
    polys = [np.array(r["polygon"], float)[:-1] for r in sec["regions"]]
    outline, between = section_lines(polys)
    pieces = between[~np.isnan(between[:, 0])].reshape(-1, 2, 2)
    # the fill sits on the clay from x = 0 to 22 at y = 4
    assert {tuple(sorted(p[:, 0])) for p in pieces} == {(0.0, 10.0), (10.0, 22.0)}
    assert np.all(pieces[:, :, 1] == 4.0)
    out = outline[~np.isnan(outline[:, 0])].reshape(-1, 2, 2)
    length = np.linalg.norm(out[:, 1] - out[:, 0], axis=1).sum()
    # base 40, right side 4, clay top 18, slope face 8 sqrt 2, crest 14, left 12
    assert length == pytest.approx(40 + 4 + 18 + 8 * math.sqrt(2) + 14 + 12)


@pytest.fixture(scope="module")
def slope_limit(tmp_path_factory) -> Path:
    """The two-layer example's factor of safety at spacing 2 m (a second)."""
    folder = tmp_path_factory.mktemp("slope") / "run"
    geometry = ROOT / "docs/examples/two_layer_slope.json"
    return _run(
        "slope", folder, spacing=2, analysis="limit", refine="none", geometry=geometry
    )


def test_slope_mechanism_shows_outline_rollers_and_layers(slope_limit, tmp_path):
    sc = scenery(slope_limit)
    assert [(x, side, text) for x, side, text in sc.walls] == [
        (0.0, 1, "side rollers"),
        (40.0, -1, ""),
    ]
    data = np.load(slope_limit / "mechanism.npz")
    fig = mechanism_figure(
        data["x"], data["triangles"], data["velocity"], data["dissipation"], sc=sc
    )
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == [
        "fixed base",
        "side rollers",
        "initial outline",
        "layer boundaries (initial)",
    ]
    layers = next(ln for ln in ax.get_lines() if ln.get_label().startswith("layer"))
    y = layers.get_ydata()
    assert np.all(y[~np.isnan(y)] == 4.0)
    x0, x1 = ax.get_xlim()
    assert x0 < 0.0 and x1 > 40.0  # both rollers in the frame
    paths = plot_results(slope_limit, animation="none", out_dir=tmp_path)
    assert paths[-1].name == "mechanism.png"


def test_slope_runout_field_pictures_show_the_scenery(tmp_path):
    folder = _run("slope", tmp_path / "r", spacing=2, runout="true", t_end=0.05)
    _, _, frames = _frames(folder, "stress_yy")
    frames.draw(0)
    labels = _legend(frames)
    assert "initial outline" in labels and "side rollers" in labels
    assert "layer boundaries (initial)" not in labels  # one region
    outline = next(
        ln for ln in frames.ax.get_lines() if ln.get_label() == "initial outline"
    )
    y = outline.get_ydata()
    # the default slope: H = 10 m on a foundation 5 m deep
    assert np.nanmax(y) == pytest.approx(15.0) and np.nanmin(y) == 0.0


def test_footing_penetration_times_are_in_w_over_b():
    from skfem_npfem.scenes import SCENES
    from skfem_npfem.viz.snapshots import _pick_snapshots, _time_unit

    scene = SCENES["footing-penetration"]
    params = {q.name: q.default for q in scene.params} | {"speed": 0.5}
    sc = scene.scenery(params, None)
    unit = _time_unit(sc, normalised=True)
    B = params["width"]
    assert (unit.prefix, unit.name) == ("wB", "w/B")
    # steps every 0.1 s at 0.5 m/s: w/B = 0.05 / B per step; ask for w/B = 0.5
    ts = np.arange(0.0, 2.0 * B / 0.5, 0.1)
    snaps = _pick_snapshots(ts, [0.5], unit)
    (i,) = snaps
    assert 0.5 * ts[i] / B == pytest.approx(0.5, abs=0.05 / B)
