"""Tests for skfem_npfem.io (VTU/PVD result writer and checkpoints)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import meshio
import numpy as np
import pytest

from skfem_npfem.errors import CheckpointError, ParameterError
from skfem_npfem.io import (
    CHECKPOINT_FORMAT,
    ResultWriter,
    checkpoint_path,
    latest_checkpoint,
    load_checkpoint,
    read_pvd,
    read_step,
    save_checkpoint,
)

P2 = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [5.0, 5.0]])
T2 = np.array([[0, 1, 2], [1, 3, 2]])


def _signed_volumes(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    p = points[tets]
    return np.linalg.det(p[:, 1:] - p[:, :1]) / 6.0


def test_2d_round_trip(tmp_path: Path) -> None:
    """2-D points, cells, point and field data survive meshio.read."""
    w = ResultWriter(tmp_path)
    u = np.arange(10.0).reshape(5, 2)
    s = np.linspace(0.0, 1.0, 5)
    flag = np.array([True, False, True, False, True])
    f = w.write(3, 0.25, P2, T2, {"u": u, "s": s, "flag": flag}, {"nstep": 7})
    assert f == tmp_path / "result_000003.vtu"
    m = meshio.read(f)
    np.testing.assert_array_equal(m.points, np.c_[P2, np.zeros(5)])
    np.testing.assert_array_equal(m.cells_dict["triangle"], T2)
    np.testing.assert_array_equal(m.cells_dict["vertex"], [[4]])
    np.testing.assert_array_equal(m.point_data["u"], np.c_[u, np.zeros(5)])
    np.testing.assert_array_equal(m.point_data["s"], s)
    assert m.point_data["flag"].dtype == np.uint8
    np.testing.assert_array_equal(m.point_data["flag"], [1, 0, 1, 0, 1])
    np.testing.assert_array_equal(m.field_data["TimeValue"], [0.25])
    np.testing.assert_array_equal(m.field_data["nstep"], [7])
    assert w.entries == [(3, 0.25, "result_000003.vtu")]


def test_3d_round_trip_and_tet_orientation(tmp_path: Path) -> None:
    """3-D write: negative tet is flipped, tensors flattened."""
    p = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [9, 9, 9]])
    t = np.array([[0, 2, 1, 3], [1, 2, 3, 4]])  # first tet negatively oriented
    assert _signed_volumes(p, t)[0] < 0
    stress = np.arange(54.0).reshape(6, 3, 3)
    w = ResultWriter(tmp_path / "out3")
    m = read_step(w.write(0, 0.0, p, t, {"v": -p, "stress": stress}))
    np.testing.assert_array_equal(m.points, p)
    tets = m.cells_dict["tetra"]
    assert np.all(_signed_volumes(m.points, tets) > 0)
    assert [sorted(c) for c in tets] == [sorted(c) for c in t]
    np.testing.assert_array_equal(tets[1], t[1])  # positive tet untouched
    np.testing.assert_array_equal(m.cells_dict["vertex"], [[5]])
    np.testing.assert_array_equal(m.point_data["v"], -p)
    np.testing.assert_array_equal(m.point_data["stress"], stress.reshape(6, 9))


def test_no_cells_gives_all_vertices(tmp_path: Path) -> None:
    """Without cells every particle becomes a vertex cell."""
    m = read_step(ResultWriter(tmp_path).write(0, 0.0, P2, None, {}))
    assert list(m.cells_dict) == ["vertex"]
    np.testing.assert_array_equal(m.cells_dict["vertex"].ravel(), np.arange(5))


def _write_steps(w: ResultWriter, steps: list[int]) -> None:
    for k in steps:
        n = 4 + k  # topology changes every step
        rng = np.random.default_rng(k)
        pts = np.r_[P2[:4], rng.random((n - 4, 2)) + 2.0]
        w.write(k, 0.1 * k, pts, T2, {"id": np.arange(n)})


def test_pvd_and_series_index(tmp_path: Path) -> None:
    """The pvd and series files list all steps sorted, with times."""
    w = ResultWriter(tmp_path, basename="run")
    _write_steps(w, [2, 0, 1])
    w.write(1, 0.15, P2, T2, {})  # rewrite of step 1 replaces it
    entries = read_pvd(tmp_path / "run.pvd")
    assert [t for t, _ in entries] == [0.0, 0.15, 0.2]
    assert [f.name for _, f in entries] == [f"run_{k:06d}.vtu" for k in range(3)]
    assert all(f.parent == tmp_path and f.exists() for _, f in entries)
    series = json.loads((tmp_path / "run.vtu.series").read_text())
    assert series["file-series-version"] == "1.0"
    assert [(e["name"], e["time"]) for e in series["files"]] == [
        ("run_000000.vtu", 0.0),
        ("run_000001.vtu", 0.15),
        ("run_000002.vtu", 0.2),
    ]
    text = (tmp_path / "run.pvd").read_text()
    assert 'type="Collection"' in text and str(tmp_path) not in text


def test_pvd_readable_by_pyvista(tmp_path: Path) -> None:
    """PyVista reads the collection with per-step point counts."""
    pv = pytest.importorskip("pyvista")
    w = ResultWriter(tmp_path)
    _write_steps(w, [0, 1, 2])
    reader = pv.get_reader(str(tmp_path / "result.pvd"))
    np.testing.assert_allclose(reader.time_values, [0.0, 0.1, 0.2])
    for k, t in enumerate(reader.time_values):
        reader.set_active_time_value(t)
        assert reader.read()[0].n_points == 4 + k
    series = pv.get_reader(str(tmp_path / "result.vtu.series"))
    np.testing.assert_allclose(series.time_values, [0.0, 0.1, 0.2])


def test_fresh_start_removes_stale_files(tmp_path: Path) -> None:
    """A fresh writer deletes only its own old VTU files."""
    _write_steps(ResultWriter(tmp_path), [0, 1, 2])
    (tmp_path / "other_000001.vtu").write_text("keep me")
    w = ResultWriter(tmp_path)
    assert w.entries == []
    assert read_pvd(tmp_path / "result.pvd") == []
    assert sorted(f.name for f in tmp_path.glob("*.vtu")) == ["other_000001.vtu"]


def test_resume_after_step(tmp_path: Path) -> None:
    """Resuming keeps earlier steps and deletes later ones."""
    _write_steps(ResultWriter(tmp_path), [0, 1, 2, 3])
    w = ResultWriter(tmp_path, resume_after_step=1)
    assert [e[0] for e in w.entries] == [0, 1]
    assert not (tmp_path / "result_000002.vtu").exists()
    assert not (tmp_path / "result_000003.vtu").exists()
    assert [t for t, _ in read_pvd(tmp_path / "result.pvd")] == [0.0, 0.1]
    _write_steps(w, [2])
    assert [t for t, _ in read_pvd(tmp_path / "result.pvd")] == [0.0, 0.1, 0.2]
    assert read_step(tmp_path / "result_000002.vtu").points.shape == (6, 3)


def test_crash_during_vtu_replace_keeps_collection(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A failed replace leaves the old collection intact."""
    w = ResultWriter(tmp_path)
    _write_steps(w, [0, 1])
    pvd_before = (tmp_path / "result.pvd").read_bytes()

    def boom(src: str | os.PathLike, dst: str | os.PathLike) -> None:
        assert Path(src).name.startswith(".tmp_") and Path(src).stat().st_size > 0
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(OSError, match="disk full"):
        _write_steps(w, [2])
    monkeypatch.undo()
    assert (tmp_path / "result.pvd").read_bytes() == pvd_before
    assert not (tmp_path / "result_000002.vtu").exists()
    assert not list(tmp_path.glob(".tmp_*"))
    assert [e[0] for e in w.entries] == [0, 1]
    for _, f in read_pvd(tmp_path / "result.pvd"):
        assert read_step(f).points.shape[1] == 3


