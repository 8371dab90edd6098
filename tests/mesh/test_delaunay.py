"""Tests of the Delaunay/alpha-shape remeshing against exact references.

Every assertion states its tolerance.  Lattice spacings and block sizes are
chosen so that the exact kept area/volume and boundary measure are known in
closed form.
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull, Delaunay
from skfem import MeshTet, MeshTri

from skfem_npfem.errors import NpfemError, ParameterError
from skfem_npfem.mesh.delaunay import Triangulation, _simplex_geometry, alpha_shape
from skfem_npfem.mesh.surface import boundary_normals, free_surface

# --------------------------------------------------------------------------- #
# helpers (independent of the implementation)


def lattice(n: int, d: int, lo: float = 0.0, hi: float = 1.0) -> np.ndarray:
    """Regular (n+1)^d lattice on [lo, hi]^d, spacing (hi - lo) / n."""
    g = np.linspace(lo, hi, n + 1)
    return np.stack(np.meshgrid(*[g] * d, indexing="ij"), axis=-1).reshape(-1, d)


def signed_volumes(x: np.ndarray, s: np.ndarray) -> np.ndarray:
    d = x.shape[1]
    e = x[s[:, 1:]] - x[s[:, :1]]
    return np.linalg.det(e) / math.factorial(d)


def facet_measure(x: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Length (2D) or area (3D) of facets."""
    if x.shape[1] == 2:
        return np.linalg.norm(x[f[:, 1]] - x[f[:, 0]], axis=1)
    c = np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]])
    return 0.5 * np.linalg.norm(c, axis=1)


def check_invariants(tri: Triangulation) -> None:
    """Structural invariants that hold for every triangulation."""
    x, s, d = tri.points, tri.simplices, tri.dim
    n = x.shape[0]
    assert s.shape[1] == d + 1
    # positive orientation, volume = sum of simplex volumes (rel 1e-12)
    vols = signed_volumes(x, s)
    assert np.all(vols > 0.0)
    assert np.isfinite(tri.volume)
    assert tri.volume == pytest.approx(vols.sum(), rel=1e-12, abs=1e-300)
    # active / compaction consistency (exact)
    expected_active = np.zeros(n, bool)
    expected_active[s.ravel()] = True
    np.testing.assert_array_equal(tri.active, expected_active)
    np.testing.assert_array_equal(tri.active_index, np.flatnonzero(expected_active))
    np.testing.assert_array_equal(tri.active_index[tri.local_simplices], s)
    # each boundary facet belongs to exactly one kept simplex (exact)
    f = tri.boundary_facets
    assert f.shape[1] == d
    if s.shape[0]:
        faces = np.concatenate([np.delete(s, j, axis=1) for j in range(d + 1)], axis=0)
        keys, counts = np.unique(np.sort(faces, axis=1), axis=0, return_counts=True)
        lookup = {tuple(k): c for k, c in zip(keys.tolist(), counts, strict=True)}
        assert all(lookup.get(tuple(k)) == 1 for k in np.sort(f, axis=1).tolist())
    expected_boundary = np.zeros(n, bool)
    expected_boundary[f.ravel()] = True
    np.testing.assert_array_equal(tri.boundary, expected_boundary)
    assert not np.any(tri.boundary & ~tri.active)
    # outward-oriented boundary is closed: every oriented ridge is matched by
    # its reverse (2D: in-degree == out-degree of every vertex)
    if d == 2:
        out_deg = np.bincount(f[:, 0], minlength=n)
        in_deg = np.bincount(f[:, 1], minlength=n)
        np.testing.assert_array_equal(out_deg, in_deg)
    elif f.shape[0]:
        edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        # as multisets: non-manifold edges (bodies touching along an edge)
        # carry several facet pairs
        fwd = Counter(map(tuple, edges.tolist()))
        assert all(fwd[(b, a)] == c for (a, b), c in fwd.items())


def boundary_measure(tri: Triangulation) -> float:
    return float(facet_measure(tri.points, tri.boundary_facets).sum())


