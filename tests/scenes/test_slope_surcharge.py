"""A strip surcharge on the slope's crest.

References: Prandtl's collapse pressure ``(2 + pi) s_u`` of a uniform
pressure on a strip of a Tresca half-space (its stress field has that
pressure all along the strip, so a flexible strip and a smooth rigid footing
collapse at the same load), which a strip far behind the crest of a stable
slope must reach: with a horizontal surface the weight does no work on an
isochoric mechanism.  For a purely cohesive soil the strength reduction is
exact, ``lambda(F) = lambda(1) / F``, so on level ground, where gravity does
no work on the strip's mechanism, ``F = q_collapse / q``.  Nearer the crest
the mechanism can run out of the slope's face, so the collapse pressure
falls.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from slope_loads import CLAY as STRIP_SLOPE  # demos/studies (tests/conftest.py)
from slope_loads import LIGHT, edge_factor

import skfem_npfem as npfem
from skfem_npfem import ParameterError

#: A stable Tresca slope (gamma H / s_u = 3.3, F = 1.75), a 2 m strip, at 0.5 m.
CLAY = {**STRIP_SLOPE, "spacing": 0.5}


@pytest.fixture(scope="module")
def far() -> dict:
    return npfem.run_scene("slope", {**CLAY, "surcharge_offset": 8.0})["metrics"]


def test_a_strip_far_from_the_crest_collapses_at_prandtls_pressure(far):
    # Measured 5.184 s_u (+0.8 %) at 0.5 m (B/4) and 5.010 (-2.6 %) at 0.25 m.
    assert far["surcharge_collapse"] / 3.0e4 == pytest.approx(2 + math.pi, rel=0.05)


def test_the_collapse_pressure_falls_toward_the_crest(far):
    # 5.18, 4.29 and 3.82 s_u at 8, 2 and 0 m from the crest's edge.
    near = [
        npfem.run_scene("slope", {**CLAY, "surcharge_offset": off})["metrics"]
        for off in (2.0, 0.0)
    ]
    q = [m["surcharge_collapse"] for m in (far, *near)]
    assert q[0] > q[1] > q[2]
    assert q[2] < 0.85 * q[0]


def test_a_surcharge_on_level_ground_sets_the_factor_of_safety():
    # A 0.5 m step at 10 deg is level ground for a 2 m strip 8 m behind it:
    # gravity does no work on the strip's mechanism, so F = q_collapse / q.
    level = {**CLAY, "height": 0.5, "angle": 10.0, "surcharge_offset": 8.0}
    free = npfem.run_scene("slope", level)["metrics"]
    q = 1.0e5
    m = npfem.run_scene("slope", {**level, "surcharge": q})["metrics"]
    assert m["factor_of_safety"] == pytest.approx(
        free["surcharge_collapse"] / q, rel=0.01
    )
    # The collapse pressure is a property of the strip, not of its load.
    assert m["surcharge_collapse"] == pytest.approx(
        free["surcharge_collapse"], rel=1e-6
    )


def test_a_surcharge_lowers_the_factor_of_safety(far):
    # On the slope the strip adds to the driving load of deeper mechanisms:
    # F falls below both the slope's own and q_collapse / q.
    q = 1.0e5
    m = npfem.run_scene("slope", {**CLAY, "surcharge_offset": 8.0, "surcharge": q})[
        "metrics"
    ]
    assert m["factor_of_safety"] < far["factor_of_safety"]
    assert m["factor_of_safety"] <= far["surcharge_collapse"] / q * (1 + 1e-6)


def test_the_initial_stresses_carry_the_surcharge():
    # The gravity step with the surcharge is in equilibrium; its vertical
    # reaction on the base is the weight plus the strip's load.
    m = npfem.run_scene(
        "slope",
        {
            **CLAY,
            "analysis": "incremental",
            "surcharge": 5.0e4,
            "surcharge_offset": 8.0,
        },
    )["metrics"]
    assert m["initial_equilibrium_residual"] < 1e-8
    assert m["surcharge_collapse"] is None  # limit analysis only


def test_a_surcharge_loads_the_runout():
    # A stable slope (F = 2.8) of a slightly cohesive sand under a strip at 1.5
    # times its collapse pressure (F = 0.89) slides; without the strip it stays.
    sand = {
        "c": 2.0e3,
        "phi": 35.0,
        "angle": 20.0,
        "height": 2.0,
        "foundation_depth": 0.4,
        "spacing": 0.4,
        "crest_length": 2.4,
        "toe_length": 4.0,
        "reduction": 1.0,
        "runout": True,
        "surcharge_width": 1.2,
    }
    limit = {k: v for k, v in sand.items() if k not in ("reduction", "runout")}
    qc = npfem.run_scene("slope", {**limit, "analysis": "limit", "refine": "none"})[
        "metrics"
    ]["surcharge_collapse"]
    still = npfem.run_scene("slope", sand)["metrics"]
    loaded = npfem.run_scene("slope", {**sand, "surcharge": 1.5 * qc, "t_end": 0.5})[
        "metrics"
    ]
    assert still["moved_volume"] == 0.0
    assert loaded["factor_of_safety"] < 1.0
    assert loaded["moved_volume"] > 0.5


@pytest.mark.parametrize(
    ("over", "name"),
    [
        ({"surcharge": 1e4, "surcharge_width": None}, "surcharge_width"),
        ({"surcharge_width": 10.0, "surcharge_offset": 6.0}, "surcharge_width"),
        ({"surcharge_width": 0.1}, "surcharge_width"),  # under one spacing
        # The default crest, 1.5 H = 7.5 m, is checked before it is derived.
        ({"crest_length": None, "surcharge_width": 8.0}, "surcharge_width"),
    ],
)
def test_bad_strips_are_refused(over, name):
    with pytest.raises(ParameterError) as err:
        npfem.run_scene("slope", {**CLAY, **over})
    assert err.value.name == name


def test_the_strip_holds_the_crest_particles_under_it():
    from skfem_npfem.scenes import get_scene
    from skfem_npfem.scenes.slope.body import slope_body
    from skfem_npfem.scenes.slope.surcharge import surcharge_load

    values = get_scene("slope").resolve({**CLAY, "surcharge": 1.0e4})
    body = slope_body(values)
    f = surcharge_load(body.pts, body.sec, values)
    # The loads sum to the pressure times the width, all downward, all on
    # the crest's surface between 15 - 2 and 15 m.
    assert f[:, 1].sum() == pytest.approx(-1.0e4 * 2.0, rel=1e-12)
    loaded = np.flatnonzero(f[:, 1] != 0)
    assert np.all(body.pts[loaded, 1] == body.pts[:, 1].max())
    assert body.pts[loaded, 0].min() == pytest.approx(13.0)
    assert body.pts[loaded, 0].max() == pytest.approx(15.0)


def test_a_deposit_without_a_factor_of_safety_keeps_the_runs_metrics(monkeypatch):
    # The deposit's factor of safety is a second analysis after the run-out:
    # when it fails, it is null with a warning, and the rest stands.
    import skfem_npfem.scenes.slope.runout as runout
    from skfem_npfem.errors import NpfemError

    def fails(sim, values):
        raise NpfemError("no factor of safety in 20 cone programs")

    monkeypatch.setattr(runout, "deposit_factor_of_safety", fails)
    from slope_fos import RUNOUT  # the small dry-sand cut of the slope tests

    with pytest.warns(UserWarning, match="deposit's factor of safety"):
        m = npfem.run_scene("slope", RUNOUT)["metrics"]
    assert m["deposit_factor_of_safety"] is None
    assert any("deposit" in w for w in m["warnings"])
    assert m["runout"] > 0 and m["at_rest"]


@pytest.mark.parametrize("beta", [15.0, 30.0])
def test_a_strip_at_the_edge_of_a_weightless_slope(beta):
    # The exact collapse pressure of a weightless Tresca soil under a strip
    # at the crest's edge: Prandtl's field with its fan narrowed by the
    # face's angle, (2 + pi - 2 beta) s_u.  gamma H / s_u = 2e-3 here.
    # Measured at 0.5 m (B/4): +1.3 % (15 deg), +3.4 % (30 deg); at 0.25 m
    # -1.0 % and +0.1 % (docs/validation/slope_loads.md).
    m = npfem.run_scene("slope", {**LIGHT, "spacing": 0.5, "angle": beta})["metrics"]
    assert m["surcharge_collapse"] / 3.0e4 == pytest.approx(edge_factor(beta), rel=0.05)


def test_a_rigid_footing_at_the_edge_carries_at_least_the_flexible_strip():
    # A rigid footing adds a kinematic constraint to the uniform pressure's
    # mechanisms: at one spacing its collapse load is above the flexible
    # strip's, and the rough one's (held sideways too) above the smooth
    # one's.  The smooth one converges from above to the flexible strip's
    # exact (2 + pi - 2 beta) s_u (measured at 30 deg: +13, +6.2, +3.0 % at
    # 0.5, 0.25 and 0.125 m); the rough one to about the two-fan bound
    # (2 + pi - beta) s_u (+9.0, +2.7, -0.2 %; docs/validation/slope_loads.md).
    over = {**LIGHT, "spacing": 0.5, "angle": 30.0}
    q = {
        kind: npfem.run_scene("slope", {**over, "surcharge_footing": kind})["metrics"][
            "surcharge_collapse"
        ]
        for kind in ("flexible", "smooth", "rough")
    }
    assert q["flexible"] <= q["smooth"] * (1 + 1e-6)
    assert q["smooth"] <= q["rough"] * (1 + 1e-6)
    assert q["smooth"] / 3.0e4 == pytest.approx(edge_factor(30.0), rel=0.15)


@pytest.mark.slow
def test_a_rigid_smooth_footing_at_the_edge_converges_to_the_exact_load():
    # 0.125 m (B/16): measured +3.0 % (about two minutes).
    over = {**LIGHT, "spacing": 0.125, "angle": 30.0, "surcharge_footing": "smooth"}
    m = npfem.run_scene("slope", over)["metrics"]
    assert m["surcharge_collapse"] / 3.0e4 == pytest.approx(edge_factor(30.0), rel=0.05)
