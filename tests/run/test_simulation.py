"""PFEM loop: remeshing every step, particle-attached state, diagnostics, restarts."""

from __future__ import annotations

import numpy as np
import pytest

from skfem_npfem.boundary import floor, project_to_walls
from skfem_npfem.materials import LinearElastic
from skfem_npfem.mesh.sources import AlphaShapeMesher, main_body
from skfem_npfem.particles import Particles
from skfem_npfem.run.simulation import AtRest, Simulation
from skfem_npfem.scenes.collapse.plane_strain import initial_particles, lattice
from skfem_npfem.step.model import Model
from skfem_npfem.step.records import StepState
from skfem_npfem.step.stages import StepRecord, advance

H = 0.05  # lattice spacing of the small blocks, m


def invariants(s: np.ndarray) -> np.ndarray:
    """Mean in-plane stress, Mohr-circle radius and s_zz per particle."""
    mean = 0.5 * (s[:, 0] + s[:, 1])
    radius = np.hypot(0.5 * (s[:, 0] - s[:, 1]), s[:, 3])
    return np.column_stack([mean, radius, s[:, 2]])


def prestressed_block() -> Particles:
    """A block whose stress differs from particle to particle (no two alike)."""
    x = lattice(0.0, 0.4, 0.2, H) + np.array([0.3, 0.1])
    stress = np.zeros((x.shape[0], 4))
    stress[:, 1] = -1e4 * (1.0 + x[:, 1])
    stress[:, 0] = -6e3 * (1.0 + x[:, 0])
    stress[:, 2] = 0.3 * (stress[:, 0] + stress[:, 1])
    stress[:, 3] = 500.0 * x[:, 0] * x[:, 1]
    fixed = np.ones_like(x, dtype=bool)  # the motion is prescribed everywhere
    return Particles.create(x, np.ones(x.shape[0]), stress=stress, fixed=fixed)


def rigid_motion(p: Particles, velocity, n_steps: int, dt: float = 0.1):
    """Advance ``n_steps`` with prescribed velocities, remeshing every step."""
    model = Model(dim=2, materials=[LinearElastic(1e7, 0.3)], gravity=0.0)
    mesher = AlphaShapeMesher(H)
    meshes = []
    for k in range(n_steps):
        p = p.replace(v_prescribed=velocity(p.x))
        p, step = advance(p, model, dt, mesher, step=k + 1)
        assert step.record.status in ("Solved", "AlmostSolved")
        meshes.append(step.local_t.shape[1])
    return p, step.record, meshes


def test_translation_keeps_stresses_on_particles():
    p0 = prestressed_block()
    p, rec, _ = rigid_motion(p0, lambda x: np.tile([0.3, -0.1], (x.shape[0], 1)), 30)
    np.testing.assert_allclose(
        p.x, p0.x + 30 * 0.1 * np.array([0.3, -0.1]), rtol=0, atol=1e-12
    )
    # Nothing mapped: every particle keeps exactly its own stress.
    np.testing.assert_allclose(p.stress, p0.stress, rtol=0, atol=1e-9 * 1e4)
    assert rec.mass == p0.mass.sum()


def test_rotation_rotates_stresses_objectively():
    p0 = prestressed_block()
    beta, n = 0.05, 40  # spin increment per step (rad), steps
    centre = p0.x.mean(axis=0)
    spin = np.array([[0.0, -1.0], [1.0, 0.0]])
    # du = beta * W (x - c): a pure spin (zero strain); the particles turn about
    # the centre through 40 remeshes.
    p, _, meshes = rigid_motion(p0, lambda x: beta * (x - centre) @ spin.T / 0.1, n)
    assert len(meshes) == n
    angle = np.arctan2(*(p.x[0] - centre)[::-1]) - np.arctan2(*(p0.x[0] - centre)[::-1])
    assert abs(angle) > 1.0  # turned by more than a radian
    inv0, inv = invariants(p0.stress), invariants(p.stress)
    scale = np.abs(inv0).max()
    np.testing.assert_allclose(inv, inv0, rtol=0, atol=1e-11 * scale)
    # Hughes-Winget turns the stress by 2 atan(beta/2) per step, particle by
    # particle (a mapped field would mix the different initial stresses).
    a = n * 2 * np.arctan(beta / 2)
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    S0 = np.stack(
        [p0.stress[:, [0, 3]], p0.stress[:, [3, 1]]], axis=1
    )  # (N, 2, 2) in-plane tensors
    S = R @ S0 @ R.T
    np.testing.assert_allclose(p.stress[:, 0], S[:, 0, 0], atol=1e-11 * scale)
    np.testing.assert_allclose(p.stress[:, 1], S[:, 1, 1], atol=1e-11 * scale)
    np.testing.assert_allclose(p.stress[:, 3], S[:, 0, 1], atol=1e-11 * scale)
    np.testing.assert_allclose(p.stress[:, 2], p0.stress[:, 2], atol=1e-11 * scale)


