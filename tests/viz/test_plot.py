"""Tests for skfem_npfem.viz.plot (off-screen PNG snapshots and animations)."""

from __future__ import annotations

import ctypes.util
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pyvista")
pytest.importorskip("imageio")
Image = pytest.importorskip("PIL.Image")
ImageSequence = pytest.importorskip("PIL.ImageSequence")

from skfem_npfem.errors import CheckpointError, NpfemError, ParameterError  # noqa: E402
from skfem_npfem.io import ResultWriter  # noqa: E402
from skfem_npfem.viz.colours import _style  # noqa: E402
from skfem_npfem.viz.loading import FIELDS  # noqa: E402
from skfem_npfem.viz.plot import plot_results  # noqa: E402
from skfem_npfem.viz.snapshots import _frame_indices  # noqa: E402

pytestmark = pytest.mark.viz

RHO_G = 2000.0 * 9.81
SIZE = (480, 400)  # multiples of 16


def _grid_mesh(nx: int, ny: int, width: float, height: float):
    """Structured triangulation of a width x height rectangle."""
    x, y = np.meshgrid(np.linspace(0, width, nx), np.linspace(0, height, ny))
    points = np.c_[x.ravel(), y.ravel()]
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    cells = np.vstack([np.c_[a, b, d], np.c_[a, d, c]])
    return points, cells


def _write_2d(folder: Path, steps: int = 8, scene: dict | None = None) -> Path:
    """A small collapsing 2D 'column': stress_yy = -rho g (top - y)."""
    p0, cells = _grid_mesh(6, 11, 1.0, 2.0)
    n = len(p0)
    writer = ResultWriter(folder)
    for k in range(steps):
        s = k / max(steps - 1, 1)
        x = p0[:, 0] * (1 + s * (1 - p0[:, 1] / 2.0))
        y = p0[:, 1] * (1 - 0.4 * s)
        p = np.c_[x, y]
        stress = np.zeros((n, 4))
        stress[:, 1] = -RHO_G * (y.max() - y)
        stress[:, 0] = stress[:, 2] = 0.5 * stress[:, 1]
        active = np.ones(n, dtype=bool)
        t = cells
        if k >= steps // 2:  # the top right particle flies off
            top_right = n - 1
            active[top_right] = False
            p[top_right] += [0.3 * s, 0.1]
            t = cells[~np.any(cells == top_right, axis=1)]
        writer.write(
            k,
            0.05 * k,
            p,
            t,
            {
                "displacement": p - p0,
                "velocity": np.c_[x - p0[:, 0], y - p0[:, 1]] * 2,
                "stress": stress,
                "plastic_strain_eq": s * (1.0 - p0[:, 1] / 2.0),
                "mass": np.ones(n),
                "active": active,
            },
        )
    scene = scene or {
        "scene": "synthetic",
        "parameters": {"aspect": 2.0, "length": 1.0},
    }
    (folder / "scene.json").write_text(json.dumps(scene))
    return folder


@pytest.fixture(scope="module")
def result2d(tmp_path_factory) -> Path:
    return _write_2d(tmp_path_factory.mktemp("r2d"))


