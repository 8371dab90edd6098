"""The volume correction (skfem_npfem/volume.py): a volumetric eigenstrain.

References: the stress-free expansion of an unconstrained elastic block under
a uniform eigenstrain (exact: u = e x, sigma = 0, for any linear field that
nodal integration reproduces), the critically damped decay of the deficit it
implies ((1 + kappa n)(1 - kappa)^n, the closed form of the filter's
recurrence), bit-for-bit equality with the uncorrected step when there is no
deficit, and a resumed run equal to the uninterrupted one (the filter state
travels in the checkpoint).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from skfem import MeshTet, MeshTri

from skfem_npfem import FixedMesh, Model, Particles, Simulation
from skfem_npfem.errors import ParameterError
from skfem_npfem.io import latest_checkpoint
from skfem_npfem.materials import LinearElastic
from skfem_npfem.mesh.smoothing import nodal_integration
from skfem_npfem.scenes import get_scene
from skfem_npfem.step.volume import (
    correction_gains,
    volume_eigenstrain,
    volume_ratio,
    volume_strains,
)

E, NU, RHO = 1.0e7, 0.3, 2000.0


def free_block(dim: int, kappa: float, excess: float = 1.01) -> Simulation:
    """A weightless elastic block on frictionless supports (u_k = 0 on x_k = 0),
    its particles ``excess`` times heavier than rho x their cells."""
    grid = [np.linspace(0.0, 1.0, 4)] * dim
    mesh = (MeshTri if dim == 2 else MeshTet).init_tensor(*grid)
    x = mesh.p.T.copy()
    # An irregular mesh: nodal integration is exact for linear fields on any.
    inner = np.all((x > 0) & (x < 1), axis=1)
    rng = np.random.default_rng(3)
    x[inner] += rng.uniform(-0.08, 0.08, (inner.sum(), dim))
    mesh = (MeshTri if dim == 2 else MeshTet)(x.T, mesh.t)
    vol = nodal_integration(mesh).volumes
    p = Particles.create(x, excess * RHO * vol, fixed=x == 0.0)
    model = Model(
        dim=dim,
        materials=[LinearElastic(E, NU, RHO)],
        mode="static",
        gravity=0.0,
        volume_correction=kappa,
    )
    return Simulation(p, model, FixedMesh(mesh.t), 1.0)


@pytest.mark.parametrize("dim", [2, 3])
def test_free_block_expands_by_the_eigenstrain_without_stress(dim):
    kappa = 0.5
    sim = free_block(dim, kappa)
    x0 = sim.particles.x.copy()
    sim.run(steps=1)
    # The first step's volumetric strain is lam g d = kappa^2 ln(V_ref / V),
    # e = that / n_v on each of the n_v = dim normal components.
    e = kappa**2 * math.log(1.01) / dim
    assert np.allclose(sim.particles.x - x0, e * x0, rtol=0, atol=1e-9 * e)
    # No stress (to the solver's tolerance, relative to E e ~ 2.5e4 Pa) and no
    # plastic strain: the eigenstrain is taken without stress where free.
    assert np.abs(sim.particles.stress).max() < 1e-6 * E * e
    assert sim.records[-1].status == "Solved"


def test_deficit_decays_critically_damped():
    # d_{n+1} = d_n - x_n with x_n = (1 - lam) x_{n-1} + lam g d_n: a double
    # pole at 1 - kappa, so after k steps ln(V_ref/V) = (1 + kappa k)
    # (1 - kappa)^k ln(1.01) (never negative: no overshoot), up to the O(e^2)
    # difference between the linearised area change (1 + e)^2 and exp(2 e).
    kappa = 0.5
    sim = free_block(2, kappa)
    for k in range(1, 5):
        sim.run(steps=1)
        tri_vol = nodal_integration(
            MeshTri(sim.particles.x.T, sim.mesh_source.t)
        ).volumes.sum()
        left = math.log(sim.particles.mass.sum() / RHO / tri_vol)
        exact = (1 + kappa * k) * (1 - kappa) ** k * math.log(1.01)
        assert left == pytest.approx(exact, abs=2e-5)
    # The filter state the loop carries is the last step's strain.
    gain, lam = correction_gains(kappa)
    assert (gain, lam) == pytest.approx((1 / 3, 0.75))
    assert sim.records[-1].extra["volume_correction_strain"][0] > 0


@pytest.mark.parametrize(
    "geometry",
    [{"spacing": 0.2 / 4}, {"geometry": "axisymmetric", "spacing": 0.039 / 4}],
)
def test_no_deficit_is_the_uncorrected_step_bit_for_bit(geometry):
    # The column collapse builds its particles with m = rho V (in axisymmetry
    # the ring masses of the 2 pi r cells): at t = 0 there is no deficit
    # (round-off of the sums is ignored), so the first step with kappa = 0.5
    # is the one without, to the last bit.
    scene = get_scene("column-collapse")
    runs = []
    for kappa in (0.0, 0.5):
        values = scene.resolve({**geometry, "volume_correction": kappa})
        sim = scene.build(values, out=None, progress=False).simulation
        sim.run(steps=1)
        runs.append((sim.particles.x.copy(), sim.particles.stress.copy()))
    assert np.array_equal(runs[0][0], runs[1][0])
    assert np.array_equal(runs[0][1], runs[1][1])


def test_ratio_and_eigenstrain_per_material():
    # Material 0: reference volume 2 / 1 = 2 in cells of 1 (ratio 2); material
    # 1: 2 / 2 = 1 in a cell of 1 (no deficit).  Plane strain: e on xx, yy only.
    mass = np.array([1.0, 1.0, 2.0])
    material = np.array([0, 0, 1])
    volumes = np.array([0.5, 0.5, 1.0])
    rho = np.array([1.0, 2.0])
    assert volume_ratio(mass, material, volumes, rho) == pytest.approx([2.0, 1.0])
    # First step: x = lam g d = kappa^2 ln 2 (g = 0.2/1.8, lam = 0.2 x 1.8).
    x = volume_strains(0.2, mass, material, volumes, rho)
    assert x == pytest.approx([0.04 * math.log(2.0), 0.0])
    eig = volume_eigenstrain(x, material, 4, (0, 1))
    e0 = 0.04 * math.log(2.0) / 2
    assert eig[:, 0] == pytest.approx([e0, e0, 0.0])
    assert np.array_equal(eig[:, 0], eig[:, 1]) and not eig[:, 2:].any()
    # A later step: the previous strain decays by 1 - lam = 0.64.
    x2 = volume_strains(0.2, mass, material, volumes, rho, previous=[0.01, 0.02])
    assert x2 == pytest.approx([0.64 * 0.01 + 0.04 * math.log(2.0), 0.64 * 0.02])
    assert volume_strains(0.0, mass, material, volumes, rho) is None
    assert volume_eigenstrain(None, material, 4, (0, 1)) is None


def test_resumed_run_repeats_the_uninterrupted_one(tmp_path):
    # The filter state is in the step records, which checkpoints keep: a run
    # resumed at step 3 ends where the uninterrupted 6-step run does, bit for
    # bit, and its steps carried a non-zero correction.
    scene = get_scene("column-collapse")
    values = scene.resolve(
        {"spacing": 0.2 / 5, "volume_correction": 0.5, "checkpoint_every": 3}
    )
    first = scene.build(values, out=tmp_path / "a", progress=False).simulation
    first.run(steps=3)
    resumed = scene.build(values, out=tmp_path / "b", progress=False).simulation
    resumed.restore(latest_checkpoint(tmp_path / "a"))
    resumed.run(steps=3)
    clean = scene.build(values, out=None, progress=False).simulation
    clean.run(steps=6)
    strains = [r.extra["volume_correction_strain"][0] for r in clean.records]
    assert strains[0] == 0.0 and any(s != 0.0 for s in strains[1:])
    assert [r.extra["volume_correction_strain"] for r in resumed.records] == [
        r.extra["volume_correction_strain"] for r in clean.records
    ]
    for name, arr in clean.particles.arrays().items():
        np.testing.assert_array_equal(resumed.particles.arrays()[name], arr, name)


def test_bad_input():
    mat = LinearElastic(E, NU, RHO)
    for bad in (-0.1, 1.5, float("nan"), True):
        with pytest.raises(ParameterError, match="volume_correction"):
            Model(dim=2, materials=[mat], volume_correction=bad)
    with pytest.raises(ParameterError, match="rho > 0"):
        Model(dim=2, materials=[LinearElastic(E, NU)], volume_correction=0.1)
    scene = get_scene("column-collapse")
    with pytest.raises(ParameterError, match="method=fem-remap"):
        scene.build(
            scene.resolve({"volume_correction": 0.1, "method": "fem-remap"}),
            out=None,
            progress=False,
        )


@pytest.mark.parametrize(
    ("overrides", "kappa"),
    [
        ({}, 0.05),  # N-PFEM in plane strain: the measured default
        ({"volume_correction": 0.0}, 0.0),  # off when asked
        ({"method": "fem-remap"}, 0.0),  # defined for N-PFEM cells only
        # axisymmetric: on by default (docs/seed_column.md, "Smooth and
        # volume-keeping by default"), with the same premise as plane strain
        ({"geometry": "axisymmetric"}, 0.05),
        ({"geometry": "axisymmetric", "psi": 10.0}, 0.0),
        ({"geometry": "axisymmetric", "E": 1e4}, 0.0),  # rho g h0 / E = 0.14
        # 3D: 0.15 with alpha = 2.0 (docs/seed_column.md, "The 3D default
        # to rest"), with the same premise
        ({"geometry": "quarter-cylinder", "spacing": 0.039 / 4}, 0.15),
        ({"geometry": "quarter-cylinder", "spacing": 0.039 / 4, "psi": 10.0}, 0.0),
        ({"psi": 10.0}, 0.0),  # dilatancy is a real volume change
        ({"E": 1e3}, 0.0),  # rho g H0 / E = 7: the soft column swells elastically
        ({"E": 7.1e5}, 0.05),  # rho g H0 / E = 0.00995 <= 0.01
        ({"E": 7.0e5}, 0.0),  # 0.0101
    ],
)
def test_scene_default(overrides, kappa):
    # docs/validation.md, "At the default spacing": kappa = 0.05 keeps every
    # aspect ratio within 2.1 % of its volume at R max <= 0.071 (N = 22), where
    # the material's own volume barely changes (rho g H0 / E = 1800 * 9.81 *
    # 0.4 / E).
    scene = get_scene("column-collapse")
    values = scene.resolve(overrides)
    model = scene.build(values, out=None, progress=False).simulation.model
    assert model.volume_correction == kappa