def resting_block(spacing: float = 0.02):
    rho, g, height = 2000.0, 9.81, 0.2
    mat = LinearElastic(1e7, 0.3, rho)
    walls = [floor(2, friction_angle=30.0)]
    mesher = AlphaShapeMesher(spacing, walls=walls)
    x = lattice(0.0, 0.4, height, spacing)
    p = initial_particles(
        x, mesher, rho=rho, gravity=g, height=height, K0=0.3 / 0.7, n_walls=1
    )
    model = Model(dim=2, materials=[mat], gravity=g, walls=walls)
    return p, model, mesher


def test_resting_block_on_floor_keeps_volume_and_mass():
    p, model, mesher = resting_block()
    lowest = []
    sim = Simulation(p, model, mesher, 5e-3)
    sim.callbacks.append(lambda s, q, r: lowest.append(q.x[:, 1].min()))
    recs = sim.run(steps=50)
    assert all(r.status in ("Solved", "AlmostSolved") for r in recs)
    assert min(lowest) >= 0.0  # never below the floor
    assert max(abs(r.volume_change) for r in recs) < 5e-3
    assert all(r.mass == p.mass.sum() for r in recs)  # exactly
    assert all(r.n_inactive == 0 for r in recs)
    # The weight rests on the floor: the total floor force equals it.
    assert sim.particles.wall_force[:, 0].sum() == pytest.approx(
        p.mass.sum() * 9.81, rel=2e-2
    )
    # Kinetic and potential energy are recorded; the block barely moves.
    assert recs[-1].kinetic_energy < 1e-4 * sim.initial["potential_energy"]
    assert recs[-1].potential_energy == pytest.approx(
        sim.initial["potential_energy"], rel=1e-3
    )


def test_free_surface_excludes_particles_on_walls():
    p, _, mesher = resting_block(spacing=0.05)
    mesher(p.x)
    free = mesher.free_surface()
    y, x = p.x[:, 1], p.x[:, 0]
    on_floor = np.isclose(y, 0.0)
    assert not free[on_floor].any()
    outer = np.isclose(y, 0.2) | np.isclose(x, 0.0) | np.isclose(x, 0.4)
    np.testing.assert_array_equal(free, outer & ~on_floor)


def test_simulation_writes_mesh_cells_and_flags(tmp_path):
    from skfem_npfem.io import ResultWriter, read_pvd, read_step

    p, model, mesher = resting_block(spacing=0.05)
    sim = Simulation(p, model, mesher, 5e-3, writer=ResultWriter(tmp_path))
    sim.run(steps=2)
    steps = read_pvd(tmp_path / "result.pvd")
    assert len(steps) == 3
    for _, f in steps:
        m = read_step(f)
        assert m.cells_dict["triangle"].shape[0] > 0
        assert set(m.point_data) >= {"active", "free_surface", "stress"}
        assert m.point_data["free_surface"].sum() > 0


def test_the_step_a_stop_rule_ends_on_is_written(tmp_path):
    # "Write every k-th step (the last step is always written)": also when the
    # run ends on a stop rule between two output steps (a deposit at rest), so
    # the last frame in ParaView is the final state, at the run's final time.
    from skfem_npfem.io import ResultWriter, read_pvd

    dt = 5e-3
    p, model, mesher = resting_block(spacing=0.05)
    sim = Simulation(
        p, model, mesher, dt, writer=ResultWriter(tmp_path), output_every=3
    )
    sim.run(steps=10, stop=lambda s: s.step >= 4)
    times = [t for t, _ in read_pvd(tmp_path / "result.pvd")]
    assert sim.step == 4
    np.testing.assert_allclose(times, [0.0, 3 * dt, 4 * dt], rtol=1e-12, atol=0)
    assert times[-1] == pytest.approx(sim.time, rel=1e-12)


