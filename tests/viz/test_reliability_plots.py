"""Pictures a geotechnician reads, and plotting a damaged result.

The figure-building functions are checked for what they draw (axes, scenery,
markers, colour ranges, crop, the footing's load-settlement curve), not for
pixels; one PNG per scene type is rendered to check that files are written.
"""

from __future__ import annotations

import io
import json
import shutil
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")
pytest.importorskip("PIL")

from skfem_npfem.cli import main
from skfem_npfem.io import ResultWriter, write_checkpoint
from skfem_npfem.laws import lube2005_runout as lube_runout
from skfem_npfem.particles import Particles
from skfem_npfem.viz.colours import _robust_range, _style
from skfem_npfem.viz.figures import Frames2D, crop, load_settlement_figure
from skfem_npfem.viz.loading import _load
from skfem_npfem.viz.plot import plot_results
from skfem_npfem.viz.scenery import scenery

L0, A = 0.2, 2.0
H0 = A * L0


def _lattice(nx: int, ny: int, w: float, h: float):
    x, y = np.meshgrid(np.linspace(0, w, nx), np.linspace(0, h, ny))
    p = np.c_[x.ravel(), y.ravel()]
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return p, np.vstack([np.c_[a, b, d], np.c_[a, d, c]])


@pytest.fixture(scope="module")
def collapse_dir(tmp_path_factory) -> Path:
    """A synthetic collapse: the column slumps; the lowest row slides (huge
    plastic strain, the 'floor band'); one grain flies to x = 5 m."""
    folder = tmp_path_factory.mktemp("collapse")
    p0, cells = _lattice(9, 17, L0, H0)
    n = len(p0)
    w = ResultWriter(folder)
    for k in range(4):
        s = k / 3
        x = p0[:, 0] * (1 + 2.0 * s * (1 - p0[:, 1] / H0))
        y = p0[:, 1] * (1 - 0.5 * s)
        pts = np.c_[x, y]
        eps = s * np.linspace(0.0, 1.0, n)  # 0..1 over the body
        band = (p0[:, 1] == 0.0) & (p0[:, 0] > L0 / 2)  # 4 of 153 particles
        eps[band] = 50.0 * s  # the floor band
        active = np.ones(n, bool)
        t = cells
        if k == 3:  # the top right grain flies off
            pts[n - 1] = [5.0, 0.3]
            active[n - 1] = False
            t = cells[~np.any(cells == n - 1, axis=1)]
        stress = np.zeros((n, 4))
        stress[:, 1] = -1800 * 9.81 * (y.max() - y)
        w.write(
            k,
            0.1 * k,
            pts,
            t,
            {
                "stress": stress,
                "plastic_strain_eq": eps,
                "mass": np.ones(n),
                "active": active,
            },
        )
    params = {"aspect": A, "half_width": L0, "symmetric": True, "gravity": 9.81}
    (folder / "scene.json").write_text(
        json.dumps({"scene": "column-collapse", "parameters": params})
    )
    return folder


def _frames(folder: Path, name: str):
    sc = scenery(folder)
    from skfem_npfem.io import read_pvd

    entries = read_pvd(folder / "result.pvd")
    loaded = _load(entries, [name], set(range(len(entries))))
    lo, hi = loaded.ranges[name]
    style = _style(name, lo, hi)
    view = crop(list(loaded.kept.values()), sc, None)
    frames = Frames2D(loaded.kept, name, style, "t", "label", sc, view)
    return sc, loaded, style, view, frames


def _legend(frames: Frames2D) -> list[str]:
    return [t.get_text() for t in frames.ax.get_legend().get_texts()]


def test_collapse_picture_shows_scenery_runout_and_reference(collapse_dir):
    sc, loaded, _, view, frames = _frames(collapse_dir, "plastic_strain_eq")
    assert sc.floor == 0.0 and sc.walls[0][:2] == (0.0, 1)
    np.testing.assert_allclose(sc.outline.min(axis=0), [0.0, 0.0])
    np.testing.assert_allclose(sc.outline.max(axis=0), [L0, H0])
    reference = L0 * (1 + lube_runout(A))  # 0.6935 m
    assert sc.runout_reference == pytest.approx(reference, rel=1e-12)
    frames.draw(3)
    ax = frames.ax
    assert ax.get_xlabel() == "x [m]" and ax.get_ylabel() == "y [m]"
    assert ax.get_aspect() == 1.0
    labels = _legend(frames)
    assert "rough floor" in labels and "initial outline" in labels
    assert "smooth wall (symmetry plane)" in labels
    assert f"Lube et al. 2005: L\u221e = {reference:.3g} m" in labels
    # The run-out marker is the 99 % mass front of the drawn step, by hand:
    step = loaded.kept[3]
    x = np.sort(step.points[:, 0])
    cum = np.arange(1, x.size + 1) - 0.5
    front = float(np.interp(0.99 * x.size, cum, x))
    assert f"run-out (99 % mass) {front:.3g} m" in labels
    # The flying grain (x = 5 m) is drawn, named in the legend and inside the
    # frame, with the body and the reference.
    assert "detached grain (in no cell): 1" in labels
    assert view.xlim[0] < 0.0 and max(5.0, reference) < view.xlim[1] < 5.5
    assert "t/\u221a(H0/g) = " in frames.fig._suptitle.get_text()