def test_stray_tmp_file_after_crash_is_ignored(tmp_path: Path) -> None:
    """A half-written temp file is removed and never listed."""
    _write_steps(ResultWriter(tmp_path), [0, 1])
    stray = tmp_path / ".tmp_result_000002.vtu"
    stray.write_bytes(b"<?xml half a file")
    w = ResultWriter(tmp_path, resume_after_step=1)
    assert not stray.exists()
    files = [f for _, f in read_pvd(tmp_path / "result.pvd")]
    assert [f.name for f in files] == ["result_000000.vtu", "result_000001.vtu"]
    assert [read_step(f).points.shape[0] for f in files] == [4, 5]
    assert len(w.entries) == 2


def test_nan_point_data_names_field(tmp_path: Path) -> None:
    """Non-finite or mis-sized point data raise naming the field."""
    w = ResultWriter(tmp_path)
    bad = np.ones(5)
    bad[2] = np.nan
    with pytest.raises(ParameterError, match="pressure"):
        w.write(0, 0.0, P2, T2, {"pressure": bad})
    with pytest.raises(ParameterError, match="short"):
        w.write(0, 0.0, P2, T2, {"short": np.ones(4)})
    assert not list(tmp_path.glob("*.vtu")) and w.entries == []


def test_bad_geometry_rejected(tmp_path: Path) -> None:
    """Bad cells, points and time raise ParameterError."""
    w = ResultWriter(tmp_path)
    with pytest.raises(ParameterError, match="cells"):
        w.write(0, 0.0, P2, np.array([[0, 1, 7]]), {})
    with pytest.raises(ParameterError, match="points"):
        w.write(0, 0.0, np.ones((3, 4)), None, {})
    with pytest.raises(ParameterError, match="time"):
        w.write(0, np.inf, P2, T2, {})
    with pytest.raises(ParameterError, match="step"):
        w.write(1.5, 0.0, P2, T2, {})
    with pytest.raises(ParameterError, match="step"):
        checkpoint_path(tmp_path, -1)
    with pytest.raises(ParameterError, match="resume_after_step"):
        ResultWriter(tmp_path, resume_after_step=-2)


