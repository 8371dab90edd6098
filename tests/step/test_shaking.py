"""Pseudo-static shaking: ``Model.kh``, a horizontal ``k_h g`` beside gravity.

Reference: the balance of momentum of a free body.  The internal forces of an
unsupported elastic block cancel, so its momentum changes by the external
impulse alone: with backward Euler, which takes each step's load at the
step's end, ``sum m v`` after ``n`` steps is ``M g dt sum_k (k_h(t_k), -1)``
with ``t_k = k dt``.
"""

from __future__ import annotations

import numpy as np
import pytest

from skfem_npfem import ParameterError
from skfem_npfem.materials import LinearElastic
from skfem_npfem.mesh.sources import AlphaShapeMesher
from skfem_npfem.particles import Particles
from skfem_npfem.run.simulation import Simulation
from skfem_npfem.scenes.collapse.plane_strain import lattice
from skfem_npfem.step.model import Model

G, DT, STEPS = 9.81, 2e-3, 5


def flight(kh) -> tuple[Simulation, float]:
    """An unsupported elastic block, five dynamic steps from rest."""
    h = 0.05
    x = lattice(0.0, 0.2, 0.1, h)
    mass = np.full(len(x), 2000.0 * h * h)
    p = Particles.create(x, mass)
    model = Model(
        dim=2,
        materials=[LinearElastic(1e6, 0.3, 2000.0)],
        gravity=G,
        nodal_mass="particle",
        kh=kh,
    )
    sim = Simulation(p, model, AlphaShapeMesher(h), DT)
    sim.run(steps=STEPS)
    return sim, float(mass.sum())


def momentum(sim: Simulation) -> np.ndarray:
    p = sim.particles
    return (p.mass[:, None] * p.v).sum(axis=0)


def test_constant_kh_is_the_free_body_impulse():
    sim, M = flight(0.3)
    expected = M * G * DT * STEPS * np.array([0.3, -1.0])
    np.testing.assert_allclose(momentum(sim), expected, rtol=1e-9)


def test_kh_history_is_read_at_each_step_end():
    # k_h rises linearly from 0 at t = 0 to 0.5 at 5 dt, then falls: the
    # steps' ends take 0.1, 0.2, ..., 0.5.
    rows = np.array([[0.0, 0.0], [STEPS * DT, 0.5], [1.0, -0.5]])
    sim, M = flight(rows)
    kh = sum(0.1 * k for k in range(1, STEPS + 1))
    expected = M * G * DT * np.array([kh, -STEPS])
    np.testing.assert_allclose(momentum(sim), expected, rtol=1e-9)


def test_zero_kh_leaves_the_free_fall_untouched():
    a, _ = flight(0.0)
    b, _ = flight(np.array([[0.0, 0.0], [1.0, 0.0]]))
    np.testing.assert_array_equal(a.particles.x, b.particles.x)
    assert abs(momentum(a)[0]) <= 1e-12 * abs(momentum(a)[1])


@pytest.mark.parametrize(
    "kh",
    [
        float("nan"),
        True,
        np.array([[0.0, 0.1], [0.0, 0.2]]),
        np.array([0.1, 0.2]),
        np.array([[0.0, np.inf]]),
    ],
)
def test_bad_kh_is_refused(kh):
    with pytest.raises(ParameterError) as err:
        Model(dim=2, materials=[LinearElastic(1e6, 0.3, 2000.0)], kh=kh)
    assert err.value.name == "kh"


def test_baselines_refuse_kh():
    model = Model(dim=2, materials=[LinearElastic(1e6, 0.3, 2000.0)], kh=0.1)
    with pytest.raises(ParameterError) as err:
        model.refuse_loads("SPFEM")
    assert err.value.name == "kh"