def on_box_surface(x: np.ndarray, lo: float, hi: float, tol: float) -> np.ndarray:
    return np.any((np.abs(x - lo) < tol) | (np.abs(x - hi) < tol), axis=1)


# --------------------------------------------------------------------------- #
# Alpha shape of a lattice: unit square


@pytest.mark.parametrize("alpha", [0.8, 1.3, 2.0])
def test_square_lattice_exact(alpha: float) -> None:
    n = 10
    h = 1.0 / n
    x = lattice(n, 2)
    tri = alpha_shape(x, h, alpha)
    check_invariants(tri)
    assert tri.volume == pytest.approx(1.0, abs=1e-10)
    assert boundary_measure(tri) == pytest.approx(4.0, abs=1e-10)
    assert tri.simplices.shape[0] == 2 * n * n
    assert tri.active.all()
    assert tri.n_components() == 1
    np.testing.assert_array_equal(tri.boundary, on_box_surface(x, 0.0, 1.0, 1e-12))
    np.testing.assert_array_equal(tri.points, x)


@pytest.mark.parametrize("alpha", [1.3, 2.0])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_square_lattice_jittered_interior(alpha: float, seed: int) -> None:
    # Interior particles moved by up to 0.3 h; the boundary ones stay on the
    # sides so the domain is still exactly the unit square.  (alpha = 0.8 is
    # not tested here: such a cloud has Delaunay triangles with R up to ~0.97 h.)
    n = 10
    h = 1.0 / n
    x = lattice(n, 2)
    interior = ~on_box_surface(x, 0.0, 1.0, 1e-12)
    rng = np.random.default_rng(seed)
    ang = rng.uniform(0.0, 2.0 * np.pi, interior.sum())
    rad = 0.3 * h * np.sqrt(rng.uniform(0.0, 1.0, interior.sum()))
    x[interior] += rad[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])
    tri = alpha_shape(x, h, alpha)
    check_invariants(tri)
    assert tri.volume == pytest.approx(1.0, abs=1e-10)
    assert boundary_measure(tri) == pytest.approx(4.0, abs=1e-10)
    assert tri.active.all()
    assert tri.n_components() == 1


def test_mesh_is_built_on_active_particles() -> None:
    # An isolated particle in the middle of the index range must not shift the
    # skfem numbering (skfem's nvertices is max(t) + 1).
    n = 8
    h = 1.0 / n
    x = lattice(n, 2)
    x = np.insert(x, 20, [[5.0, 5.0]], axis=0)
    tri = alpha_shape(x, h)
    mesh = tri.mesh()
    assert isinstance(mesh, MeshTri)
    assert mesh.nvertices == tri.active_index.size == x.shape[0] - 1
    np.testing.assert_array_equal(mesh.p, x[tri.active_index].T)
    np.testing.assert_array_equal(mesh.t, tri.local_simplices.T)
    np.testing.assert_array_equal(tri.active_index[mesh.t].T, tri.simplices)
    assert np.all(mesh.orientation() > 0)
    detA = mesh.mapping().detA
    assert np.all(detA > 0.0)
    assert np.sum(detA) / 2.0 == pytest.approx(1.0, abs=1e-12)


def test_arrays_are_read_only() -> None:
    tri = alpha_shape(lattice(3, 2), 1.0 / 3)
    with pytest.raises(ValueError):
        tri.simplices[0, 0] = 1


# --------------------------------------------------------------------------- #
# geometry of the alpha test