def test_unwritable_directory(tmp_path: Path) -> None:
    """A path below a regular file is not a writable directory."""
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    with pytest.raises(ParameterError, match="out"):
        ResultWriter(blocker / "sub")
    with pytest.raises(ParameterError, match="writable directory"):
        ResultWriter(blocker)


def test_read_pvd_errors(tmp_path: Path) -> None:
    """Missing or corrupt pvd/vtu files raise CheckpointError."""
    with pytest.raises(CheckpointError, match="does not exist"):
        read_pvd(tmp_path / "missing.pvd")
    bad = tmp_path / "bad.pvd"
    bad.write_text("<VTKFile type='Collection'><Collection>")
    with pytest.raises(CheckpointError, match="corrupt"):
        read_pvd(bad)
    with pytest.raises(CheckpointError, match="does not exist"):
        read_step(tmp_path / "missing.vtu")


def _checkpoint(tmp_path: Path) -> tuple[Path, dict, dict]:
    rng = np.random.default_rng(0)
    arrays = {
        "x": rng.random((50, 2)),
        "v": rng.standard_normal((50, 2)),
        "stress": rng.standard_normal((50, 3, 3)),
        "material": np.arange(50, dtype=np.int32) % 3,
        "active": np.arange(50) % 2 == 0,
    }
    meta = {"step": 12, "time": 0.012, "dt": np.float64(1e-3), "scene": "dam"}
    meta["parameters"] = {"E": 1e7, "nu": 0.3, "g": [0.0, -9.81]}
    path = save_checkpoint(checkpoint_path(tmp_path, 12), arrays, meta)
    return path, arrays, meta


