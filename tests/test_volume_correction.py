"""The volume correction (skfem_npfem/volume.py): a volumetric eigenstrain.

References: the stress-free expansion of an unconstrained elastic block under
a uniform eigenstrain (exact: u = e x, sigma = 0, for any linear field that
nodal integration reproduces), the geometric decay of the deficit it implies,
and bit-for-bit equality with the uncorrected step when there is no deficit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from skfem import MeshTet, MeshTri

from skfem_npfem import FixedMesh, Model, Particles, Simulation
from skfem_npfem.errors import ParameterError
from skfem_npfem.materials import LinearElastic
from skfem_npfem.scenes import get_scene
from skfem_npfem.smoothing import nodal_integration
from skfem_npfem.volume import volume_eigenstrain, volume_ratio

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
    # e = kappa ln(V_ref / V) / n_v on each of the n_v = dim normal components.
    e = kappa * math.log(1.01) / dim
    assert np.allclose(sim.particles.x - x0, e * x0, rtol=0, atol=1e-9 * e)
    # No stress (to the solver's tolerance, relative to E e ~ 2.5e4 Pa) and no
    # plastic strain: the eigenstrain is taken without stress where free.
    assert np.abs(sim.particles.stress).max() < 1e-6 * E * e
    assert sim.records[-1].status == "Solved"


def test_deficit_decays_geometrically():
    # Each step returns kappa of the remaining deficit: after k steps
    # ln(V_ref/V) = (1 - kappa)^k ln(1.01), up to the O(e^2) difference between
    # the linearised area change (1 + e)^2 and exp(2 e) (~1e-5 here).
    kappa = 0.5
    sim = free_block(2, kappa)
    for k in range(1, 4):
        sim.run(steps=1)
        tri_vol = nodal_integration(
            MeshTri(sim.particles.x.T, sim.mesh_source.t)
        ).volumes.sum()
        left = math.log(sim.particles.mass.sum() / RHO / tri_vol)
        assert left == pytest.approx((1 - kappa) ** k * math.log(1.01), abs=2e-5)


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
    eig = volume_eigenstrain(0.2, mass, material, volumes, rho, 4, (0, 1))
    e0 = 0.2 * math.log(2.0) / 2
    assert eig[:, 0] == pytest.approx([e0, e0, 0.0])
    assert np.array_equal(eig[:, 0], eig[:, 1]) and not eig[:, 2:].any()
    assert volume_eigenstrain(0.0, mass, material, volumes, rho, 4, (0, 1)) is None


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