def test_l_shape_reflex_corner() -> None:
    # L = [0, 2]^2 minus (1, 2]^2 on a lattice of spacing h, area 3.
    # Exact alpha-shape reference: the reflex corner cell has three of its four
    # corners present, so its half-cell triangle (1,1), (1+h,1), (1,1+h) has
    # R = h / sqrt(2) -- the same as every lattice triangle -- and is kept for
    # any alpha that keeps the lattice.  The next triangle into the notch has
    # R = sqrt(10)/2 h = 1.58 h and is rejected for alpha < 1.58.  So the kept
    # area is exactly 3 + h^2 / 2 and the notch is otherwise empty.
    h = 0.1
    x = lattice(20, 2, 0.0, 2.0)
    x = x[~((x[:, 0] > 1.0 + 1e-9) & (x[:, 1] > 1.0 + 1e-9))]
    for alpha in (0.8, 1.3, 1.5):
        tri = alpha_shape(x, h, alpha)
        check_invariants(tri)
        assert tri.volume == pytest.approx(3.0 + 0.5 * h * h, abs=1e-10)
        perimeter = 8.0 - 2.0 * h + math.sqrt(2.0) * h
        assert boundary_measure(tri) == pytest.approx(perimeter, abs=1e-10)
        centroids = tri.points[tri.simplices].mean(axis=1)
        in_notch = np.all(centroids > 1.0 + 1e-9, axis=1)
        assert in_notch.sum() == 1
        corner = np.sort(tri.points[tri.simplices[in_notch][0]], axis=0)
        np.testing.assert_allclose(
            corner, [[1.0, 1.0], [1.0, 1.0], [1.0 + h, 1.0 + h]], atol=1e-12
        )
        assert tri.n_components() == 1
        assert tri.active.all()
    # alpha = 2 accepts the R = 1.58 h triangles as well: 1.5 more cells.
    tri = alpha_shape(x, h, 2.0)
    assert tri.volume == pytest.approx(3.0 + 2.0 * h * h, abs=1e-10)


def test_two_blocks_separated_by_gap() -> None:
    # Blocks [0,1]^2 and [1+3h, 2+3h] x [0,1]: a triangle spanning the 3h gap
    # has diameter >= 3h, i.e. R >= 1.5h.  The Delaunay gap triangles are
    # halves of 3h x h rectangles, R = sqrt(10)/2 h = 1.58 h.
    h = 0.1
    a = lattice(10, 2)
    b = a + np.array([1.0 + 3.0 * h, 0.0])
    x = np.vstack([a, b])
    tri = alpha_shape(x, h, 1.3)
    check_invariants(tri)
    assert tri.n_components() == 2
    assert tri.volume == pytest.approx(2.0, abs=1e-10)
    assert boundary_measure(tri) == pytest.approx(8.0, abs=1e-10)
    assert tri.active.all()
    # With alpha = 1.6 > 1.58 the gap is filled with a 3h x 1 strip.
    tri = alpha_shape(x, h, 1.6)
    assert tri.n_components() == 1
    assert tri.volume == pytest.approx(2.0 + 3.0 * h, abs=1e-10)


