"""Bad input to the baselines: one clear ParameterError before any work."""

from __future__ import annotations

import numpy as np
import pytest

from skfem_npfem.baseline import SPFEM, FemRemap, transfer_values
from skfem_npfem.errors import ParameterError
from skfem_npfem.materials import LinearElastic
from skfem_npfem.mesh.sources import AlphaShapeMesher
from skfem_npfem.particles import Particles
from skfem_npfem.scenes.methods import make_method
from skfem_npfem.step.model import Model


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: make_method("fem"), "method"),
        (lambda: make_method("fem-remap", transfer="linear"), "transfer"),
        (lambda: make_method("fem-remap", element="p3"), "element"),
        (lambda: make_method("spfem", element="p2"), "spfem has no option element"),
        (lambda: make_method("spfem", transfer="nearest"), "spfem has no option"),
        (lambda: make_method("npfem", element="p1"), "npfem has no option"),
        (lambda: make_method("fem-remap", damping=1.0), "fem-remap has no option"),
        (lambda: FemRemap("p1", "spline"), "transfer"),
        (lambda: SPFEM(damping=float("nan")), "damping"),
        (
            lambda: transfer_values(
                "cubic",
                np.zeros((3, 2)),
                np.zeros((1, 3), int),
                np.zeros((1, 2)),
                np.zeros((1, 1)),
                np.zeros((1, 2)),
            ),
            "transfer",
        ),
    ],
)
def test_bad_options(call, match):
    with pytest.raises(ParameterError, match=match):
        call()


def test_valid_options_build_methods():
    assert make_method("npfem") is None
    assert make_method("fem-remap", element="p2", transfer=None) == FemRemap("p2")
    assert make_method("spfem", damping=5.0) == SPFEM(5.0)


def test_state_of_another_element_is_refused():
    g = np.linspace(0, 1, 5)
    x = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    p = Particles.create(x, 1.0)
    mesher = AlphaShapeMesher(h=0.25)
    state = FemRemap("p1").initial_state(p, mesher)
    model = Model(dim=2, materials=[LinearElastic(1e6, 0.3, 1000.0)])
    other = AlphaShapeMesher(h=0.25, seed=5)
    for mesh_source in (mesher, other):
        with pytest.raises(ParameterError, match="element"):
            FemRemap("p2").advance(state, model, 0.01, mesh_source)
    with pytest.raises(ParameterError, match="GaussState"):
        FemRemap("p1").advance(p, model, 0.01, mesher)
    with pytest.raises(ParameterError, match="dt"):
        FemRemap("p1").advance(state, model, -1.0, mesher)
