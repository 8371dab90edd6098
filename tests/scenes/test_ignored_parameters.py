"""Parameters the chosen material, analysis or option would ignore.

A parameter the run does not use must not be accepted in silence (the summary
would record a value that had no effect): it is refused with a message naming
it, its value and what to choose, or warned about.
"""

from __future__ import annotations

import warnings

import pytest
from helpers import check_cli_error, run_cli

from skfem_npfem.errors import ParameterError
from skfem_npfem.scenes import get_scene


def _resolve(scene: str, overrides: dict) -> list[str]:
    """Resolve; return the warnings' messages."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        get_scene(scene).resolve(overrides)
    return [str(w.message) for w in caught]


def test_phi_with_tresca_is_refused_on_the_command_line():
    code, err = run_cli(
        ["run", "strip-footing", "--set", "analysis=limit", "--set", "phi=30"]
    )
    check_cli_error(code, err, "phi=30", "material=tresca", "mohr-coulomb")
    code, err = run_cli(["run", "slope", "--set", "material=tresca", "--set", "phi=20"])
    check_cli_error(code, err, "phi=20", "material=tresca")


@pytest.mark.parametrize("scene", ["strip-footing", "slope"])
def test_angles_with_tresca(scene):
    for name in ("phi", "psi"):
        with pytest.raises(ParameterError, match=f"invalid {name}=10.0") as err:
            get_scene(scene).resolve({"material": "tresca", name: 10.0})
        assert err.value.name == name
    # 0 (or left out) is what Tresca means: accepted, and other materials use it
    assert _resolve(scene, {"material": "tresca", "phi": 0.0}) == []
    assert _resolve(scene, {"material": "mohr-coulomb", "phi": 25.0}) == []


def test_runout_with_limit_analysis_is_refused():
    code, err = run_cli(
        ["run", "slope", "--set", "runout=true", "--set", "analysis=limit"]
    )
    check_cli_error(code, err, "runout=True", "analysis=incremental")
    assert _resolve("slope", {"runout": True, "t_end": 1.0}) == []


def test_unused_parameters_are_warned_about():
    msgs = _resolve("strip-footing", {"analysis": "limit", "E": 1e7, "steps": 3})
    assert len(msgs) == 1 and msgs[0].startswith("E, steps not used: analysis=limit")
    msgs = _resolve("slope", {"analysis": "limit", "reduction": 1.5})
    assert any(m.startswith("reduction not used") for m in msgs)
    msgs = _resolve("slope", {"K0": 0.6})  # initial_stress=gravity
    assert msgs and msgs[0].startswith("K0 not used: initial_stress=gravity")
    assert _resolve("slope", {"K0": 0.6, "initial_stress": "k0"}) == []
    msgs = _resolve("strip-footing", {"K0": 0.6})  # weightless soil
    assert msgs and msgs[0].startswith("K0 not used")