def test_far_particle_is_inactive_and_rest_unaffected() -> None:
    n = 10
    h = 1.0 / n
    x0 = lattice(n, 2)
    ref = alpha_shape(x0, h)
    k = x0.shape[0]
    x = np.vstack([x0, [[0.5, 1.0 + 10.0 * h]]])
    tri = alpha_shape(x, h)
    check_invariants(tri)
    assert not tri.active[k]
    assert not tri.boundary[k]
    assert tri.active[:k].all()
    assert tri.volume == pytest.approx(ref.volume, abs=1e-14)
    # identical simplices: the tie-breaking jitter of the other particles does
    # not depend on the extra one
    np.testing.assert_array_equal(
        np.unique(np.sort(tri.simplices, axis=1), axis=0),
        np.unique(np.sort(ref.simplices, axis=1), axis=0),
    )
    np.testing.assert_array_equal(tri.boundary[:k], ref.boundary)
    assert np.all(boundary_normals(tri)[k] == 0.0)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_near_coincident_duplicates(seed: int) -> None:
    # A lattice plus copies of 5 particles shifted by 1e-8 h, plus 2 exact
    # duplicates.  Nothing may be inf/nan, the kept area stays 1 (abs 1e-8),
    # at least one of every twin pair stays active, and no internal boundary
    # appears (boundary particles all lie on the square's sides, abs 1e-6 h).
    n = 10
    h = 1.0 / n
    x0 = lattice(n, 2)
    rng = np.random.default_rng(seed)
    idx = rng.choice(x0.shape[0], 7, replace=False)
    shift = rng.standard_normal((5, 2))
    shift *= 1e-8 * h / np.linalg.norm(shift, axis=1, keepdims=True)
    x = np.vstack([x0, x0[idx[:5]] + shift, x0[idx[5:]]])
    with np.errstate(all="raise"):
        tri = alpha_shape(x, h)
        nrm = boundary_normals(tri)
    check_invariants(tri)
    assert np.isfinite(tri.volume)
    assert np.all(np.isfinite(nrm))
    assert tri.volume == pytest.approx(1.0, abs=1e-8)
    twin = np.arange(x0.shape[0], x.shape[0])
    assert np.all(tri.active[idx] | tri.active[twin])
    assert np.delete(tri.active, np.concatenate([idx, twin])).all()
    assert np.all(on_box_surface(x[tri.boundary], 0.0, 1.0, 1e-6 * h))
    assert tri.n_components() == 1
    mesh = tri.mesh()
    assert np.all(np.isfinite(mesh.p))
    detA = mesh.mapping().detA
    assert np.all(detA > 0.0) and np.all(np.isfinite(detA))


def test_collinear_points_give_empty_triangulation() -> None:
    x = np.column_stack([np.linspace(0.0, 1.0, 6), np.zeros(6)])
    tri = alpha_shape(x, 0.2, jitter=0.0)
    check_invariants(tri)
    assert tri.simplices.shape == (0, 3)
    assert tri.volume == 0.0
    assert not tri.active.any()
    assert tri.n_components() == 0
    with pytest.raises(NpfemError, match="no simplices"):
        tri.mesh()


def test_min_quality_drops_slivers_without_internal_boundary() -> None:
    # A second particle 1e-4 h from an interior lattice particle forms two thin
    # triangles with it (quality ~ 1.5e-4 < 1e-3).  They are dropped from the
    # mesh, losing at most their area (< 1e-4 h^2), but being buried in the
    # body they open no internal boundary: the boundary is still the square.
    n = 6
    h = 1.0 / n
    x0 = lattice(n, 2)
    twin = x0[24] + 1e-4 * h * np.array([math.cos(0.3), math.sin(0.3)])
    x = np.vstack([x0, twin])
    tri = alpha_shape(x, h)
    check_invariants(tri)
    assert tri.active.all()
    assert boundary_measure(tri) == pytest.approx(4.0, abs=1e-10)
    np.testing.assert_array_equal(tri.boundary, on_box_surface(x, 0.0, 1.0, 1e-12))
    assert 1.0 - 1e-4 * h * h < tri.volume < 1.0
    keep_all = alpha_shape(x, h, min_quality=0.0)
    check_invariants(keep_all)
    assert keep_all.volume == pytest.approx(1.0, abs=1e-12)
    assert keep_all.simplices.shape[0] == tri.simplices.shape[0] + 2


def test_quality_measure_exact() -> None:
    # quality = |e| / volume of the regular simplex with the same circumradius
    tri2 = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, math.sqrt(3.0) / 2.0]])
    vol, rad = _simplex_geometry(tri2, np.array([[0, 1, 2]]), 0.0)
    assert rad[0] == pytest.approx(1.0 / math.sqrt(3.0), rel=1e-14)
    assert vol[0] / (3.0 * math.sqrt(3.0) / 4.0 * rad[0] ** 2) == pytest.approx(
        1.0, rel=1e-13
    )
    tet = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float)
    vol, rad = _simplex_geometry(tet, np.array([[0, 1, 2, 3]]), 0.0)
    assert rad[0] == pytest.approx(math.sqrt(3.0), rel=1e-14)
    assert abs(vol[0]) == pytest.approx(8.0 / 3.0, rel=1e-14)
    q = abs(vol[0]) / (8.0 * math.sqrt(3.0) / 27.0 * rad[0] ** 3)
    assert q == pytest.approx(1.0, rel=1e-13)
    # a flat simplex has infinite circumradius, not nan
    flat = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    vol, rad = _simplex_geometry(flat, np.array([[0, 1, 2]]), 1e-12)
    assert vol[0] == 0.0 and rad[0] == math.inf


