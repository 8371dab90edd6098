"""Particle insertion on stretched edges: conservation, exactness, ids, refusals."""

from __future__ import annotations

import numpy as np
import pytest

from skfem_npfem import Particles
from skfem_npfem.errors import ParameterError
from skfem_npfem.mesh.insertion import edge_shares, long_edges
from skfem_npfem.mesh.sources import AlphaShapeMesher
from skfem_npfem.run.refining import Refiner, refined_point_data


def stretched(dim: int = 2, n: int = 9) -> Particles:
    """A lattice of spacing 1/(n-1) stretched 2x sideways at its top, moving."""
    g = np.linspace(0.0, 1.0, n)
    x = np.stack(np.meshgrid(*[g] * dim, indexing="ij"), -1).reshape(-1, dim)
    x[:, 0] *= 1.0 + x[:, -1]
    rng = np.random.default_rng(3)
    nf = 4 if dim == 2 else 6
    stress = np.zeros((x.shape[0], nf))
    stress[:, 0] = 3.0 + 2.0 * x[:, 0] - x[:, -1]  # linear fields
    stress[:, nf - 1] = 0.5 * x[:, 0]
    p = Particles.create(x, rng.uniform(0.5, 2.0, x.shape[0]), stress=stress)
    return p.replace(v=rng.normal(size=x.shape), eps_p=0.1 * x[:, 0] + 0.2 * x[:, -1])


@pytest.mark.parametrize("dim", [2, 3])
def test_insertion_conserves_mass_and_momentum(dim):
    p = stretched(dim, 9 if dim == 2 else 5)
    h = 1.0 / (8 if dim == 2 else 4)
    refiner = Refiner(1.6)
    q = refiner(p, AlphaShapeMesher(h, 1.5))
    assert q.n > p.n and refiner.inserted == q.n - p.n
    # Conservation laws, to round-off (relative).
    assert abs(q.mass.sum() - p.mass.sum()) <= 1e-14 * p.mass.sum()
    mom0 = (p.mass[:, None] * p.v).sum(0)
    mom1 = (q.mass[:, None] * q.v).sum(0)
    scale = np.abs(p.mass[:, None] * p.v).sum()
    assert np.abs(mom1 - mom0).max() <= 1e-12 * scale
    assert refiner.last.momentum_error <= 1e-12
    assert np.all(q.mass > 0)
    # The particles that were there keep their positions, velocities, stresses.
    np.testing.assert_array_equal(q.x[: p.n], p.x)
    np.testing.assert_array_equal(q.v[: p.n], p.v)
    np.testing.assert_array_equal(q.stress[: p.n], p.stress)


def test_new_particles_sit_on_the_midpoints_with_the_linear_fields_exact():
    p = stretched()
    q = Refiner(1.6)(p, AlphaShapeMesher(0.125, 1.5))
    new = q.x[p.n :]
    # A field linear in x is exact at the midpoint of any edge.
    np.testing.assert_allclose(
        q.stress[p.n :, 0], 3.0 + 2.0 * new[:, 0] - new[:, 1], atol=1e-13
    )
    np.testing.assert_allclose(q.stress[p.n :, 3], 0.5 * new[:, 0], atol=1e-14)
    np.testing.assert_allclose(
        q.eps_p[p.n :], 0.1 * new[:, 0] + 0.2 * new[:, 1], atol=1e-14
    )
    # Only stretched edges were split: every new particle is at least half the
    # threshold away from its nearest old particle.
    d = np.linalg.norm(new[:, None, :] - p.x[None, :, :], axis=2).min(axis=1)
    assert d.min() >= 0.5 * 1.6 * 0.125 - 1e-12


def test_ids_are_stable_and_new_ones_come_after_the_largest():
    p = stretched()
    mesher = AlphaShapeMesher(0.125, 1.5)
    refiner = Refiner(1.6)
    q = refiner(p, mesher)
    np.testing.assert_array_equal(q.ids[: p.n], np.arange(p.n))
    np.testing.assert_array_equal(q.ids[p.n :], np.arange(p.n, q.n))
    r = refiner(q.replace(x=q.x * [1.3, 1.0]), mesher)  # stretch again
    assert r.n > q.n
    np.testing.assert_array_equal(r.ids[: q.n], q.ids)
    assert np.unique(r.ids).size == r.n
    assert mesher.spacing.shape == (r.n,)  # the alpha test follows the count
    data = refined_point_data(r)
    np.testing.assert_array_equal(data["particle_id"], r.ids)
    assert refined_point_data(p) == {}


def test_an_undeformed_lattice_gets_no_particle():
    g = np.linspace(0.0, 1.0, 6)
    x = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    p = Particles.create(x, np.ones(x.shape[0]))
    q = Refiner(1.6)(p, AlphaShapeMesher(0.2, 1.3))
    assert q.n == p.n