def test_plastic_strain_range_is_not_swamped_by_the_floor_band(collapse_dir):
    _, loaded, style, _, _ = _frames(collapse_dir, "plastic_strain_eq")
    lo, hi = loaded.extremes["plastic_strain_eq"]
    assert hi == pytest.approx(50.0)  # the band
    # Top of the range: the 95th percentile of the plastic values, below the
    # band; the body (0..1 at the end) spans most of the colours.
    assert 0.9 < style.clim[1] < 5.0
    # 50 elastic (0) and 100 plastic values 0.01..1: the zeros do not count,
    # the 95th percentile of the plastic ones is 0.95 + 0.05 * 0.01.
    values = np.r_[np.zeros(50), np.linspace(0, 1, 101)[1:]]
    lo, hi = _robust_range(values, "plastic_strain_eq")
    assert lo == 0.0 and hi == pytest.approx(0.9505, abs=1e-12)


@pytest.fixture(scope="module")
def footing_dir(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("footing")
    b, domain = 1.0, 5.0
    p0, cells = _lattice(11, 11, domain * b, domain * b)
    n = len(p0)
    w = ResultWriter(folder)
    curve = [[0.001 * k, 51e3 * (1 - np.exp(-k))] for k in range(1, 6)]
    for k in range(6):
        w.write(
            k,
            0.001 * k,  # pseudo-time = settlement, m
            p0,
            cells,
            {
                "stress": np.zeros((n, 4)),
                "plastic_strain_eq": np.zeros(n),
                "mass": np.ones(n),
            },
        )
    records = [{"extra": {"settlement": s, "pressure": q}} for s, q in curve]
    write_checkpoint(
        folder, 5, Particles.create(p0, np.ones(n)), {"step": 5, "records": records}
    )
    params = {
        "material": "tresca",
        "c": 1e4,
        "phi": 0.0,
        "rho": 0.0,
        "width": 2 * b,
        "domain_width": domain,
    }
    (folder / "scene.json").write_text(
        json.dumps({"scene": "strip-footing", "parameters": params})
    )
    return folder


def test_footing_picture_has_the_load_settlement_curve(footing_dir):
    sc, _, _, _, frames = _frames(footing_dir, "stress_yy")
    assert sc.load_curve.shape == (5, 2)
    assert sc.q_reference == pytest.approx((2 + np.pi) * 1e4, rel=1e-12)
    frames.draw(3)
    title = frames.fig._suptitle.get_text()
    assert "settlement s = 3 mm" in title and "s/B = 0.0015" in title
    assert "t = " not in title
    assert "footing (half width b)" in _legend(frames)
    assert "symmetry axis" in _legend(frames) and "fixed base" in _legend(frames)
    ax = frames.curve_ax
    assert ax.get_xlabel() == "footing pressure q [kPa]"
    assert ax.get_ylabel() == "settlement s [mm]"
    assert ax.get_ylim()[0] > ax.get_ylim()[1]  # settlement grows downward
    q, s = ax.get_lines()[0].get_data()
    np.testing.assert_allclose(s, [0, 1, 2, 3, 4, 5])  # mm
    np.testing.assert_allclose(q, np.r_[0, 51 * (1 - np.exp(-np.arange(1, 6)))])
    marker = next(ln for ln in ax.get_lines() if ln.get_label() == "this picture")
    assert marker.get_data()[1][0] == pytest.approx(3.0)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "Prandtl N_c c = 51.42 kPa" in texts
    fig = load_settlement_figure(sc)
    assert fig.axes[0].get_title() == "load-settlement curve"


def test_plot_writes_the_pictures(collapse_dir, footing_dir, tmp_path):
    paths = plot_results(collapse_dir, times=[0, 1], animation="none", out_dir=tmp_path)
    assert [p.name for p in paths] == [
        "stress_yy_t0.png",
        "stress_yy_t1.png",
        "plastic_strain_eq_t0.png",
        "plastic_strain_eq_t1.png",
    ]
    paths = plot_results(
        footing_dir, field=["stress_yy"], animation="none", out_dir=tmp_path / "f"
    )
    assert paths[-1].name == "load_settlement.png"
    from PIL import Image

    for path in paths:
        with Image.open(path) as im:
            im.verify()


def test_detached_grains_and_the_front_of_a_coarse_collapse_are_in_the_frame(
    tmp_path,
):
    """The coarse a = 1 collapse whose 8 stray grains set the 99 % front.

    Its picture used to crop to the meshed body: the grains (inactive, in no
    cell) and the run-out line the legend labels (0.513 m against a main body
    ending at 0.433 m) were off the frame.  Everything the legend names must be
    inside it, the grains drawn apart from the body.
    """
    from skfem_npfem import run_scene

    d = tmp_path / "a1"
    s = run_scene(
        "column-collapse", {"aspect": 1, "spacing": 0.0167, "dt": 0.01}, out=d
    )
    n_free = s["metrics"]["n_inactive_final"]
    assert n_free >= 1
    sc, loaded, _, view, frames = _frames(d, "plastic_strain_eq")
    last = max(loaded.kept)
    frames.draw(last)
    step = loaded.kept[last]
    assert len(step.free) == n_free
    labels = _legend(frames)
    assert f"detached grains (in no cell): {n_free}" in labels
    front = float(next(t for t in labels if t.startswith("run-out"))[20:-2])
    (x0, x1), (y0, y1) = view.xlim, view.ylim
    assert x0 < step.points[:, 0].min() and step.points[:, 0].max() < x1
    assert y0 < step.points[:, 1].min() and step.points[:, 1].max() < y1
    assert x0 < front < x1 and x0 < sc.runout_reference < x1
    # The grains are diamonds with black edges, the body a coloured mesh.
    grains = next(c for c in frames.ax.collections if c.get_label().startswith("det"))
    assert grains.get_offsets().shape == (n_free, 2)
    assert np.allclose(grains.get_edgecolor()[0][:3], 0.0)


def test_snapshot_names_and_messages_say_what_is_drawn(
    collapse_dir, footing_dir, tmp_path
):
    """``--times 100`` (normalised) beyond the last step, and the footing.

    The message used to mix t/sqrt(H0/g) with seconds and the file was named
    after 100, a time it does not show; footing files were named ``_t`` after a
    settlement.
    """
    tau = (H0 / 9.81) ** 0.5
    last = 0.3 / tau  # the last stored step, t = 0.3 s
    with pytest.warns(UserWarning) as caught:
        paths = plot_results(
            collapse_dir,
            times=[100],
            field=["stress_yy"],
            animation="none",
            out_dir=tmp_path,
        )
    shown = float(f"{last:.4g}")
    assert [p.name for p in paths] == [f"stress_yy_t{shown:g}.png"]
    [msg] = [str(w.message) for w in caught if "outside" in str(w.message)]
    assert msg.startswith("t/sqrt(H0/g) = 100 is outside the stored steps (0..")
    assert f"drawing the step at t/sqrt(H0/g) = {shown:g} (t = 0.3 s)" in msg
    paths = plot_results(
        footing_dir,
        times=[0.002, 1.0],
        field=["stress_yy"],
        animation="none",
        out_dir=tmp_path / "f",
    )
    assert [p.name for p in paths[:2]] == [
        "stress_yy_s0.002.png",
        "stress_yy_s0.005.png",
    ]


def cli(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(out):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def test_plot_skips_a_corrupt_vtu_and_refuses_an_all_corrupt_folder(
    collapse_dir, tmp_path
):
    # Reproducer: truncate a result_*.vtu and run plot (meshio called
    # sys.exit(1): 'Error: ...', exit 1, SystemExit in Python).
    d = tmp_path / "c"
    shutil.copytree(collapse_dir, d)
    bad = d / "result_000002.vtu"
    bad.write_bytes(bad.read_bytes()[:3000])
    code, out, err = cli(["plot", str(d), "--animation", "none", "--absolute"])
    assert code == 0, err
    assert err.startswith("note: skipped an unreadable step: ")
    assert str(bad) in err and "Error:" not in out + err
    # the three readable steps (t = 0, 0.1, 0.3 s), two fields each
    names = sorted(Path(p).name for p in out.split())
    assert names == sorted(
        f"{f}_t{t}.png"
        for f in ("stress_yy", "plastic_strain_eq")
        for t in ("0", "0.1", "0.3")
    )
    for f in d.glob("result_*.vtu"):
        f.write_bytes(f.read_bytes()[:100])
    code, _, err = cli(["plot", str(d), "--animation", "none"])
    lines = err.strip().splitlines()
    assert code == 2 and lines[-1].startswith("error: ")
    assert "no readable step" in lines[-1]
