"""Particles that start a hair inside a body are put on its outline.

Between the outline's tolerance (1e-9 of the body's size) and the depth a run
refuses (1e-6 of it), a particle would count as inside the body for the mesh:
the elements joining it to the soil span the body and the first step drops
them.  The reference is the same start with the particle on the outline.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

import skfem_npfem as npfem
from skfem_npfem import Simulation
from skfem_npfem.boundary import START_DEPTH, start_clear
from skfem_npfem.errors import ParameterError
from skfem_npfem.scenes.footing.cone import build


@pytest.fixture(scope="module")
def cone():
    values = npfem.get_scene("cone-penetration").resolve(
        {"spacing": 0.0357 / 4, "shoulder_round": 1.0}
    )
    srun = build(values, progress=False)
    return srun.simulation, srun.simulation.dt


def shaft_particle(sim) -> int:
    """A particle on the shaft, well above the shoulder."""
    body, x = sim.model.bodies[0], sim.particles.x
    on = np.abs(body.signed_distance(x, 0.0)[0]) < 1e-12 * body.size
    shaft = on & np.isclose(x[:, 0], x[on, 0].max())
    return int(np.flatnonzero(shaft & (x[:, 1] > np.median(x[shaft, 1])))[0])


def first_step(sim, dt, k, inward):
    p = copy.deepcopy(sim.particles)
    p.x[k, 0] -= inward
    s = Simulation(p, copy.deepcopy(sim.model), copy.deepcopy(sim.mesh_source), dt)
    start = s.particles.x[k].copy()
    s.run(steps=1)
    rec = s.records[-1]
    return start, rec.extra["cone_force_y"], rec.extra["dropped_elements"]


def test_a_particle_started_a_hair_inside_the_shaft_is_put_on_it(cone):
    sim, dt = cone
    k, size = shaft_particle(sim), sim.model.bodies[0].size
    x0, f0, dropped0 = first_step(sim, dt, k, 0.0)
    x1, f1, dropped1 = first_step(sim, dt, k, 0.1 * START_DEPTH * size)
    assert dropped0 == dropped1 == 0
    assert np.allclose(x1, x0, rtol=0, atol=1e-12 * size)  # back on the shaft
    # Without the projection this force was a third lower (one element lost).
    assert f1 == pytest.approx(f0, rel=1e-6)


def test_a_particle_deeper_than_the_start_depth_is_refused(cone):
    sim, _ = cone
    p = copy.deepcopy(sim.particles)
    k, body = shaft_particle(sim), sim.model.bodies[0]
    p.x[k, 0] -= 2 * START_DEPTH * body.size
    with pytest.raises(ParameterError, match="inside it"):
        start_clear(sim.model.bodies, p)
    assert start_clear(sim.model.bodies, sim.particles) is sim.particles