def test_invariance_under_scaling_and_translation() -> None:
    x = np.random.default_rng(5).random((300, 2))
    h = 1.0 / math.sqrt(300)
    a = alpha_shape(x, h, 1.4)
    b = alpha_shape(1e3 * x + [5e3, -2e3], 1e3 * h, 1.4)
    np.testing.assert_array_equal(a.simplices, b.simplices)
    assert b.volume == pytest.approx(1e6 * a.volume, rel=1e-10)
    c = alpha_shape(x, h, 1.4)
    np.testing.assert_array_equal(a.simplices, c.simplices)


# --------------------------------------------------------------------------- #
# normals and free surface


def test_boundary_normals_square() -> None:
    n = 4
    h = 1.0 / n
    x = lattice(n, 2)
    tri = alpha_shape(x, h)
    nrm = boundary_normals(tri)
    eps = 1e-12
    left, right = np.abs(x[:, 0]) < eps, np.abs(x[:, 0] - 1) < eps
    bottom, top = np.abs(x[:, 1]) < eps, np.abs(x[:, 1] - 1) < eps
    expected = np.zeros_like(x)
    expected[left, 0] -= 1.0
    expected[right, 0] += 1.0
    expected[bottom, 1] -= 1.0
    expected[top, 1] += 1.0
    norm = np.linalg.norm(expected, axis=1)
    expected[norm > 0] /= norm[norm > 0, None]  # corners: bisector
    np.testing.assert_allclose(nrm, expected, atol=1e-12)


def test_free_surface_excludes_walls() -> None:
    n = 5
    h = 1.0 / n
    x = lattice(n, 2)
    tri = alpha_shape(x, h)
    wall = (x[:, 1] < 1e-12) | (x[:, 0] < 1e-12) | (x[:, 0] > 1 - 1e-12)
    fs = free_surface(tri, wall)
    top_open = (x[:, 1] > 1 - 1e-12) & ~wall
    np.testing.assert_array_equal(fs, top_open)
    np.testing.assert_array_equal(free_surface(tri), tri.boundary)
    with pytest.raises(ParameterError, match="on_wall"):
        free_surface(tri, wall[:-1])
    with pytest.raises(ParameterError, match="on_wall"):
        free_surface(tri, wall.astype(float))


# --------------------------------------------------------------------------- #
# 3D


def test_cube_lattice_exact() -> None:
    n = 6
    h = 1.0 / n
    x = lattice(n, 3)
    tri = alpha_shape(x, h)
    check_invariants(tri)
    assert tri.volume == pytest.approx(1.0, abs=1e-10)
    assert boundary_measure(tri) == pytest.approx(6.0, abs=1e-10)
    assert tri.active.all()
    assert tri.n_components() == 1
    np.testing.assert_array_equal(tri.boundary, on_box_surface(x, 0.0, 1.0, 1e-12))
    mesh = tri.mesh()
    assert isinstance(mesh, MeshTet)
    np.testing.assert_array_equal(mesh.t, tri.local_simplices.T)
    detA = mesh.mapping().detA
    assert np.all(detA > 0.0)
    assert np.sum(detA) / 6.0 == pytest.approx(1.0, abs=1e-12)
    # face-centre particle normals are the axis normals (abs 1e-12)
    nrm = boundary_normals(tri)
    i = np.flatnonzero(np.all(np.isclose(x, [0.5, 0.5, 1.0]), axis=1))[0]
    np.testing.assert_allclose(nrm[i], [0.0, 0.0, 1.0], atol=1e-12)
    # a cubic lattice needs alpha > sqrt(3)/2: below it nothing survives
    assert alpha_shape(x, h, 0.85).simplices.shape[0] == 0


