"""The stress-roughness index against a closed form and the reference tool.

References: a checkerboard +-1 on a structured triangle lattice (each interior
node has four axis neighbours of the other sign and two diagonal ones of its
own, so ``s - mean = 4/3 s`` and ``R = 4/3`` exactly); a linear field on the
lattice (``R = 0``); ``x^2`` on the lattice (six neighbours at offsets whose
``dx^2`` sum to ``4 h^2``, so ``s - mean = -2 h^2 / 3``) for the floor of a
field with a checkerboard on top; and an independent implementation of the
definition (``tests/roughness_reference.py``: plain sets and counters) on the
VTU files of a run, which must give the values the scene stored on its step
records (to round-off), as must the public :func:`skfem_npfem.stress_roughness`
on the same files.
"""

from __future__ import annotations

import meshio
import numpy as np
import pytest
from roughness_reference import reference_roughness
from skfem import MeshTri

import skfem_npfem as npfem
from skfem_npfem.io import read_pvd
from skfem_npfem.metrics import (
    MIN_INTERIOR,
    roughness_floor,
    roughness_index,
    stress_roughness,
)
from skfem_npfem.scenes import run_scene


def lattice(n: int = 12) -> MeshTri:
    return MeshTri.init_tensor(*[np.linspace(0.0, 1.0, n + 1)] * 2)


def test_checkerboard_and_linear_field():
    m = lattice()
    i = np.rint(m.p * 12).astype(int)
    board = np.where((i[0] + i[1]) % 2 == 0, 1.0, -1.0)
    r, n = roughness_index(m.t.T, board)
    assert n == 9 * 9  # the nodes two or more rows from the boundary
    assert r == pytest.approx(4.0 / 3.0, rel=1e-12)
    assert roughness_index(m.t.T, 3.0 - 2.0 * m.p[0] + m.p[1])[0] < 1e-14
    # Too small a mesh: no interior particle worth a statistic.
    assert np.isnan(roughness_index(lattice(3).t.T, board[:16])[0])
    # stress_roughness picks the vertical stress (Voigt component 1 in 2D).
    stress = np.zeros((m.p.shape[1], 4))
    stress[:, 1] = board
    assert stress_roughness(m.t.T, stress) == pytest.approx(4.0 / 3.0, rel=1e-12)


def test_floor_is_the_roughness_of_the_smooth_part():
    m = lattice()
    h = 1.0 / 12
    i = np.rint(m.p * 12).astype(int)
    board = np.where((i[0] + i[1]) % 2 == 0, 1.0, -1.0)
    smooth = 1.0 + m.p[0] ** 2
    r_smooth, n = roughness_index(m.t.T, smooth)
    interior = (i.min(axis=0) >= 2) & (i.max(axis=0) <= 10)
    assert n == np.count_nonzero(interior)
    exact = (2.0 * h**2 / 3.0) / np.sqrt(np.mean(smooth[interior] ** 2))
    assert r_smooth == pytest.approx(exact, rel=1e-12)
    # A checkerboard on top makes R large; the floor stays the smooth part's R
    # (the cubic fit of the board on this lattice is nearly zero: 2 %).
    rough = smooth + 0.05 * board
    assert roughness_index(m.t.T, rough)[0] > 5 * exact
    assert roughness_floor(m.p.T, m.t.T, rough) == pytest.approx(exact, rel=0.02)
    # A cubic is fitted exactly, on an irregular mesh too: floor = R.
    rng = np.random.default_rng(0)
    p = m.p + rng.uniform(-0.2 * h, 0.2 * h, m.p.shape) * (i % 12 != 0)
    cubic = 2.0 + p[0] ** 3 - p[0] * p[1] + 0.5 * p[1] ** 2
    r_cubic = roughness_index(m.t.T, cubic)[0]
    assert r_cubic > 1e-3
    assert roughness_floor(p.T, m.t.T, cubic) == pytest.approx(r_cubic, rel=1e-9)


def test_scene_records_equal_the_reference_measure(tmp_path):
    res = run_scene(
        "column-collapse",
        {
            "spacing": 0.04,
            "t_end": 0.04,
            "rest_fraction": 0.0,
            "output_every": 2,
            "method": "spfem",
        },
        out=tmp_path,
    )
    history = {h["step"]: h["stress_roughness"] for h in res["history"]}
    checked = 0
    for _, vtu in read_pvd(tmp_path / "result.pvd")[1:]:
        step = int(vtu.stem.rsplit("_", 1)[1])
        m = meshio.read(vtu)
        cells = np.vstack([c.data for c in m.cells if c.type == "triangle"])
        stress = m.point_data["stress"]
        ref, n = reference_roughness(cells, stress[:, 1])
        assert n >= MIN_INTERIOR
        assert history[step] == pytest.approx(ref, rel=1e-12, abs=1e-15)
        assert npfem.stress_roughness(cells, stress) == history[step]
        checked += 1
    assert checked == 4
    assert res["metrics"]["stress_roughness"] == history[max(history)]
