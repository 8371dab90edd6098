"""Rigid bodies in the FEM-remap baseline: a flat punch on a confined layer.

Reference: a rigid, smooth, flat body wider than the layer pushed down by
``w`` onto an elastic layer of thickness ``H`` and width ``W`` on a fixed base
with rollers on both sides puts it in uniaxial strain ``w / H``: the force
on the body is ``F = M (w / H) W`` per m with the constrained modulus ``M =
E (1 - nu) / ((1 + nu)(1 - 2 nu))``.  A uniform strain is exact for nodal
integration and for P1 and P2 elements; the steps move the geometry, so with
``w / H = 2e-4`` over two steps the force is ``M (w/H) W`` to a fraction of
``w/H`` (updated geometry) plus the solver's tolerance.  Measured: N-PFEM,
P1 and P2 all +5.0e-5 off it (tolerance 2e-4), no penetration.
"""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshTri

from skfem_npfem import advance
from skfem_npfem.baseline import FemRemap
from skfem_npfem.boundary import RigidBody
from skfem_npfem.errors import ParameterError
from skfem_npfem.materials import LinearElastic
from skfem_npfem.mesh.sources import FixedMesh
from skfem_npfem.particles import Particles
from skfem_npfem.step.model import Model

E, NU = 1.0e7, 0.3
W, H = 1.0, 0.5
SPEED, DT, STEPS = 1e-5, 5.0, 2  # w = 1e-4 m: w/H = 2e-4


def confined_layer():
    mesh = MeshTri.init_tensor(np.linspace(0, W, 9), np.linspace(0, H, 5))
    x = mesh.p.T.copy()
    fixed = np.zeros_like(x, dtype=bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    fixed[np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], W), 0] = True
    p = Particles.create(x, np.full(x.shape[0], 1e-9), fixed=fixed)
    punch = RigidBody(
        [[-0.5 * W, H], [1.5 * W, H], [1.5 * W, 2 * H], [-0.5 * W, 2 * H]],
        velocity=[0.0, -SPEED],
        name="punch",
    )
    model = Model(
        dim=2,
        materials=[LinearElastic(E, NU, 0.0)],
        gravity=0.0,
        mode="static",
        bodies=[punch],
    )
    return p, model, FixedMesh(mesh)


def punch_force(method: FemRemap | None) -> tuple[float, dict]:
    p, model, source = confined_layer()
    state = p if method is None else method.initial_state(p, source)
    step = advance if method is None else method.advance
    start = None
    for k in range(STEPS):
        state, result = step(state, model, DT, source, step=k + 1, start=start)
        start = result.state
    return result.record.extra["punch_force_y"], result.record.extra


@pytest.mark.parametrize("method", [None, FemRemap("p1"), FemRemap("p2")])
def test_punch_on_confined_layer_gives_the_constrained_modulus(method):
    force, extra = punch_force(method)
    M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))
    w = SPEED * DT * STEPS
    assert force == pytest.approx(M * w / H * W, rel=2e-4)
    assert extra["punch_y"] == pytest.approx(-w, rel=1e-12)
    assert extra["punch_penetration"] <= 1e-9 * w
    assert extra["dropped_elements"] == 0


def test_spfem_refuses_bodies():
    from skfem_npfem.baseline import SPFEM

    p, model, source = confined_layer()
    model = Model(dim=2, materials=model.materials, bodies=model.bodies)
    with pytest.raises(ParameterError) as info:
        SPFEM().advance(p, model, 1e-4, source)
    assert info.value.name == "bodies"