def test_ball_volume_bounds() -> None:
    # Lattice particles inside the unit ball.  Exact bounds: every lattice cube
    # with all 8 corners present is kept (its tets have R = sqrt(3)/2 h), and
    # nothing outside the convex hull can be.
    h = 0.2
    x = lattice(10, 3, -1.0, 1.0)
    x = x[np.linalg.norm(x, axis=1) <= 1.0 + 1e-12]
    lo_corner = lattice(9, 3, -1.0, 0.8)
    cube_corners = lo_corner[:, None, :] + h * lattice(1, 3)[None]
    full = np.all(np.linalg.norm(cube_corners, axis=2) <= 1.0 + 1e-12, axis=1)
    lower = full.sum() * h**3
    upper = ConvexHull(x).volume
    for alpha in (1.3, 2.0):
        tri = alpha_shape(x, h, alpha)
        check_invariants(tri)
        assert lower - 1e-12 <= tri.volume <= upper + 1e-12
        assert tri.n_components() == 1
        assert tri.active.all()
    big = alpha_shape(x, h, 1e9, min_quality=0.0)
    assert big.volume == pytest.approx(upper, rel=1e-9)


def test_random_ball_3d_closed_surface() -> None:
    rng = np.random.default_rng(3)
    m = 1500
    v = rng.standard_normal((m, 3))
    x = v / np.linalg.norm(v, axis=1, keepdims=True) * rng.random((m, 1)) ** (1 / 3)
    h = (4.0 / 3.0 * math.pi / m) ** (1.0 / 3.0)
    for min_quality in (1e-3, 3e-2):
        tri = alpha_shape(x, h, 1.5, min_quality=min_quality)
        check_invariants(tri)  # includes: boundary surface is closed
        assert 0.0 < tri.volume <= ConvexHull(x).volume + 1e-12


# --------------------------------------------------------------------------- #
# input validation


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"points": [[0, 0], [1, 0], [np.nan, 1]]}, "points"),
        ({"points": np.zeros((10, 4))}, "points"),
        ({"points": np.zeros((10, 1))}, "points"),
        ({"points": np.zeros(10)}, "points"),
        ({"points": [[0, 0], [1, 0]]}, "points"),
        ({"points": np.eye(3)}, "points"),
        ({"points": np.ones((4, 2)) * 1j}, "points"),
        ({"points": [["a", "b"]] * 4}, "points"),
        ({"points": [[0, 0], [1, 0], [0, np.inf]]}, "points"),
        ({"h": 0.0}, "h"),
        ({"h": -1.0}, "h"),
        ({"h": np.nan}, "h"),
        ({"h": np.inf}, "h"),
        ({"h": "1"}, "h"),
        ({"alpha": 0.0}, "alpha"),
        ({"alpha": -1.3}, "alpha"),
        ({"alpha": np.nan}, "alpha"),
        ({"min_quality": -0.1}, "min_quality"),
        ({"min_quality": 1.5}, "min_quality"),
        ({"jitter": -1e-6}, "jitter"),
        ({"jitter": np.inf}, "jitter"),
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
    ],
)
def test_bad_input_raises(kwargs: dict, name: str) -> None:
    args = {"points": lattice(2, 2), "h": 0.5}
    args.update(kwargs)
    with pytest.raises(ParameterError, match=name) as info:
        alpha_shape(**args)
    assert info.value.name == name
    assert isinstance(info.value, ValueError)


def test_bad_triangulation_argument() -> None:
    with pytest.raises(ParameterError, match="tri"):
        boundary_normals(np.zeros((3, 2)))  # type: ignore[arg-type]


# --------------------------------------------------------------------------- #
# property test (2D random clouds)


