"""Holes the alpha test opens inside the body, and sealing them (``seal_cavities``).

References: geometry (a lattice with a gap the alpha test cannot bridge has
a hole of known area) and the collapse load of a smooth strip footing, which
on any soil configuration is a property of the configuration alone (a
weightless Tresca soil): the pushed footing's configuration at the start of
one of its load dips, saved from ``footing-penetration`` at its defaults
(``tests/data/footing_dip_start.npz``: step 55, w = 0.6875 B, where the load
fell to 3.60 s_u from 5.83 the step before).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from skfem import MeshTri

from skfem_npfem import ParameterError, Tresca
from skfem_npfem.boundary import wall_x
from skfem_npfem.limit.analysis import limit_analysis
from skfem_npfem.mesh.cavities import sealed_cavities
from skfem_npfem.mesh.delaunay import alpha_shape
from skfem_npfem.mesh.smoothing import nodal_integration
from skfem_npfem.mesh.sources import AlphaShapeMesher, mesh_particles, seal_with

DATA = Path(__file__).resolve().parents[1] / "data"


def lattice_without(hole) -> np.ndarray:
    """A 9 x 9 unit lattice without the points ``hole(x, y)`` marks."""
    g = np.arange(9.0)
    x = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    return x[~hole(x[:, 0], x[:, 1])]


def test_a_hole_inside_the_body_is_sealed():
    # Without the 3 x 3 points round the centre the gap is 4 wide: the alpha
    # test (1.3 h) drops its triangles but the four corner half-cells (right
    # triangles of legs 1, circumradius 0.71): a hole of area 16 - 2 = 14.
    x = lattice_without(lambda a, b: (np.abs(a - 4) <= 1) & (np.abs(b - 4) <= 1))
    opened = alpha_shape(x, 1.0, 1.3)
    assert opened.volume == pytest.approx(64.0 - 14.0, rel=1e-9)
    # It reaches no hull edge, so it is sealed whatever the supports are.
    sealed = alpha_shape(x, 1.0, 1.3, closed=np.zeros(len(x), bool))
    assert sealed.volume == pytest.approx(64.0, rel=1e-9)
    assert sealed.boundary.sum() == 32  # the square's edge only


def test_a_hole_on_the_edge_is_sealed_only_if_the_edge_is_a_support():
    # A notch 2 wide and 4 tall from the left edge (x = 0), its opening on the
    # hull's left side: area 8 less the two inner corners' half-cells.
    x = lattice_without(lambda a, b: (a <= 1) & (np.abs(b - 4) <= 1))
    opened = alpha_shape(x, 1.0, 1.3, closed=np.zeros(len(x), bool))
    assert opened.volume == pytest.approx(64.0 - 7.0, rel=1e-9)
    on_axis = x[:, 0] == 0.0  # a symmetry axis: the soil cannot part from it
    sealed = alpha_shape(x, 1.0, 1.3, closed=on_axis)
    assert sealed.volume == pytest.approx(64.0, rel=1e-9)


class Cloud:
    """What ``seal_with`` reads of the particles: positions and supports."""

    def __init__(self, x: np.ndarray, fixed: np.ndarray) -> None:
        self.x, self.fixed = x, fixed


def test_a_mesher_seals_at_its_supports_and_at_its_walls():
    # The notch on the left edge: the particles there are free (no fixed
    # dof), so only a wall along x = 0 (a cone's axis) closes it.
    x = lattice_without(lambda a, b: (a <= 1) & (np.abs(b - 4) <= 1))
    free = Cloud(x, np.zeros(x.shape, bool))
    plain = AlphaShapeMesher(1.0, 1.3, seal_cavities=True)
    seal_with(plain, free)
    assert plain.triangulate(x).volume == pytest.approx(57.0, rel=1e-9)
    held = Cloud(x, np.column_stack([x[:, 0] == 0.0, np.zeros(len(x), bool)]))
    seal_with(plain, held)  # the axis's particles held in x: a support
    assert plain.triangulate(x).volume == pytest.approx(64.0, rel=1e-9)
    walled = AlphaShapeMesher(
        1.0, 1.3, walls=[wall_x(2, 0.0, facing=1)], seal_cavities=True
    )
    seal_with(walled, free)
    assert walled.triangulate(x).volume == pytest.approx(64.0, rel=1e-9)
    # Without seal_cavities the mesher ignores the supports.
    off = AlphaShapeMesher(1.0, 1.3)
    seal_with(off, held)
    assert off.closed is None and off.triangulate(x).volume == pytest.approx(57.0)


def test_every_mesh_of_a_run_is_told_the_supports():
    # mesh_particles (the step's, a baseline's and the written mesh) gives
    # the mesher the particles' supports before it meshes them: the notch on
    # the held axis is sealed without a seal_with call before.
    x = lattice_without(lambda a, b: (a <= 1) & (np.abs(b - 4) <= 1))

    def area(cloud: Cloud) -> float:
        active, t = mesh_particles(mesher, cloud)
        a, b, c = x[active][t]  # t: (3, n_triangles), into the active particles
        e, f = b - a, c - a
        return 0.5 * np.abs(e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0]).sum()

    mesher = AlphaShapeMesher(1.0, 1.3, seal_cavities=True)
    held = Cloud(x, np.column_stack([x[:, 0] == 0.0, np.zeros(len(x), bool)]))
    assert area(held) == pytest.approx(64.0, rel=1e-9)
    # The supports of the call count, not the last call's.
    assert area(Cloud(x, np.zeros(x.shape, bool))) == pytest.approx(57.0, rel=1e-9)


def test_closed_needs_one_flag_per_particle():
    x = lattice_without(lambda a, b: a < 0)
    with pytest.raises(ParameterError, match="closed"):
        alpha_shape(x, 1.0, 1.3, closed=np.zeros(3, bool))
    with pytest.raises(ParameterError, match="closed"):
        alpha_shape(x, 1.0, 1.3, closed=np.zeros(len(x)))  # not bool
    none = np.empty((0, 3), int)
    assert not sealed_cavities(none, np.zeros(0, bool), x[:0, 0] > 0).any()


def footing_collapse(x, t, fixed, on) -> float:
    """The smooth rigid footing's collapse pressure over s_u on ``x``, ``t``."""
    used = np.unique(t)
    local = np.full(len(x), -1)
    local[used] = np.arange(used.size)
    mesh = MeshTri(np.ascontiguousarray(x[used].T), np.ascontiguousarray(local[t].T))
    ni = nodal_integration(mesh, (0, 1, 3))
    foot = local[on[np.isin(on, used)]]
    free = fixed[used].copy()
    free[foot, 1] = False
    load = np.zeros((used.size, 2))
    load[foot, 1] = -0.5 / foot.size  # s_u b on the half footing (s_u = 1, b = 0.5)
    res = limit_analysis(
        ni,
        [Tresca(E=1.0, nu=0.3, c=1.0)],
        np.zeros(used.size, int),
        load,
        fixed=free,
        tied=[2 * foot + 1],
    )
    return res.multiplier


