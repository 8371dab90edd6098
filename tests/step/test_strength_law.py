"""Strain softening and rate dependence of the undrained strength in the step.

A patch in simple shear with every particle prescribed: each particle's
stress is its own cone's answer to its strain, so the shear stress of step
``n`` is the strength the law gives for the state at the start of the step,
``tau_n = c F(xi_{n-1}, g_{n-1})``, and the plastic shear strain grows by the
strain increment less the elastic one, ``xi_n = xi_{n-1} + d_gamma - (tau_n -
tau_{n-1}) / G``.  The recursion is computed here independently and the
library's steps must follow it.
"""

import math

import numpy as np
import pytest
from skfem import MeshTri

from skfem_npfem import Model, ParameterError, Particles, Tresca, advance
from skfem_npfem.strength_laws import ClayStrength, nonlocal_average

E, NU, C = 1.0e7, 0.49, 1.0e4
G = E / (2 * (1 + NU))


def shear_run(law: ClayStrength, rate: float, dt: float, steps: int):
    """``steps`` steps of simple shear at ``rate`` (1/s); stresses and strains."""
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 1, 4))
    mat = Tresca(E, NU, 1.0, c=C)
    p = Particles.from_mesh(mesh, mat, fixed=np.ones(mesh.p.shape[1], bool))
    p = p.replace(v_prescribed=np.column_stack([rate * p.x[:, 1], 0 * p.x[:, 1]]))
    model = Model(
        dim=2,
        materials=[mat],
        gravity=0.0,
        mode="static",
        objective_rotation=False,
        update_geometry=False,
        strength_law=law,
    )
    taus, xis = [], []
    for n in range(steps):
        p, _ = advance(p, model, dt, mesh, step=n)
        taus.append(p.stress[:, 3].copy())
        xis.append(math.sqrt(3) * p.eps_p.copy())
    return np.array(taus), np.array(xis)


def recursion(law: ClayStrength, rate: float, dt: float, steps: int):
    """The law integrated as the step does, from scratch (scalar, one point)."""
    tau, xi, g, out = 0.0, 0.0, 0.0, []
    for _ in range(steps):
        f = law.softening(xi) * (law.rate_factor(g) if law.rate_parameter else 1.0)
        strength = C * float(f)
        new_tau = min(tau + G * rate * dt, strength)
        d_xi = rate * dt - (new_tau - tau) / G
        tau, xi, g = new_tau, xi + d_xi, d_xi / dt
        out.append((tau, xi))
    return np.array(out)


def test_simple_shear_follows_the_softening_law():
    # S_t = 3, xi_95 = 0.2, steps of 0.02: the strength falls from c to about
    # c/3 in 20 steps; every particle within 1e-6 c of the recursion.
    law = ClayStrength(sensitivity=3.0, ductility=0.2)
    taus, xis = shear_run(law, rate=1.0, dt=0.02, steps=20)
    ref = recursion(law, 1.0, 0.02, 20)
    np.testing.assert_allclose(taus, ref[:, :1] + 0 * taus, atol=1e-6 * C)
    np.testing.assert_allclose(xis, ref[:, 1:] + 0 * xis, atol=1e-6)
    assert taus[-1].mean() < 0.40 * C  # softened towards c / S_t
    assert taus[-1].mean() > C / 3.0


def test_simple_shear_follows_the_rate_law():
    # mu = 0.1, reference 1e-2/s, sheared at 1/s: two decades above it, the
    # strength settles at 1.2 c once the plastic rate is the applied one.
    law = ClayStrength(rate_parameter=0.1, reference_rate=1e-2)
    taus, _ = shear_run(law, rate=1.0, dt=0.01, steps=12)
    ref = recursion(law, 1.0, 0.01, 12)
    np.testing.assert_allclose(taus, ref[:, :1] + 0 * taus, atol=1e-6 * C)
    assert taus[-1].mean() == pytest.approx(1.2 * C, rel=1e-3)


def test_rate_enters_only_over_the_reference_rate():
    # Ten times the speed with ten times the reference rate: the same strain
    # per step, the same rate over the reference, the same stresses.
    slow = shear_run(
        ClayStrength(rate_parameter=0.1, reference_rate=1e-3), 1.0, 0.01, 6
    )
    fast = shear_run(
        ClayStrength(rate_parameter=0.1, reference_rate=1e-2), 10.0, 1e-3, 6
    )
    np.testing.assert_allclose(fast[0], slow[0], rtol=1e-9)


def test_law_parameters_are_checked():
    for kw, name in (
        ({"sensitivity": 0.5}, "sensitivity"),
        ({"ductility": 0.0}, "ductility"),
        ({"rate_parameter": -0.1}, "rate_parameter"),
        ({"reference_rate": 0.0}, "reference_rate"),
    ):
        with pytest.raises(ParameterError, match=name):
            ClayStrength(**kw)
    with pytest.raises(ParameterError, match="strength_law"):
        Model(dim=2, materials=[Tresca(E, NU, c=C)], strength_law=3.0)
    with pytest.raises(ParameterError, match="length"):
        ClayStrength(length=-1.0)


def test_nonlocal_average_keeps_a_uniform_field_and_smooths_a_spike():
    # A uniform field is its own average (1e-12); a spike at one point of a
    # lattice is shared with the points within the length, the weighted sum
    # kept where the weights are symmetric (the interior).
    g = np.stack(np.meshgrid(np.arange(11.0), np.arange(11.0)), -1).reshape(-1, 2)
    w = np.ones(len(g))
    np.testing.assert_allclose(nonlocal_average(g, np.full(len(g), 3.0), w, 2.5), 3.0)
    spike = np.zeros(len(g))
    centre = 5 * 11 + 5
    spike[centre] = 1.0
    avg = nonlocal_average(g, spike, w, 2.5)
    assert avg[centre] < 0.2
    near = np.linalg.norm(g - g[centre], axis=1) < 2.5
    assert np.all(avg[near] > 0) and np.all(avg[~near] == 0)