def test_every_callback_sees_the_step_another_one_stops_on(tmp_path):
    # A callback returning True stops the run after this step; the callbacks
    # after it still see the step (scene recorders keep their history whole),
    # and that step is written.
    from skfem_npfem.io import ResultWriter, read_pvd

    p, model, mesher = resting_block(spacing=0.05)
    sim = Simulation(
        p, model, mesher, 5e-3, writer=ResultWriter(tmp_path), output_every=5
    )
    seen: list[int] = []
    sim.callbacks = [
        lambda s, q, r: s.step == 2,
        lambda s, q, r: seen.append(s.step) or False,
    ]
    sim.run(steps=6)
    assert sim.step == 2
    assert seen == [1, 2]
    assert len(read_pvd(tmp_path / "result.pvd")) == 2  # steps 0 and 2


def test_ballistic_grain_feels_floor_friction():
    wall = floor(2, friction_angle=30.0)
    mu, g, dt = wall.mu, 9.81, 1e-3
    x, v = np.array([[0.0, 0.0]]), np.array([[1.0, 0.0]])
    ballistic = np.array([True])
    travelled = 0.0
    for _ in range(1000):
        x_new = x + dt * v + dt**2 * np.array([0.0, -g])
        v_new = v + dt * np.array([0.0, -g])
        x_new, v_new = project_to_walls([wall], x_new, v_new, friction=ballistic)
        travelled += x_new[0, 0] - x[0, 0]
        x, v = x_new, v_new
    assert x[0, 1] == 0.0
    assert v[0, 0] == 0.0  # stopped, never reversed
    assert travelled == pytest.approx(1.0 / (2 * mu * g), rel=2e-2)
    # Without the flag (active particles) only the normal velocity is removed.
    _, v2 = project_to_walls([wall], np.array([[0.0, -1e-3]]), np.array([[1.0, -0.1]]))
    np.testing.assert_array_equal(v2, [[1.0, 0.0]])


def test_main_body_ignores_flying_grains():
    x = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.5], [6.0, 0.0], [7.0, 0.0]])
    np.testing.assert_array_equal(main_body(x, 1.5), [1, 1, 1, 0, 0])


def test_at_rest_rule():
    p, model, mesher = resting_block(spacing=0.05)
    sim = Simulation(p, model, mesher, 5e-3)

    def rec(ke, pe):
        return StepRecord(1, 0.1, 5e-3, "Solved", 10, {}, 1, 0, 1.0, 0, 0,
                          1.0, ke, pe)  # fmt: skip

    rule = AtRest(fraction=0.01, min_time=0.05)
    assert not rule(sim)  # no records yet
    sim.records = [rec(10.0, 0.0), rec(0.05, 0.0)]
    sim.state = StepState(time=0.01)
    assert not rule(sim)  # too early
    sim.state = StepState(time=0.1)
    assert rule(sim)
    pe0 = sim.initial["potential_energy"]
    drop = AtRest(fraction=0.01, reference="potential_drop")
    sim.records = [rec(0.05, pe0 - 1.0)]
    assert not drop(sim)  # 0.05 J > 1 % of the 1 J released
    sim.records = [rec(0.005, pe0 - 1.0)]
    assert drop(sim)
    with pytest.raises(ValueError, match="reference"):
        AtRest(reference="nope")


def test_record_roundtrip_keeps_scene_extras():
    r = StepRecord(3, 0.3, 0.1, "Solved", 12, {"solve": 0.1}, 5, 1, 2.0, 4)
    r.extra["runout"] = 0.7
    d = r.as_dict()
    assert d["runout"] == 0.7 and "extra" not in d and "solution" not in d
    back = StepRecord.from_dict(d)
    assert back.extra == {"runout": 0.7}
    assert back.as_dict() == d