def test_sealing_restores_the_collapse_load_of_a_dip_step():
    d = np.load(DATA / "footing_dip_start.npz")
    x, fixed, h = d["x"], d["fixed"], float(d["h"])
    b, base = float(d["half_width"]), float(d["base_y"])
    mesher = AlphaShapeMesher(h, float(d["alpha"]), spacing=d["spacing"])
    opened = mesher.triangulate(x).simplices
    sealer = AlphaShapeMesher(
        h, float(d["alpha"]), spacing=d["spacing"], seal_cavities=True
    )

    seal_with(sealer, Cloud(x, fixed))
    sealed = sealer.triangulate(x).simplices
    # The hole under the footing: a few triangles on the symmetry axis half a
    # width below the footing's base, which the sealed mesh keeps.
    extra = sealed[~np.isin(map_rows(sealed), map_rows(opened))]
    centre = x[extra].mean(axis=1)
    assert 2 <= len(extra) <= 12
    assert np.all(centre[:, 0] < 0.3 * b) and np.all(centre[:, 1] < base - 0.5 * b)
    on = np.flatnonzero((x[:, 0] <= b + 1e-9) & (np.abs(x[:, 1] - base) < 0.25 * h))
    q_open = footing_collapse(x, opened, fixed, on)
    q_sealed = footing_collapse(x, sealed, fixed, on)
    # Measured 3.73 and 5.83 s_u (the step before the dip: 5.87; the load of
    # the incremental run there 3.60 and 5.83).  A smooth footing at this
    # depth in weightless clay carries more than Prandtl's 2 + pi at the
    # surface: the open mesh's collapse load is below it, the sealed one's
    # above.
    assert q_open < 0.8 * (2.0 + np.pi) < (2.0 + np.pi) < q_sealed
    assert q_sealed == pytest.approx(5.87, rel=0.05)


def map_rows(t: np.ndarray) -> np.ndarray:
    """One integer per triangle (its sorted vertex ids), to compare meshes."""
    s = np.sort(t, axis=1).astype(np.int64)
    return (s[:, 0] * 100_000 + s[:, 1]) * 100_000 + s[:, 2]
