"""Pore water in the outputs: the VTU fields, checkpoints and the summary.

References: below a water table at rest the pore pressure is hydrostatic,
``rho_w g (z_w - z)``, and zero above it; the total stress is the effective
stress less the pore pressure on the normal components (Terzaghi's principle,
tension positive).  A column loaded from scratch by its own weight without
drainage keeps its volume, so its pore water carries the whole total vertical
stress: the pore pressure at depth ``H - z`` is ``rho_sat g (H - z)``, of
which ``rho_w g (H - z)`` is the static field of a table at the top and the
rest, ``(rho_sat - rho_w) g (H - z)``, is the excess.  A run resumed from a
checkpoint repeats the uninterrupted one bit for bit.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from skfem import MeshTri

import skfem_npfem as npfem
from skfem_npfem.io import ResultWriter, read_pvd, read_step, water_point_data
from skfem_npfem.scenes.base import (
    WATER_METRICS_DOC,
    Scene,
    SceneRun,
    water_metrics,
)
from skfem_npfem.scenes.params import Param

G, RHO_SAT, RHO_W, H = 10.0, 2000.0, 1000.0, 2.0
DRY_FIELDS = {
    "displacement",
    "velocity",
    "stress",
    "plastic_strain_eq",
    "mass",
    "active",
}
WET_FIELDS = {"pore_pressure", "excess_pore_pressure", "effective_stress"}


def _simulation(water, mode="static", dt=1.0, **kwargs) -> npfem.Simulation:
    """A 1 m x 2 m column on a fixed base between smooth walls."""
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 4), np.linspace(0, H, 7))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = x[:, 1] == 0.0
    fixed[:, 0] = (x[:, 0] == 0.0) | (x[:, 0] == 1.0)
    soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=RHO_SAT)
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    model = npfem.Model(dim=2, materials=[soil], mode=mode, gravity=G, water=water)
    return npfem.Simulation(p, model, mesh, dt=dt, progress=False, **kwargs)


def _steps(folder: Path) -> list:
    return [read_step(f) for _, f in read_pvd(folder / "result.pvd")]


def test_wet_steps_carry_hydrostatic_pore_pressure_and_total_stress(tmp_path):
    level = 1.5
    water = npfem.Water("drained", npfem.WaterTable(level=level), rho_w=RHO_W)
    sim = _simulation(water, writer=ResultWriter(tmp_path))
    sim.run(steps=1)
    steps = _steps(tmp_path)
    assert len(steps) == 2  # the initial state and the step
    for mesh in steps:
        data = mesh.point_data
        assert set(data) == DRY_FIELDS | WET_FIELDS | {"total_stress"}
        # The step's static field is the table's at the step's start: the
        # positions before its displacement (the first step starts at rest).
        z = mesh.points[:, 1] - data["displacement"][:, 1]
        hydrostatic = RHO_W * G * np.maximum(level - z, 0.0)
        np.testing.assert_allclose(data["pore_pressure"], hydrostatic, rtol=1e-14)
        assert not np.any(data["excess_pore_pressure"])
        np.testing.assert_array_equal(data["effective_stress"], data["stress"])
        total = data["total_stress"]
        np.testing.assert_allclose(
            total[:, :3],
            data["stress"][:, :3] - hydrostatic[:, None],
            rtol=1e-14,
            atol=1e-9,
        )
        np.testing.assert_array_equal(total[:, 3], data["stress"][:, 3])
    # The step's effective stress is what the particles carry.
    np.testing.assert_array_equal(steps[-1].point_data["stress"], sim.particles.stress)


def test_dry_steps_write_the_dry_fields_only(tmp_path):
    sim = _simulation(None, writer=ResultWriter(tmp_path))
    sim.run(steps=1)
    for mesh in _steps(tmp_path):
        assert set(mesh.point_data) == DRY_FIELDS


def test_resumed_undrained_run_repeats_the_straight_run_bit_for_bit(tmp_path):
    def water():
        return npfem.Water("undrained", npfem.WaterTable(level=1.5), rho_w=RHO_W)

    straight = _simulation(water(), mode="dynamic", dt=0.01)
    straight.run(steps=4)
    first = _simulation(
        water(),
        mode="dynamic",
        dt=0.01,
        checkpoint_dir=tmp_path,
        checkpoint_every=2,
        writer=ResultWriter(tmp_path / "a"),
    )
    first.run(steps=2)
    resumed = _simulation(
        water(), mode="dynamic", dt=0.01, writer=ResultWriter(tmp_path / "b")
    )
    resumed.restore(tmp_path / "checkpoint_000002.npz")
    assert resumed.particles.excess_pore_pressure is not None
    np.testing.assert_array_equal(
        resumed.particles.excess_pore_pressure, first.particles.excess_pore_pressure
    )
    resumed.run(steps=2)
    a, b = straight.particles.arrays(), resumed.particles.arrays()
    assert set(a) == set(b) and "excess_pore_pressure" in a
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)
    # the undrained excess evolves from step to step (the state carried)
    assert np.abs(a["excess_pore_pressure"]).max() > 0
    last = _steps(tmp_path / "b")[-1]
    np.testing.assert_array_equal(last.point_data["pore_pressure"], a["pore_pressure"])


def test_undrained_metrics_carry_the_weight_of_the_column():
    water = npfem.Water("undrained", npfem.WaterTable(level=H), rho_w=RHO_W)
    sim = _simulation(water)
    assert water_metrics(sim) == {}  # no step yet: no pore pressure
    sim.run(steps=1)
    m = water_metrics(sim)
    assert set(m) == set(WATER_METRICS_DOC)
    # Nodal integration carries the weight at the base within a few per cent.
    assert m["pore_pressure_max"] == pytest.approx(RHO_SAT * G * H, rel=0.05)
    excess = (RHO_SAT - RHO_W) * G * H
    assert m["excess_pore_pressure_max"] == pytest.approx(excess, rel=0.1)
    assert abs(m["excess_pore_pressure_min"]) < 0.05 * RHO_SAT * G * H


def test_drained_metrics_have_no_excess_and_dry_ones_none():
    level = 1.5
    water = npfem.Water("drained", npfem.WaterTable(level=level), rho_w=RHO_W)
    sim = _simulation(water)
    sim.run(steps=1)
    assert water_metrics(sim) == {
        "pore_pressure_max": pytest.approx(RHO_W * G * level, rel=1e-14)
    }
    dry = _simulation(None)
    dry.run(steps=1)
    assert water_metrics(dry) == {}


def _scene(wet: bool) -> Scene:
    params = [Param("drainage", "drained", "-", "pore water", str, ("drained",))]

    def build(values, out=None, progress=None, resume=False):
        water = npfem.Water("drained", npfem.WaterTable(level=1.0)) if wet else None
        sim = _simulation(water, writer=None if out is None else ResultWriter(out))
        return SceneRun(sim, {"steps": 1}, lambda s: {"own": 1.0})

    return Scene(
        "wet-column",
        "a column under water",
        params if wet else [],
        build,
        {"own": "a scene's own metric"},
        time_params=None,
    )


def test_a_scene_with_water_reports_and_documents_the_pore_pressure(tmp_path):
    wet = _scene(True)
    assert set(wet.metrics_doc) == {"own"} | set(WATER_METRICS_DOC)
    summary = wet.run(out=tmp_path / "wet")
    assert summary["metrics"] == {
        "own": 1.0,
        "pore_pressure_max": pytest.approx(RHO_W * G * 1.0, rel=1e-14),
    }
    dry = _scene(False)
    assert set(dry.metrics_doc) == {"own"}
    assert dry.run(out=tmp_path / "dry")["metrics"] == {"own": 1.0}


def test_total_stress_is_the_effective_stress_less_the_pore_pressure():
    # 3D full Voigt: xx, yy, zz, xy, yz, zx; the shear is the water's none.
    p = npfem.Particles.create(np.zeros((1, 3)), 1.0, stress=[[-3, -5, -4, 1, 2, 3]])
    data = water_point_data(p.replace(pore_pressure=np.array([2.0])), None)
    assert data["total_stress"].tolist() == [[-5, -7, -6, 1, 2, 3]]
    assert data["excess_pore_pressure"].tolist() == [0.0]
    assert water_point_data(p, None) == {}


def test_initial_state_of_a_seepage_run_has_its_pore_pressure(tmp_path):
    # A uniform head over the column's top: hydrostatic water of that head
    # (no flow), p = rho_w g (h - z), already in the initial state's file.
    head = 2.5
    top = npfem.water.HeadBoundary([[0.0, H], [1.0, H]], head=head)
    seepage = npfem.water.Seepage([top], k=1e-5)
    water = npfem.Water("drained", rho_w=RHO_W, seepage=seepage)
    sim = _simulation(water, writer=ResultWriter(tmp_path))
    sim.run(steps=1)
    for mesh in _steps(tmp_path):
        z = mesh.points[:, 1] - mesh.point_data["displacement"][:, 1]
        np.testing.assert_allclose(
            mesh.point_data["pore_pressure"], RHO_W * G * (head - z), rtol=1e-10
        )