def test_resume_repeats_the_uninterrupted_run(tmp_path):
    """Checkpoint at K, restore into a fresh Simulation, run to N: identical."""
    n, k = 12, 5

    def make(folder):
        p, model, mesher = resting_block(spacing=0.05)
        p = p.replace(v=np.tile([0.2, 0.0], (p.n, 1)))  # slide and stop
        return Simulation(
            p,
            model,
            mesher,
            5e-3,
            adaptive=True,
            checkpoint_dir=folder,
            checkpoint_every=4,
        )

    full = make(tmp_path / "a")
    full.run(steps=n)
    part = make(tmp_path / "b")
    part.run(steps=k)
    resumed = make(tmp_path / "b")
    from skfem_npfem.io import latest_checkpoint

    resumed.restore(latest_checkpoint(tmp_path / "b"))
    assert resumed.step == k
    resumed.run(steps=n - k)
    for name, a in full.particles.arrays().items():
        np.testing.assert_array_equal(getattr(resumed.particles, name), a, name)
    assert [r.dt for r in resumed.records] == [r.dt for r in full.records]
    assert [r.kinetic_energy for r in resumed.records] == [
        r.kinetic_energy for r in full.records
    ]
    assert resumed.time == full.time


def test_a_run_keeps_scalars_only_per_step():
    # The run keeps one scalar StepRecord per step; the step's arrays reach the
    # callbacks in a Step and are dropped.  Reference: the solution
    # arrays of one step (du, sigma, deps_p, reaction: 12 floats = 96 bytes per
    # particle); what the run keeps per step stays below a quarter of that
    # (measured 2-2.7 kB per step, 6 bytes per particle here: the record and a
    # few hundred bytes that Clarabel's binding keeps per solve).
    import gc
    import tracemalloc

    from skfem_npfem.scenes import get_scene
    from skfem_npfem.step.stages import Step

    scene = get_scene("column-collapse")
    values = scene.resolve({"spacing": 0.2 / 14, "linear_solver": "qdldl"})
    sim = scene.build(values, out=None, progress=False).simulation
    seen = []
    sim.callbacks.append(lambda s, p, step: seen.append(type(step)))
    tracemalloc.start()  # before the state arrays that later steps replace
    sim.run(steps=7)  # the first steps fill caches (scipy, numpy, clarabel)
    gc.collect()
    before = tracemalloc.get_traced_memory()[0]
    sim.run(steps=10)
    gc.collect()
    kept = (tracemalloc.get_traced_memory()[0] - before) / 10
    tracemalloc.stop()
    assert seen == [Step] * 17
    assert kept < 0.25 * 96 * sim.particles.n, kept
    for rec in sim.records:
        values = [v for k, v in vars(rec).items() if k not in ("timings", "extra")]
        values += [*rec.timings.values(), *rec.extra.values()]
        # The volume correction's filter state: one number per material.
        values = [v[0] if isinstance(v, list) and len(v) == 1 else v for v in values]
        assert all(isinstance(v, int | float | str) for v in values)


@pytest.mark.parametrize("mode", ["static", "dynamic"])
def test_grain_outside_the_mesh_falls_only_in_a_dynamic_step(mode: str):
    # A grain far above a resting block is outside every element.  A dynamic
    # step moves it ballistically from rest: after n steps of the theta scheme
    # y = y0 - g dt^2 sum_{k<n} (k + theta2); a static step has no
    # inertia and leaves it where it is (a coupled cone's weightless soil with
    # gravity only for gamma_w once lost a grain that fell for kilometres).
    p, model, mesher = resting_block(spacing=0.05)
    p = Particles.create(
        np.vstack([p.x, [[0.2, 1.0]]]),
        np.append(p.mass, p.mass[0]),
        stress=np.vstack([p.stress, np.zeros((1, p.stress.shape[1]))]),
        n_walls=1,
    )
    model = Model(
        dim=2,
        materials=model.materials,
        gravity=9.81,
        walls=model.walls,
        mode=mode,
    )
    dt = 5e-3
    sim = Simulation(p, model, mesher, dt)
    sim.run(steps=3)
    assert [r.n_inactive for r in sim.records] == [1, 1, 1]
    grain = sim.particles.x[-1]
    if mode == "static":
        np.testing.assert_array_equal(grain, [0.2, 1.0])
        np.testing.assert_array_equal(sim.particles.v[-1], [0.0, 0.0])
    else:
        drop = 9.81 * dt**2 * sum(k + model.theta2 for k in range(3))
        assert grain[0] == 0.2
        assert grain[1] == pytest.approx(1.0 - drop, rel=1e-12)
