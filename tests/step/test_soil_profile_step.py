"""Per-particle strength and stiffness factors in the cone program.

With every dof prescribed, each node's stress is its own cone's answer to its
own strain: in simple shear ``tau_i = min(s_i G gamma, f_i c)`` (Tresca, von
Mises), the elastic part scaled by the stiffness factor ``s_i`` and the yield
stress by the strength factor ``f_i``.
"""

import math

import numpy as np
import pytest
from skfem import MeshTri

from skfem_npfem import (
    ConeInput,
    Contacts,
    MohrCoulomb,
    ParameterError,
    Particles,
    Tresca,
    VonMises,
    solve_step,
)
from skfem_npfem.limit.analysis import limit_analysis
from skfem_npfem.mesh.smoothing import nodal_integration
from skfem_npfem.profiles import StrengthProfile, linear_strength

E, NU, C = 1.0e7, 0.3, 1.0e4
G = E / (2 * (1 + NU))


def prescribed_shear(mat, comps, gamma, strength=None, stiffness=None, p0=0.0):
    """Every node prescribed on u_x = gamma y: each node's cone on its own.

    ``p0``: an isotropic initial pressure (compression positive).
    """
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 6), np.linspace(0, 1, 6))
    n = mesh.p.shape[1]
    x = mesh.p.T
    du = np.column_stack([gamma * x[:, 1], np.zeros(n)])
    data = ConeInput(
        operator=nodal_integration(mesh, comps),
        materials=[mat],
        material=np.zeros(n, int),
        sigma_n=np.tile([-p0, -p0, -p0, 0.0], (n, 1)),
        force=np.zeros((n, 2)),
        fixed=np.ones((n, 2), bool),
        du_prescribed=du,
        contacts=Contacts.empty(2),
        strength=None if strength is None else strength(x),
        stiffness=None if stiffness is None else stiffness(x),
    )
    return x, solve_step(data)


MATERIALS = [
    (lambda: Tresca(E, NU, c=C), (0, 1, 3)),
    (lambda: VonMises(E, NU, sigma_y=math.sqrt(3) * C), (0, 1, 2, 3)),
]


@pytest.mark.parametrize(("make", "comps"), MATERIALS)
def test_each_node_yields_at_its_own_strength(make, comps):
    # Strength factors 1..3 with height; a shear of 5 yield strains: every
    # node at f_i c (1e-6 relative, the interior-point tolerance).
    def f(x):
        return 1.0 + 2.0 * x[:, 1]

    x, sol = prescribed_shear(make(), comps, 5 * C / G, strength=f)
    np.testing.assert_allclose(sol.sigma[:, 3], f(x) * C, rtol=1e-6)


@pytest.mark.parametrize(("make", "comps"), MATERIALS)
def test_elastic_shear_follows_the_stiffness_factor(make, comps):
    # Half a yield strain: tau_i = s_i G gamma with s_i from 0.5 to 1.5, all
    # below the strength (1e-6 relative).
    def s(x):
        return 0.5 + x[:, 0]

    x, sol = prescribed_shear(make(), comps, 0.5 * C / G, stiffness=s)
    np.testing.assert_allclose(sol.sigma[:, 3], s(x) * 0.5 * C, rtol=1e-6)


def test_mohr_coulomb_factor_scales_the_cohesion_only():
    # phi = 30 deg, psi = 0 (no dilation: the normal stresses stay at the
    # initial pressure p0 under the prescribed shear): the in-plane radius
    # at yield is R = f c cos(phi) + p0 sin(phi), the friction's share
    # unscaled (1e-6 relative).
    mat = MohrCoulomb(E, NU, c=C, phi=30.0, psi=0.0)
    p0 = 3 * C

    def f(x):
        return 1.0 + x[:, 1]

    x, sol = prescribed_shear(mat, (0, 1, 3), 5 * C / G, strength=f, p0=p0)
    s = math.sin(math.radians(30.0))
    expected = f(x) * C * math.cos(math.radians(30.0)) + p0 * s
    np.testing.assert_allclose(sol.sigma[:, 3], expected, rtol=1e-6)