def test_checkpoint_round_trip(tmp_path: Path) -> None:
    """Arrays (dtype and values) and meta round-trip exactly."""
    path, arrays, meta = _checkpoint(tmp_path)
    assert path.name == "checkpoint_000012.npz"
    loaded, meta2 = load_checkpoint(path)
    assert sorted(loaded) == sorted(arrays)
    for k, a in arrays.items():
        assert loaded[k].dtype == a.dtype
        np.testing.assert_array_equal(loaded[k], a)
    assert meta2 == {**meta, "dt": 1e-3}
    assert not list(tmp_path.glob(".tmp_*"))


def test_truncated_checkpoint(tmp_path: Path) -> None:
    """A checkpoint cut at any length raises CheckpointError."""
    path, _, _ = _checkpoint(tmp_path)
    data = path.read_bytes()
    for cut in (10, len(data) // 3, len(data) // 2, len(data) - 30, len(data) - 1):
        path.write_bytes(data[:cut])
        with pytest.raises(CheckpointError, match=r"checkpoint_000012\.npz.*truncated"):
            load_checkpoint(path)


def test_random_bytes_missing_and_empty_checkpoint(tmp_path: Path) -> None:
    """Junk, empty, missing and .npy files raise."""
    junk = tmp_path / "checkpoint_000001.npz"
    junk.write_bytes(np.random.default_rng(1).bytes(4096))
    with pytest.raises(CheckpointError, match="not an npz"):
        load_checkpoint(junk)
    junk.write_bytes(b"")
    with pytest.raises(CheckpointError, match="not an npz"):
        load_checkpoint(junk)
    with pytest.raises(CheckpointError, match="does not exist"):
        load_checkpoint(tmp_path / "nope.npz")
    npy = tmp_path / "single.npz"
    with open(npy, "wb") as f:
        np.save(f, np.ones(3))
    with pytest.raises(CheckpointError, match="not an npz"):
        load_checkpoint(npy)


def test_checkpoint_format_and_content_errors(tmp_path: Path) -> None:
    """Version, metadata and NaN problems are detected."""
    p = tmp_path / "c.npz"
    np.savez(p, x=np.ones(3), __meta__=np.array("{}"), __format__=np.array("x/9"))
    with pytest.raises(CheckpointError, match="unknown format version 'x/9'"):
        load_checkpoint(p)
    np.savez(p, x=np.ones(3), __meta__=np.array("{}"))
    with pytest.raises(CheckpointError, match="__format__"):
        load_checkpoint(p)
    fmt = np.array(CHECKPOINT_FORMAT)
    np.savez(p, x=np.ones(3), __meta__=np.array("{bad"), __format__=fmt)
    with pytest.raises(CheckpointError, match="metadata"):
        load_checkpoint(p)
    np.savez(p, x=np.array([1.0, np.inf]), __meta__=np.array("{}"), __format__=fmt)
    with pytest.raises(CheckpointError, match="'x' has NaN/inf"):
        load_checkpoint(p)
    with pytest.raises(ParameterError, match="x"):
        save_checkpoint(p, {"x": np.array([np.nan])}, {})
    with pytest.raises(ParameterError, match="meta"):
        save_checkpoint(p, {}, {"f": object()})


def test_latest_checkpoint(tmp_path: Path) -> None:
    """The checkpoint with the largest step number is found."""
    assert latest_checkpoint(tmp_path) is None
    assert latest_checkpoint(tmp_path / "missing") is None
    for k in (9, 120, 30):
        save_checkpoint(checkpoint_path(tmp_path, k), {"x": np.zeros(1)}, {"step": k})
    (tmp_path / ".tmp_checkpoint_000999.npz").write_bytes(b"junk")
    assert latest_checkpoint(tmp_path) == tmp_path / "checkpoint_000120.npz"
    assert load_checkpoint(latest_checkpoint(tmp_path))[1]["step"] == 120
