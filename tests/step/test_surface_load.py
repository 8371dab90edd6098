"""Dead loads on a surface: a surcharge held by a uniform stress, an oedometer.

References: a uniform stress ``-p`` is in equilibrium with the pressure ``p``
on the loaded face (the consistent loads are exactly the nodal integration's
internal force there); a laterally confined elastic layer of height ``H``
under ``p`` settles ``p H / M`` with the oedometric modulus
``M = E (1 - nu) / ((1 + nu) (1 - 2 nu))``, in plane strain and about an axis.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import skfem

import skfem_npfem as npfem
from skfem_npfem.errors import ParameterError
from skfem_npfem.materials import LinearElastic
from skfem_npfem.mesh.axisymmetric import AxisymmetricMohrCoulomb

E, NU, P = 1.0e6, 0.3, 5.0e4


def layer(axi: bool, stress0: float, material=None, stabilisation: float = 0.0):
    """A 1 x 1 layer on a fixed base, rollers at both sides, P on its top."""
    mesh = skfem.MeshTri.init_tensor(np.linspace(0, 1, 9), np.linspace(0, 1, 7))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    fixed[np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], 1.0), 0] = True
    stress = np.zeros((x.shape[0], 4))
    stress[:, :3] = -stress0
    mat = material or LinearElastic(E, NU, 1.0)
    p = npfem.Particles.from_mesh(
        mesh, [mat], fixed=fixed, stress=stress, axisymmetric=axi
    )
    loads = npfem.surface_load(x, np.isclose(x[:, 1], 1.0), P, axisymmetric=axi)
    model = npfem.Model(
        dim=2,
        materials=[mat],
        gravity=0.0,
        mode="static",
        axisymmetric=axi,
        loads=loads,
        stabilisation=stabilisation,
    )
    return p, model, mesh, loads


@pytest.mark.parametrize("axi", [False, True])
def test_surface_load_sums_to_pressure_times_area(axi):
    _, _, _, loads = layer(axi, 0.0)
    area = math.pi if axi else 1.0  # unit disc's area, or unit length
    assert -loads[:, 1].sum() == pytest.approx(P * area, rel=1e-12)
    assert np.all(loads[:, 0] == 0.0)


@pytest.mark.parametrize("axi", [False, True])
@pytest.mark.parametrize("plastic", [False, True])
def test_surcharge_holds_a_uniform_stress_in_place(axi, plastic):
    mat = AxisymmetricMohrCoulomb(E, NU, 1.0, c=1e3, phi=0.0) if plastic else None
    p, model, mesh, _ = layer(axi, P, mat)
    q, step = npfem.advance(p, model, 1.0, mesh)
    assert step.record.status == "Solved"
    # measured 1.7e-16 of P H / E
    assert np.abs(q.u).max() <= 1e-10 * P / E
    np.testing.assert_allclose(q.stress[:, :3], -P, rtol=1e-9)


@pytest.mark.parametrize("axi", [False, True])
def test_a_stabilised_step_holds_the_surcharged_uniform_stress_too(axi):
    # The stress stabilisation's element residual takes body forces only: read
    # as a body force of the top elements, the surcharge made the exact field
    # -P a residual there, and the step moved the layer (the cone's sigma0 is
    # such a load: a particle was thrown 7 spacings in its first step).
    p, model, mesh, _ = layer(axi, P, stabilisation=1.0)
    q, step = npfem.advance(p, model, 1.0, mesh)
    assert step.record.status == "Solved"
    assert np.abs(q.u).max() <= 1e-10 * P / E
    np.testing.assert_allclose(q.stress[:, :3], -P, rtol=1e-9)


@pytest.mark.parametrize("axi", [False, True])
def test_surcharge_on_an_unstressed_layer_settles_oedometrically(axi):
    p, model, mesh, _ = layer(axi, 0.0)
    q, _ = npfem.advance(p, model, 1.0, mesh)
    M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))
    top = np.isclose(p.x[:, 1], 1.0)
    np.testing.assert_allclose(q.u[top, 1], -P / M, rtol=1e-9)
    np.testing.assert_allclose(q.stress[:, 1], -P, rtol=1e-9)


def test_loads_with_the_wrong_number_of_rows_are_refused():
    p, model, mesh, loads = layer(False, 0.0)
    model.loads = loads[:-1]
    with pytest.raises(ParameterError, match="loads"):
        npfem.advance(p, model, 1.0, mesh)


@pytest.mark.parametrize(
    "bad",
    [np.zeros((3, 3)), np.full((3, 2), np.nan), "heavy"],
    ids=["3 columns", "nan", "text"],
)
def test_bad_loads_are_refused_by_the_model(bad):
    with pytest.raises(ParameterError, match="loads"):
        npfem.Model(dim=2, materials=[LinearElastic(E, NU, 1.0)], loads=bad)


def test_surface_load_refuses_a_surface_that_is_not_flat():
    x = np.array([[0.0, 1.0], [1.0, 1.1], [0.0, 0.0]])
    with pytest.raises(ParameterError, match="horizontal"):
        npfem.surface_load(x, np.array([True, True, False]), P)


def test_baselines_refuse_dead_loads():
    from skfem_npfem.baseline.fem_remap import FemRemap

    p, model, mesh, _ = layer(False, 0.0)
    method = FemRemap()
    state = method.initial_state(p, npfem.mesh.sources.FixedMesh(mesh))
    with pytest.raises(ParameterError, match="N-PFEM only"):
        method.advance(state, model, 1.0, npfem.mesh.sources.FixedMesh(mesh))