def donor_pairs(p: Particles, q: Particles) -> list[np.ndarray]:
    """For each new particle, the old pairs whose midpoint it is (one or more:
    the diagonals of a parallelogram share theirs)."""
    mid = 0.5 * (p.x[:, None, :] + p.x[None, :, :])
    out = []
    for y in q.x[p.n :]:
        i, j = np.nonzero(np.linalg.norm(mid - y, axis=2) < 1e-12)
        assert i.size, "a new particle off every midpoint"
        out.append(np.stack([i, j], axis=1))
    return out


def test_edges_across_materials_or_with_a_fixed_end_are_not_split():
    p = stretched()
    free = Refiner(1.6)(p, AlphaShapeMesher(0.125, 1.5))
    top = p.x[:, 1] > 0.7
    fixed = np.repeat(top[:, None], 2, axis=1)  # the stretched top: a support
    q = Refiner(1.6)(p.replace(fixed=fixed), AlphaShapeMesher(0.125, 1.5))
    assert q.n < free.n  # some edges were split there before
    assert all(np.any(~top[c].any(axis=1)) for c in donor_pairs(p, q))
    # Columns of alternating materials: every stretched edge crosses two.
    column = np.rint(p.x[:, 0] / (1.0 + p.x[:, 1]) * 8).astype(np.int64)
    r = Refiner(1.6)(p.replace(material=column % 2), AlphaShapeMesher(0.125, 1.5))
    assert r.n == p.n


def test_long_edges_take_one_edge_per_particle():
    x = np.array([[0.0, 0.0], [3.0, 0.0], [6.5, 0.0], [3.0, 4.0]])
    edges = np.array([[0, 1], [1, 2], [1, 3], [0, 3]])
    chosen = long_edges(x, edges, np.ones(4), 1.6)
    ends = edges[chosen].ravel()
    assert np.unique(ends).size == ends.size  # disjoint
    assert 3 in chosen  # the longest (5.0) first


def test_edge_shares_split_the_volume_in_halves():
    x = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 1.0], [2.0, 1.0]])
    t = np.array([[0, 1, 2], [1, 3, 2]])
    edges, share, volume = edge_shares(x, t)
    # Each triangle has area 1: a node's share 1/3 per triangle; an edge's
    # split frees 1/6 per triangle at each end.
    np.testing.assert_allclose(volume, [1 / 3, 2 / 3, 2 / 3, 1 / 3])
    diag = np.flatnonzero((edges == [1, 2]).all(axis=1))[0]
    assert share[diag] == pytest.approx(2 / 6)
    assert volume.sum() == pytest.approx(2.0)


def test_refiner_refuses_a_ratio_below_the_lattice_diagonal():
    with pytest.raises(ParameterError, match="ratio"):
        Refiner(1.2)


def crowded(dim: int = 2) -> Particles:
    """A lattice of spacing 0.125 squeezed to a third of it at the top."""
    g = np.linspace(0.0, 1.0, 9 if dim == 2 else 5)
    x = np.stack(np.meshgrid(*[g] * dim, indexing="ij"), -1).reshape(-1, dim)
    x[:, -1] = np.where(x[:, -1] > 0.7, 0.7 + (x[:, -1] - 0.7) / 3.0, x[:, -1])
    rng = np.random.default_rng(5)
    stress = np.zeros((x.shape[0], 4 if dim == 2 else 6))
    stress[:, 0] = 3.0 + 2.0 * x[:, 0]
    p = Particles.create(x, rng.uniform(0.5, 2.0, x.shape[0]), stress=stress)
    return p.replace(v=rng.normal(size=x.shape), eps_p=rng.uniform(size=x.shape[0]))


@pytest.mark.parametrize("dim", [2, 3])
def test_merging_conserves_mass_momentum_and_the_centre_of_mass(dim):
    p = crowded(dim)
    h = 0.125 if dim == 2 else 0.25
    refiner = Refiner(3.0, merge=0.4)  # merges only (an insertion moves mass)
    q = refiner(p, AlphaShapeMesher(h, 1.5))
    k = refiner.last_merge.count
    assert k > 0 and refiner.last.count == 0 and q.n == p.n - k
    assert abs(q.mass.sum() - p.mass.sum()) <= 1e-14 * p.mass.sum()
    for field in ("x", "v"):  # centre of mass and momentum
        before = (p.mass[:, None] * getattr(p, field)).sum(0)
        after = (q.mass[:, None] * getattr(q, field)).sum(0)
        scale = np.abs(p.mass[:, None] * getattr(p, field)).sum()
        assert np.abs(after - before).max() <= 1e-13 * scale, field
    # Ids stay unique; the largest id survives, so an added one never reuses one.
    assert np.unique(q.ids).size == q.n
    assert q.ids.max() == p.n - 1

    # The crowding went down: fewer particles have a neighbour closer than
    # the merge threshold.
    def closest(z):
        d = np.linalg.norm(z[:, None] - z[None], axis=2)
        return np.sort(d + np.eye(len(z)) * 9, axis=1)[:, 0]

    assert np.sum(closest(q.x) < 0.4 * h) < np.sum(closest(p.x) < 0.4 * h)
    # The stress of a merged particle is a mean of two: within their range.
    assert q.stress[:, 0].min() >= p.stress[:, 0].min() - 1e-12
    assert q.stress[:, 0].max() <= p.stress[:, 0].max() + 1e-12