@st.composite
def clouds(draw: st.DrawFn) -> np.ndarray:
    n = draw(st.integers(20, 200))
    seed = draw(st.integers(0, 2**32 - 1))
    kind = draw(st.sampled_from(["uniform", "snapped", "stretched", "clustered"]))
    rng = np.random.default_rng(seed)
    x = rng.random((n, 2))
    if kind == "snapped":  # duplicates, collinear and co-circular points
        x = np.round(x * 8.0) / 8.0
    elif kind == "stretched":
        x[:, 1] *= 0.05
    elif kind == "clustered":
        x = np.vstack([x[: n // 2] * 0.1, x[n // 2 :]])
    # at least three non-collinear points so that the hull exists
    x = np.vstack([x, [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]])
    return x


@settings(max_examples=60, deadline=None)
@given(x=clouds(), alpha=st.sampled_from([0.9, 1.3, 2.0, 4.0]))
def test_property_random_clouds(x: np.ndarray, alpha: float) -> None:
    hull = ConvexHull(x)
    h = math.sqrt(hull.volume / x.shape[0])
    tri = alpha_shape(x, h, alpha)
    check_invariants(tri)
    assert tri.volume <= hull.volume * (1.0 + 1e-12)
    # alpha -> infinity (and no quality filter): the convex hull, rel 1e-9
    big = alpha_shape(x, h, 1e12, min_quality=0.0)
    check_invariants(big)
    assert big.volume == pytest.approx(hull.volume, rel=1e-9)
    assert big.n_components() == 1
    assert boundary_measure(big) == pytest.approx(hull.area, rel=1e-9)


def test_property_reference_delaunay() -> None:
    # For points in general position the triangulation is scipy's Delaunay
    # triangulation (exact set equality).
    x = np.random.default_rng(11).random((400, 2))
    ref = Delaunay(x).simplices
    tri = alpha_shape(x, 0.05, 1e9, min_quality=0.0)
    np.testing.assert_array_equal(
        np.unique(np.sort(tri.simplices, axis=1), axis=0),
        np.unique(np.sort(ref, axis=1), axis=0),
    )


def test_near_lattice_3d_positions_that_break_qhull_triangulated_mode():
    # Quarter-cylinder lattice (R = 0.2 m, 13 spacings over R, 3 942 particles)
    # after one small PFEM step (displacements <= 3.2e-5 m = 0.2 % of h): qhull's
    # "Qt" mode stops with a "twisted facet" precision error on these positions,
    # which used to leave the alpha shape with no simplex at all.  The joggled
    # fallback must mesh every particle, reproducibly, with the lattice's volume
    # (to 1e-3: the displacements change it by ~1e-4).
    data = np.load(Path(__file__).parents[1] / "data" / "qhull_twisted_facet_3d.npz")
    x, h = data["x"], float(data["h"])
    tri = alpha_shape(x, h)
    assert tri.active.all()
    again = alpha_shape(x, h)
    np.testing.assert_array_equal(tri.simplices, again.simplices)
    nr, radius = 13, 0.2
    g = np.arange(nr + 1) * h
    gz = np.arange(round(0.4 / h) + 1) * h
    lat = np.stack(np.meshgrid(g, g, gz, indexing="ij"), axis=-1).reshape(-1, 3)
    lat = lat[lat[:, 0] ** 2 + lat[:, 1] ** 2 <= radius**2 * (1 + 1e-9)]
    assert lat.shape == x.shape and np.abs(x - lat).max() < 3.2e-5
    ref = alpha_shape(lat, h).volume
    assert abs(tri.volume / ref - 1) < 1e-3


def _facet_counts(simplices: np.ndarray) -> Counter:
    d = simplices.shape[1] - 1
    return Counter(
        tuple(sorted(np.delete(s, j))) for s in simplices for j in range(d + 1)
    )


def test_near_cubic_lattice_keeps_buried_slivers_conforming() -> None:
    # A cubic lattice moved by 1e-4 h (a body one small step after release):
    # its cubes split along different face diagonals with slivers (quality
    # ~1e-4) between them.  Dropped (the default), the kept tetrahedra do not
    # match across those faces: facets used by one kept tetrahedron that are
    # not on the boundary.  Kept (keep_buried_slivers), every facet is shared
    # by two tetrahedra except the boundary ones, the boundary is unchanged
    # and the volume is the cube's to the size of the displacements.
    n = 6
    h = 1.0 / n
    x0 = lattice(n, 3)
    x = x0 + 1e-4 * h * np.random.default_rng(1).uniform(-1.0, 1.0, x0.shape)
    dropped = alpha_shape(x, h)
    kept = alpha_shape(x, h, keep_buried_slivers=True)
    for tri in (dropped, kept):
        check_invariants(tri)
        np.testing.assert_array_equal(tri.boundary, on_box_surface(x, 0, 1, 2e-4 * h))
        assert boundary_measure(tri) == pytest.approx(6.0, abs=1e-4)
    bnd = {tuple(sorted(f)) for f in kept.boundary_facets}
    once = {f for f, c in _facet_counts(kept.simplices).items() if c == 1}
    assert once == bnd
    assert max(_facet_counts(kept.simplices).values()) == 2
    once_dropped = {f for f, c in _facet_counts(dropped.simplices).items() if c == 1}
    assert len(once_dropped - {tuple(sorted(f)) for f in dropped.boundary_facets}) > 0
    assert kept.simplices.shape[0] > dropped.simplices.shape[0]
    assert kept.volume == pytest.approx(1.0, abs=6 * 1e-4 * h)
    # a regular lattice has no slivers: both rules give the same mesh
    np.testing.assert_array_equal(
        alpha_shape(x0, h).simplices,
        alpha_shape(x0, h, keep_buried_slivers=True).simplices,
    )
    # a uniform graded spacing is the plain alpha test
    graded = alpha_shape(x, h, keep_buried_slivers=True, h_local=np.full(len(x), h))
    np.testing.assert_array_equal(graded.simplices, kept.simplices)


def test_keep_buried_slivers_drops_surface_slivers() -> None:
    # The top face of a cubic lattice moved up and down by 1e-4 h: flat
    # slivers form on it, open to the outside.  min_quality=0 meshes them
    # (16 more tetrahedra); keep_buried_slivers leaves them out, as the
    # default does, because they are not buried.
    n = 4
    h = 1.0 / n
    x = lattice(n, 3)
    top = np.flatnonzero(np.isclose(x[:, 2], 1.0))
    x[top, 2] += 1e-4 * h * np.random.default_rng(0).uniform(-1.0, 1.0, top.size)
    default = alpha_shape(x, h)
    kept = alpha_shape(x, h, keep_buried_slivers=True)
    every = alpha_shape(x, h, min_quality=0.0)
    check_invariants(kept)
    np.testing.assert_array_equal(kept.simplices, default.simplices)
    assert every.simplices.shape[0] > kept.simplices.shape[0]


def test_quarter_cylinder_after_one_step_meshes_conforming() -> None:
    # The quarter-cylinder lattice after one small step (the qhull data above):
    # with the buried slivers dropped, thousands of facets of kept tetrahedra
    # have no neighbour and are not on the boundary (6 056 with scipy 1.x's
    # qhull: a non-conforming mesh); meshed, every facet has two tetrahedra
    # except the boundary's, the same facets either way.
    data = np.load(Path(__file__).parents[1] / "data" / "qhull_twisted_facet_3d.npz")
    x, h = data["x"], float(data["h"])
    boundaries = []
    for keep in (False, True):
        tri = alpha_shape(x, h, keep_buried_slivers=keep)
        bnd = {tuple(sorted(f)) for f in tri.boundary_facets}
        once = {f for f, c in _facet_counts(tri.simplices).items() if c == 1}
        assert bnd <= once
        assert (len(once - bnd) > 1000) if not keep else (once == bnd)
        boundaries.append(bnd)
    assert boundaries[0] == boundaries[1]
