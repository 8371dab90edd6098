"""One name per concept across the scenes (no aliases).

The alpha-shape factor of the remeshing is ``alpha`` in every scene that
remeshes, the adhesion factor of an interface ``adhesion``, the footing-soil
(or cone-soil) interface ``interface``, a footing's size its ``width`` B, and
the sizes of the soil block ``domain_*``.
"""

from __future__ import annotations

import pytest

from skfem_npfem.errors import ParameterError
from skfem_npfem.scenes import SCENES, get_scene

OLD_NAMES = {"alpha_shape", "footing", "half_width", "domain", "below"}


def _params(scene: str) -> dict:
    return {p.name: p for p in SCENES[scene].params}


def test_each_concept_has_one_name():
    for name in SCENES:
        params = _params(name)
        for p in params.values():
            if "alpha-shape" in p.help:
                assert p.name == "alpha", (name, p.name)
            if "adhesion factor" in p.help:
                assert p.name == "adhesion", (name, p.name)
            if "interface" in p.help and p.kind is str:
                assert p.name == "interface", (name, p.name)
            if p.help.startswith("soil ") and p.unit == "-":
                assert p.name.startswith("domain_"), (name, p.name)
        if name in ("strip-footing", "footing-penetration", "cone-penetration"):
            assert not OLD_NAMES & set(params), (name, OLD_NAMES & set(params))
    for name in ("strip-footing", "footing-penetration"):
        assert "footing width B" in _params(name)["width"].help
    assert {"alpha", "adhesion", "interface"} <= set(_params("cone-penetration"))


def test_strip_footing_width_is_the_full_width():
    """width = 2 b: the half model's footing covers x <= width / 2."""
    scene = get_scene("strip-footing")
    values = scene.resolve({"width": 1.0, "spacing": 0.125, "domain_width": 4.0})
    p = scene.build(values).simulation.particles
    top = p.x[:, 1] == p.x[:, 1].max()
    assert p.x[top, 0].max() == pytest.approx(4.0 * 0.5)  # domain_width x b
    assert values["interface"] == "smooth"


@pytest.mark.parametrize("scene", ["footing-penetration", "cone-penetration"])
def test_adhesion_needs_the_adhesion_interface(scene):
    with pytest.raises(ParameterError, match="interface=adhesion") as err:
        get_scene(scene).resolve({"adhesion": 0.3})
    assert err.value.name == "adhesion"
    values = get_scene(scene).resolve({"interface": "adhesion", "adhesion": 0.3})
    assert values["adhesion"] == 0.3