def test_merge_threshold_must_stay_below_half_the_split_ratio():
    with pytest.raises(ParameterError, match="merge"):
        Refiner(1.6, merge=0.9)


def test_dead_loads_follow_the_particles_and_ties_are_refused():
    from skfem_npfem import LinearElastic, Model

    p = stretched()
    loads = np.zeros((p.n, 2))
    top = p.x[:, 1] > 0.99
    loads[top, 1] = -np.arange(1.0, top.sum() + 1.0)
    model = Model(dim=2, materials=[LinearElastic(1e6, 0.3)], loads=loads)
    refiner = Refiner(1.6)
    q = refiner(p, AlphaShapeMesher(0.125, 1.5), model)
    assert q.n > p.n and model.loads.shape == (q.n, 2)
    np.testing.assert_array_equal(model.loads[: p.n], loads)  # kept, by row
    assert not np.any(model.loads[p.n :])  # an added particle carries none
    # A retry of the step from the same particles gives the same loads.
    again = refiner(p, AlphaShapeMesher(0.125, 1.5), model)
    assert again.n == q.n and model.loads.shape == (q.n, 2)
    tied = Model(
        dim=2,
        materials=[LinearElastic(1e6, 0.3)],
        mode="static",
        tied=[(np.array([0, 1, 2]), 1)],
    )
    with pytest.raises(ParameterError, match="tied"):
        Refiner(1.6)(p, AlphaShapeMesher(0.125, 1.5), tied)


def test_merging_leaves_the_loaded_particles_and_keeps_the_total_dead_load():
    from skfem_npfem import LinearElastic, Model

    p = crowded()  # squeezed at its top
    loads = np.zeros((p.n, 2))
    top = p.x[:, 1] == np.unique(p.x[:, 1])[-3]  # a row that merges unloaded
    loads[top, 1] = -np.arange(1.0, top.sum() + 1.0)
    model = Model(dim=2, materials=[LinearElastic(1e6, 0.3)], loads=loads)
    refiner = Refiner(3.0, merge=0.4)
    q = refiner(p, AlphaShapeMesher(0.125, 1.5), model)
    assert refiner.last_merge.count > 0 and model.loads.shape == (q.n, 2)
    # Every loaded particle is still there, at its place, with its own load.
    kept = np.isin(q.ids, np.flatnonzero(top))
    assert kept.sum() == top.sum()
    np.testing.assert_array_equal(q.x[kept], p.x[q.ids[kept]])
    np.testing.assert_array_equal(model.loads[kept], loads[q.ids[kept]])
    assert not np.any(model.loads[~kept])
    # Without the load they merge (and move to a pair's centre).
    free = Refiner(3.0, merge=0.4)(p, AlphaShapeMesher(0.125, 1.5))
    stayed = (np.abs(free.x[:, None] - p.x[top][None]).max(axis=2) == 0).any(axis=0)
    assert stayed.sum() < top.sum()


def test_the_mesher_gives_the_last_triangulation_back_only_for_the_same_input():
    # A refined run triangulates its particles before the step does: the
    # step's call with the same positions, spacings and settings reuses it.
    p = stretched()
    mesher = AlphaShapeMesher(0.125, 1.5)
    first = mesher.triangulate(p.x)
    assert mesher.triangulate(p.x.copy()) is first
    moved = p.x.copy()
    moved[0, 0] += 1e-9
    assert mesher.triangulate(moved) is not first
    again = mesher.triangulate(p.x)
    mesher.keep_buried_slivers = True  # a setting changed after a call
    assert mesher.triangulate(p.x) is not again
    mesher.spacing = np.full(p.n, 0.125)
    fresh = mesher.triangulate(p.x)
    np.testing.assert_array_equal(fresh.simplices, again.simplices)  # same h
    mesher.spacing = np.full(p.n, 0.2)  # a new spacing array: triangulated again
    assert mesher.triangulate(p.x) is not fresh


