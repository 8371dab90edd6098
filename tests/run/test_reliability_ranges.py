"""Every allowed range is a range the scenes can run.

For every parameter with a magnitude window (``scenes/limits.py``), both ends
are run in every scene that has the parameter (coarse, one to three steps, the
other parameters at their defaults): each end either runs with every step
Solved/AlmostSolved and finite metrics, or is refused up front by a scene check
in one line (a ParameterError naming the parameter that is out of proportion).
No end may crash or return NaN silently.
"""

from __future__ import annotations

import math

import pytest

from skfem_npfem import ParameterError, get_scene, run_scene
from skfem_npfem.scenes.limits import MAGNITUDES

BASE = {
    "column-collapse": {
        "spacing": 0.2 / 6,
        "t_end": 0.015,
        "rest_fraction": 0.0,
        "linear_solver": "qdldl",
    },
    "strip-footing": {
        "steps": 2,
        "plateau_tol": 0.0,
        "spacing": 0.25,
        "linear_solver": "qdldl",
    },
    "elastic-column": {"spacing": 0.5, "linear_solver": "qdldl"},
}

#: Ends refused by a scene check, and the parameter the refusal names.
REFUSED = {
    # rho g H0 = 0.004 Pa: E = 1e7 Pa is 2.5e9 times the weight stress
    ("column-collapse", "rho", "lo"): "E",
    # a cohesion 1.4e8 times the weight stress
    ("column-collapse", "c", "hi"): "c",
    # K0 outside the cohesionless Mohr-Coulomb cone [1/3, 3] (phi = 30)
    ("column-collapse", "K0", "lo"): "K0",
    ("column-collapse", "K0", "hi"): "K0",
    # t_end/dt = 0.015/1e-9: 1.5e7 steps; 1e6/0.005: 2e8 steps
    ("column-collapse", "dt", "lo"): "dt",
    ("column-collapse", "t_end", "hi"): "dt",
    # H0 = 0.004 m, less than 2 spacings of 0.033 m
    ("column-collapse", "aspect", "lo"): "spacing",
    # rho g H / M = 5.8e4: the stress rotation of a huge increment
    ("elastic-column", "E", "lo"): "E",
    # A body 1e-4 m across cannot hold the 2-4 spacings its scene needs, the
    # spacing being a length of at least 1e-4 m too.
    ("column-collapse", "length", "lo"): "spacing",
    ("column-collapse", "half_width", "lo"): "spacing",
    # (the axisymmetric column of height 1e-4 m: its radius 5e-5 m)
    ("column-collapse", "height", "lo"): "radius",
    ("strip-footing", "width", "lo"): "spacing",
    ("elastic-column", "height", "lo"): "spacing",
}

#: Smallest spacing (a length: docs/output.md).
MIN_SPACING = 1e-4


def _scaled(scene: str, name: str, value: float) -> dict:
    """The coarse base case with ``name = value`` (and a spacing to match)."""
    over = {**BASE[scene], name: value}
    if name == "length" or (name, scene) == ("half_width", "column-collapse"):
        over["spacing"] = value / 6
    elif name == "height" and scene == "column-collapse":
        # the cylindrical geometries' h0: an axisymmetric column of aspect 2,
        # spacing r0/4 (the coarsest allowed), 5 x 9 particles
        over.update(geometry="axisymmetric", radius=value / 2, spacing=value / 8)
    elif name == "height":  # a square column, 4 elements high
        over["spacing"], over["width"] = value / 4, value
    elif name == "width" and scene == "strip-footing":  # spacing b/4
        over["spacing"] = value / 8
    elif name == "width":  # 4 times as high (at most 1e4 m), 4 elements high
        over["height"] = min(4 * value, 1e4)
        over["spacing"] = over["height"] / 4
    elif name == "half_width":
        over["spacing"] = value / 4
    elif name == "aspect":
        over["spacing"] = 0.2 / 2 if value > 1 else over["spacing"]
    over["spacing"] = max(over["spacing"], MIN_SPACING)
    return over


def _cases():
    for scene in BASE:
        params = {p.name: p for p in get_scene(scene).params}
        for name in MAGNITUDES:
            if name in params:
                lo, hi, *_ = params[name].bounds()
                yield pytest.param(scene, name, "lo", lo, id=f"{scene}-{name}-lo")
                yield pytest.param(scene, name, "hi", hi, id=f"{scene}-{name}-hi")


@pytest.mark.parametrize(("scene", "name", "end", "value"), list(_cases()))
def test_both_ends_of_every_range_run_or_are_refused_clearly(scene, name, end, value):
    over = _scaled(scene, name, value)
    refused_by = REFUSED.get((scene, name, end))
    if refused_by is not None:
        with pytest.raises(ParameterError) as info:
            run_scene(scene, over)
        assert info.value.name == refused_by and "\n" not in str(info.value)
        return
    res = run_scene(scene, over)
    assert res["solver"]["steps"] >= 1
    assert set(res["solver"]["statuses"]) <= {"Solved", "AlmostSolved"}
    for key, v in res["metrics"].items():
        if isinstance(v, float) and key not in ("period", "relative_error"):
            # undefined metrics are None/NaN by design only where documented
            if key in ("collapse_time", "collapse_time_normalised"):
                continue
            assert math.isfinite(v), (key, v)
    assert res["metrics"]["n_particles"] < 2000  # the case stayed coarse