def test_a_uniform_factor_scales_the_collapse_load_exactly():
    # A purely cohesive collapse load is linear in the cohesion: a factor 2.5
    # everywhere multiplies the Prandtl multiplier by 2.5 (1e-6 relative).
    mesh = MeshTri.init_tensor(np.linspace(0, 4, 17), np.linspace(-4, 0, 17))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[np.isclose(x[:, 1], -4.0)] = True
    fixed[np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], 4.0), 0] = True
    foot = np.flatnonzero(np.isclose(x[:, 1], 0.0) & (x[:, 0] <= 1.0 + 1e-9))
    load = np.zeros_like(x)
    load[foot, 1] = -1.0 / foot.size
    args = (nodal_integration(mesh), [Tresca(E, NU, c=1.0)], np.zeros(len(x), int))
    one = limit_analysis(*args, load, fixed=fixed, tied=[2 * foot + 1])
    more = limit_analysis(
        *args, load, fixed=fixed, tied=[2 * foot + 1], strength=np.full(len(x), 2.5)
    )
    assert more.multiplier == pytest.approx(2.5 * one.multiplier, rel=1e-6)


def test_linear_profile_factors_and_refusals():
    np.testing.assert_allclose(
        linear_strength([0.0, 1.0, 2.5, -1.0], 2e3, 1e3), [1.0, 1.5, 2.25, 1.0]
    )
    with pytest.raises(ParameterError, match="su_gradient"):
        linear_strength([0.0], 1e3, -1.0)
    with pytest.raises(ParameterError, match="su"):
        linear_strength([0.0], 0.0, 1.0)


def test_particles_check_and_keep_their_factors():
    p = Particles.create(np.zeros((3, 2)), np.ones(3))
    with pytest.raises(ParameterError, match="strength"):
        p.replace(strength=np.array([1.0, -0.1, 1.0])).validate()
    with pytest.raises(ParameterError, match="stiffness"):
        p.replace(stiffness=np.array([1.0, 0.0, 1.0])).validate()
    with pytest.raises(ParameterError, match="strength"):
        p.replace(strength=np.ones(2)).validate()
    q = p.replace(strength=np.array([1.0, 2.0, 3.0]), stiffness=np.full(3, 2.0))
    back = Particles.from_arrays(q.arrays())
    np.testing.assert_array_equal(back.strength, q.strength)
    np.testing.assert_array_equal(back.stiffness, q.stiffness)
    assert Particles.from_arrays(p.arrays()).strength is None


def test_step_refuses_bad_factors():
    with pytest.raises(ParameterError, match="strength"):
        prescribed_shear(
            Tresca(E, NU, c=C), (0, 1, 3), 1e-3, strength=lambda x: -x[:, 0]
        )
    with pytest.raises(ParameterError, match="stiffness"):
        prescribed_shear(
            Tresca(E, NU, c=C), (0, 1, 3), 1e-3, stiffness=lambda x: 0 * x[:, 0]
        )


def test_layers_give_each_depth_its_strength():
    p = StrengthProfile.from_rows([[0.0, 10e3, 2e3], [3.0, 30e3], [5.0, 20e3, 1e3]])
    z = np.array([-1.0, 0.0, 2.999, 3.0, 4.9, 5.0, 7.0])
    np.testing.assert_allclose(
        p.at(z), [10e3, 10e3, 15.998e3, 30e3, 30e3, 20e3, 22e3], rtol=1e-12
    )
    assert StrengthProfile.linear(1e3, 0.0).uniform
    for rows in ([], [[1.0, 1e3]], [[0.0, 1e3], [0.0, 2e3]], [[0.0, -1.0]], "x"):
        with pytest.raises(ParameterError, match="layers"):
            StrengthProfile.from_rows(rows)