def test_a_user_target_spacing_refines_only_where_it_asks():
    """target(x, t): half the spacing on the left; passes until no edge is long."""
    h = 0.1
    g = np.linspace(0.0, 1.0, 11)
    p = Particles.create(np.stack(np.meshgrid(g, g), -1).reshape(-1, 2), h * h)
    mesher = AlphaShapeMesher(h, 1.3)

    def target(x, time):
        return np.where(x[:, 0] < 0.5, h / 2, h)

    refiner = Refiner(1.6, target=target)
    for _ in range(40):  # at most one edge per particle a pass
        p = refiner(p, mesher)
        if refiner.last.count == 0:
            break
    assert refiner.last.count == 0
    assert p.mass.sum() == pytest.approx(121 * h * h, rel=1e-13)
    edges, _, _ = edge_shares(p.x, mesher.triangulate(p.x).simplices)
    a, b = edges[:, 0], edges[:, 1]
    length = np.linalg.norm(p.x[a] - p.x[b], axis=1)
    assert np.all(length <= 1.6 * np.minimum(target(p.x[a], 0), target(p.x[b], 0)))
    # The right half (target h) keeps its lattice: no particle added there.
    assert np.all(p.x[121:, 0] <= 0.5 + 1e-12)
    # About four times the particles on the left half: (h / (h/2))^2.
    left = np.sum(p.x[:, 0] < 0.5 - 1e-9)
    assert 3.0 < left / 55 < 5.0
    with pytest.raises(ParameterError, match="target"):
        Refiner(1.6, target=lambda x, t: -np.ones(x.shape[0]))(p, mesher)
    with pytest.raises(ParameterError, match="target"):
        Refiner(1.6, target=0.05)


def test_the_target_is_halved_where_the_plastic_strain_rate_concentrates():
    """strain_share: particles added only round those that carry the plastic flow."""
    h = 0.1
    g = np.linspace(0.0, 1.0, 11)
    p = Particles.create(np.stack(np.meshgrid(g, g), -1).reshape(-1, 2), h * h)
    mesher = AlphaShapeMesher(h, 1.3)
    refiner = Refiner(1.6, strain_share=1.0)
    # No rate yet (before the first step): nothing marked, nothing added, and
    # the particles carry a zero rate for the steps to fill in.
    q = refiner(p, mesher)
    assert q.n == p.n and refiner.marked == 0
    np.testing.assert_array_equal(q.shear_rate, np.zeros(p.n))
    # A band of plastic flow x <= 0.2 (3 columns of 11 particles).
    band = p.x[:, 0] < 0.25
    p = p.replace(shear_rate=np.where(band, 2.0, 0.0))
    q = refiner(p, mesher)
    assert refiner.record()["refined"] == refiner.marked == 33
    assert q.n > p.n
    # Every new particle is on an edge with an end in the band, and it takes
    # the rate of the edge's midpoint (the linear interpolant).
    new = q.x[p.n :]
    assert np.all(new[:, 0] <= 0.25 + 1e-12)
    expect = np.where(new[:, 0] < 0.2 + 1e-12, 2.0, 1.0)
    np.testing.assert_allclose(q.shear_rate[p.n :], expect, rtol=1e-15)
    assert q.mass.sum() == pytest.approx(p.mass.sum(), rel=1e-14)
    for _ in range(40):  # passes until no edge round the flow is long
        q = refiner(q, mesher)
        if refiner.last.count == 0:
            break
    assert refiner.last.count == 0
    # Outside the band and its edge (x > 0.3) the lattice is untouched.
    assert np.sum(q.x[:, 0] > 0.3 + 1e-9) == np.sum(p.x[:, 0] > 0.3 + 1e-9)
    # About four times the particles in the band: (h / (h / 2))^2.
    inner = np.sum(q.x[:, 0] < 0.2 - 1e-9) / np.sum(p.x[:, 0] < 0.2 - 1e-9)
    assert 3.0 < inner < 5.0
    with pytest.raises(ParameterError, match="strain_share"):
        Refiner(1.6, strain_share=0.0)
    with pytest.raises(ParameterError, match="strain_share"):
        Refiner(1.6, strain_share=1.5)


def test_refining_by_strain_alone_leaves_the_stretched_soil_elsewhere():
    """stretched=False: only the edges round the marked particles are split."""
    p = stretched()  # spacing 1/8, stretched 2x sideways at its top (y = 1)
    h = 1.0 / 8
    low = p.x[:, 1] < 0.2  # plastic flow in the two bottom rows only
    p = p.replace(shear_rate=np.where(low, 1.0, 0.0))
    both = Refiner(1.6, strain_share=1.0)(p, AlphaShapeMesher(h, 1.5))
    only = Refiner(1.6, strain_share=1.0, stretched=False)
    only = only(p, AlphaShapeMesher(h, 1.5))
    # Both split round the flow; only the first splits the stretched top too.
    assert np.any(both.x[p.n :, 1] > 0.5) and np.any(both.x[p.n :, 1] < 0.25)
    assert only.n > p.n and np.all(only.x[p.n :, 1] < 0.25 + 1e-12)