def _rgb(path: Path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB")).astype(int)


def _body_mask(img: np.ndarray) -> np.ndarray:
    """Saturated (coloured) pixels: the field, not the white background/black text."""
    return (img.max(axis=2) - img.min(axis=2)) > 40


def _mode_share(pixels: np.ndarray) -> float:
    """Share of the pixels that have the most frequent colour."""
    _, counts = np.unique(pixels, axis=0, return_counts=True)
    return counts.max() / counts.sum()


def test_default_snapshots_and_gifs(result2d, tmp_path):
    out = tmp_path / "plots"
    paths = plot_results(result2d, out_dir=out, window_size=SIZE)
    names = [p.name for p in paths]
    # default: vertical stress and plastic strain, 5 times (t/sqrt(H0/g)) each
    tau = np.sqrt(2.0 / 9.81)
    t_last = 0.35 / tau
    for field in ("stress_yy", "plastic_strain_eq"):
        pngs = [n for n in names if n.startswith(field + "_t")]
        assert len(pngs) == 5, names
        assert f"{field}_t0.png" in pngs
        assert f"{field}_t{t_last:.4g}.png" in pngs
        assert f"{field}.gif" in names
    assert all(p.parent == out and p.is_file() for p in paths)

    for path in paths:
        if path.suffix != ".png":
            continue
        with Image.open(path) as im:
            im.verify()
        img = _rgb(path)
        assert img.shape == (SIZE[1], SIZE[0], 3)
        assert img.var() > 0
        body = _body_mask(img)
        assert body.mean() > 0.05, path.name  # field + colour bar cover > 5 %
        assert np.all(img[0, -1] >= 250)  # background (top right) is white

    # the vertical stress varies with depth: the body is not one colour, the
    # bottom of the column (most compressed) is darker (viridis) than the top
    img = _rgb(out / "stress_yy_t0.png")
    body = _body_mask(img)
    body[-140:] = False  # leave out the colour bar
    rows = np.flatnonzero(body.any(axis=1))
    top, bottom = rows.min(), rows.max()
    cols = np.flatnonzero(body[(top + bottom) // 2])
    mid = (cols.min() + cols.max()) // 2
    assert img[body].std(axis=0).max() > 20
    assert img[bottom - 3, mid].sum() < img[top + 3, mid].sum() - 150
    # the column slumps: first and last snapshots differ
    assert np.abs(img - _rgb(out / f"stress_yy_t{t_last:.4g}.png")).mean() > 1

    # one GIF frame per step, frames differ
    with Image.open(out / "stress_yy.gif") as gif:
        frames = [np.asarray(f.convert("RGB")) for f in ImageSequence.Iterator(gif)]
    assert len(frames) == 8
    assert frames[0].shape[:2] == (SIZE[1], SIZE[0])
    assert np.abs(frames[0].astype(int) - frames[-1]).mean() > 1


def test_times_fields_and_downsampled_gif(result2d, tmp_path):
    paths = plot_results(
        result2d,
        times=[0.0, 0.15, 0.35],
        normalised=False,
        field=["velocity", "pressure"],
        out_dir=tmp_path,
        window_size=SIZE,
        max_frames=5,
    )
    assert [p.name for p in paths] == [
        "velocity_t0.png",
        "velocity_t0.15.png",
        "velocity_t0.35.png",
        "velocity.gif",
        "pressure_t0.png",
        "pressure_t0.15.png",
        "pressure_t0.35.png",
        "pressure.gif",
    ]
    with Image.open(tmp_path / "velocity.gif") as gif:
        assert gif.n_frames == 5
    # velocity is zero at t = 0 (one colour), not later (several colours)
    v0, v1 = _rgb(tmp_path / "velocity_t0.png"), _rgb(tmp_path / "velocity_t0.35.png")
    v0[-140:], v1[-140:] = 255, 255  # leave out the colour bar
    # (most of the body: thin mesh edges are drawn over the cells)
    assert _mode_share(v0[_body_mask(v0)]) > 0.6
    assert _mode_share(v1[_body_mask(v1)]) < 0.3
    assert v1[_body_mask(v1)].std(axis=0).max() > 20


def test_nearest_step_and_duplicates(result2d, tmp_path):
    # 0.16 s and 0.14 s both pick the step at 0.15 s: drawn once (first label)
    paths = plot_results(
        result2d,
        times=[0.16, 0.14],
        normalised=False,
        field="displacement",
        animation="none",
        out_dir=tmp_path,
        window_size=SIZE,
    )
    assert [p.name for p in paths] == ["displacement_t0.16.png"]
    with pytest.warns(UserWarning, match="outside the stored steps"):
        plot_results(
            result2d,
            times=[99.0],
            field="displacement",
            animation="none",
            out_dir=tmp_path,
            window_size=SIZE,
        )


def test_without_scene_scales_falls_back_to_seconds(tmp_path):
    folder = _write_2d(
        tmp_path / "r", steps=3, scene={"scene": "x", "parameters": {"E": 1.0}}
    )
    with pytest.warns(UserWarning, match="absolute seconds"):
        paths = plot_results(
            folder, times=[0.1], field="stress_xx", animation="none", window_size=SIZE
        )
    assert [p.name for p in paths] == ["stress_xx_t0.1.png"]
    assert paths[0].parent == folder / "plots"


def test_mp4(result2d, tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    import imageio.v2 as imageio

    paths = plot_results(
        result2d,
        times=[0],
        field="stress_xy",
        animation="mp4",
        out_dir=tmp_path,
        window_size=SIZE,
    )
    mp4 = tmp_path / "stress_xy.mp4"
    assert paths[-1] == mp4
    reader = imageio.get_reader(mp4, format="FFMPEG")
    try:
        assert reader.count_frames() == 8
        assert reader.get_data(0).shape == (SIZE[1], SIZE[0], 3)
    finally:
        reader.close()


def _write_3d(folder: Path) -> Path:
    """Two unit cubes stacked (12 tetrahedra), two steps of rising stress."""
    pts = np.array(
        [[x, y, z] for z in (0.0, 1.0, 2.0) for y in (0.0, 1.0) for x in (0.0, 1.0)]
    )
    tets = []
    for base in (0, 4):  # two unit cubes stacked, 6 tetrahedra each
        c = base + np.array([0, 1, 2, 3, 4, 5, 6, 7])
        for a, b in ((1, 3), (3, 2), (2, 6), (6, 4), (4, 5), (5, 1)):
            tets.append([c[0], c[7], c[a], c[b]])
    writer = ResultWriter(folder)
    for k in range(2):
        stress = np.zeros((len(pts), 6))
        stress[:, 2] = -RHO_G * (2.0 - pts[:, 2]) * (1 + k)
        writer.write(
            k,
            0.1 * k,
            pts,
            np.array(tets),
            {"stress": stress, "plastic_strain_eq": np.zeros(len(pts))},
        )
    return folder


def test_3d_default_is_vertical_stress(tmp_path):
    _write_3d(tmp_path)
    paths = plot_results(tmp_path, animation="none", window_size=SIZE)
    names = sorted(p.name for p in paths)
    assert names == [
        "plastic_strain_eq_t0.1.png",
        "plastic_strain_eq_t0.png",
        "stress_zz_t0.1.png",
        "stress_zz_t0.png",
    ]
    img = _rgb(tmp_path / "plots" / "stress_zz_t0.1.png")
    assert img.shape == (SIZE[1], SIZE[0], 3)
    assert _body_mask(img[:-140]).mean() > 0.03


def test_cli_run_then_plot(tmp_path, capsys):
    from skfem_npfem.cli import main

    out = tmp_path / "run"
    args = ["run", "elastic-column", "--set", "mode=dynamic", "--set", "steps=3"]
    assert main([*args, "--set", "spacing=0.5", "--out", str(out), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["plot", str(out), "--animation", "none", "--absolute"]) == 0
    printed = capsys.readouterr().out.split()
    assert printed and all(Path(p).is_file() for p in printed)
    assert {Path(p).name.split("_t")[0] for p in printed} == {
        "stress_yy",
        "plastic_strain_eq",
    }


def test_errors(result2d, tmp_path):
    with pytest.raises(CheckpointError, match=r"no result\.pvd"):
        plot_results(tmp_path)
    with pytest.raises(NpfemError, match="does not exist"):
        plot_results(tmp_path / "missing")
    with pytest.raises(ParameterError, match="field"):
        plot_results(result2d, field="stress_yyy", out_dir=tmp_path)
    with pytest.raises(ParameterError, match="3D only"):
        plot_results(result2d, field="stress_yz", out_dir=tmp_path)
    with pytest.raises(ParameterError, match="animation"):
        plot_results(result2d, animation="avi", out_dir=tmp_path)
    with pytest.raises(ParameterError, match="times"):
        plot_results(result2d, times=[float("nan")], out_dir=tmp_path)
    with pytest.raises(ParameterError, match="clim"):
        plot_results(result2d, clim={"stress_yy": (0.0, -1.0)}, out_dir=tmp_path)
    empty = tmp_path / "empty"
    ResultWriter(empty)  # writes an empty collection
    with pytest.raises(CheckpointError, match="no steps"):
        plot_results(empty)
    assert not list(tmp_path.glob("*.png"))


def test_no_opengl_gives_clear_error(tmp_path):
    """Without a usable OpenGL backend: a library error, not a VTK crash.

    (Only 3D results need VTK; 2D pictures are drawn with matplotlib.)
    """
    result3d = _write_3d(tmp_path / "r3d")
    script = textwrap.dedent(
        f"""
        import sys
        from skfem_npfem.errors import NpfemError
        from skfem_npfem.viz.plot import plot_results
        try:
            plot_results({str(result3d)!r}, out_dir={str(tmp_path)!r},
                         animation="none", times=[0])
        except NpfemError as err:
            print(err)
            sys.exit(3)
        """
    )
    env = {**os.environ, "VTK_DEFAULT_OPENGL_WINDOW": "vtkOSMesaRenderWindow"}
    env["PYTHONPATH"] = os.pathsep.join(
        [str(Path(__file__).resolve().parents[2]), env.get("PYTHONPATH", "")]
    )
    proc = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        check=False,
    )
    if ctypes.util.find_library("OSMesa") is None:
        assert proc.returncode == 3, proc.stderr
        assert "off-screen rendering is not possible" in proc.stdout
        assert "OSMesa" in proc.stdout
    else:  # OSMesa present: rendering works
        assert proc.returncode == 0, proc.stderr


def test_colour_ranges():
    # compression only (a little round-off tension): min..0, sequential map
    s = _style("stress_yy", -79e3, 300.0)
    assert s.clim == (-79.0, 0.0) and s.unit == "kPa" and s.cmap == "viridis"
    # both signs: symmetric, diverging map
    s = _style("stress_xy", -2e6, 1e6)
    assert s.clim == (-2.0, 2.0) and s.unit == "MPa" and s.cmap == "coolwarm"
    # pressure (compression positive) of a body at rest: 0..max
    assert _style("pressure", -10.0, 5e3).clim == (0.0, 5.0)
    # plastic strain round-off is not coloured
    assert _style("plastic_strain_eq", 0.0, 1e-17).clim == (0.0, 1e-6)
    assert _style("velocity", 0.0, 0.0).clim == (0.0, 1.0)
    assert _style("stress_yy", -5.0, 5.0, fixed=True).clim == (-5.0, 5.0)
    assert set(FIELDS) >= {"stress_xx", "stress_yy", "pressure", "velocity"}


def test_frame_indices():
    assert list(_frame_indices(6, 150)) == list(range(6))
    idx = _frame_indices(1001, 150)
    assert len(idx) == 150 and idx[0] == 0 and idx[-1] == 1000
    assert np.all(np.diff(idx) > 0)
