"""Strip footing run to a detected load plateau.

References: Prandtl-Reissner ``N_c(phi) = (N_q - 1) cot(phi)`` (2 + pi at
phi = 0) with the tolerances of docs/verification.md, computed here from the
closed form; the collapse load of the same mesh from a single rigid-plastic step
(E = 1e12), which the plateau approaches from below (the stresses of every step
are statically admissible); and linear elasticity (load proportional to the
settlement) for the capped case.  Default mesh: spacing 0.125 m, 576 particles.
"""

from __future__ import annotations

import io
import json
import math
import warnings
from contextlib import redirect_stderr, redirect_stdout

import numpy as np
import pytest

from skfem_npfem import ParameterError, get_scene, run_scene
from skfem_npfem.cli import main
from skfem_npfem.io import checkpoint_path
from skfem_npfem.scenes.footing.plateau import PlateauRule, doubling_change

TOL = 1e-3  # the scene's default plateau_tol


def exact_n_c(phi: float) -> float:
    if phi == 0:
        return 2.0 + math.pi
    t = math.tan(math.radians(phi))
    n_q = math.exp(math.pi * t) * math.tan(math.radians(45 + phi / 2)) ** 2
    return (n_q - 1.0) / t


def overrides(phi: float, footing: str = "smooth") -> dict:
    material = "tresca" if phi == 0 else "mohr-coulomb"
    return {"material": material, "phi": phi, "interface": footing}


def rigid_plastic(o: dict) -> float:
    """q/c of one rigid-plastic step (E/c = 1e8) on the same mesh."""
    one = {"E": 1e12, "settlement": 0.01, "steps": 1, "plateau_tol": 0}
    return run_scene("strip-footing", o | one)["metrics"]["bearing_factor"]


# ---------------------------------------------------------------- the rule ----
def test_doubling_change_on_closed_forms():
    # Straight line through the origin: q(s/2) = q(s)/2, change 1/2 exactly.
    s = np.array([0.5, 1.0, 1.5, 2.0, 3.0])
    assert doubling_change(np.c_[s, 7.0 * s].tolist()) == pytest.approx(0.5, 1e-14)
    # Tail q = 1 - 1/(1 + s) with s/2 on a recorded point: exact value.
    s = np.array([1.0, 2.0, 4.0, 8.0])
    q = 1.0 - 1.0 / (1.0 + s)
    exact = (q[3] - q[2]) / q[3]
    assert doubling_change(np.c_[s, q].tolist()) == pytest.approx(exact, 1e-14)
    # Not yet defined while s/2 lies before the first point.
    assert doubling_change([[1.0, 1.0], [1.5, 1.2]]) is None
    assert doubling_change([]) is None


def test_increments_equal_then_growing_and_landing_on_the_cap():
    rule = PlateauRule(
        settlement=0.01, steps=4, tol=TOL, growth=2.0, max_settlement=0.1
    )
    # Straight curve (elastic): equal steps to 0.01, then doubling, last one
    # shortened to land exactly on the cap.
    curve, inc, incs = [], rule.first_increment, []
    while True:
        s = (curve[-1][0] if curve else 0.0) + inc
        curve.append([s, 3.0e7 * s])
        incs.append(inc)
        if rule.stop_reason(curve):
            break
        inc = rule.next_increment(curve, inc)
    assert incs[:4] == [0.0025] * 4
    assert incs[4:7] == pytest.approx([0.005, 0.01, 0.02], rel=1e-12)
    assert curve[-1][0] == pytest.approx(0.1, rel=1e-12)
    assert rule.stop_reason(curve) == "max_settlement"
    # A bend (slope drops by more than BEND = 10 % of the initial slope between
    # two steps) keeps the increment.
    bent = [[0.01, 1.0], [0.02, 2.0], [0.03, 2.5]]
    assert rule.next_increment(bent, 0.01) == pytest.approx(0.01)


# ------------------------------------------------- plateau vs exact N_c ----
@pytest.mark.parametrize(
    ("phi", "footing", "gate"),
    [
        (0.0, "smooth", 0.03),  # Prandtl footing: 2 + pi within 3 % (measured +0.39 %)
        (20.0, "smooth", 0.03),  # N_c footing: N_c(20) within 3 % (measured -1.34 %)
        (30.0, "smooth", 0.05),  # N_c footing: N_c(30) within 5 % (measured -3.41 %)
        (30.0, "rough", 0.05),  # exact for rough too (measured -1.56 %)
    ],
)
def test_plateau_gives_the_exact_bearing_factor(phi, footing, gate):
    o = overrides(phi, footing)
    m = run_scene("strip-footing", o)["metrics"]
    ref = exact_n_c(phi)
    assert m["bearing_factor_reference"] == pytest.approx(ref, rel=1e-12)
    assert abs(m["bearing_factor"] / ref - 1) <= gate
    assert m["plateau_reached"] is True and m["stopped_by"] == "plateau"
    assert m["warnings"] == []
    curve = m["load_curve"]
    # The stop test, recomputed here: load change over the last doubling of the
    # settlement at most 1e-3, and the settlement at least the minimum 0.01 m.
    s, q = np.array(curve).T
    change = abs(q[-1] - np.interp(s[-1] / 2, s, q)) / q[-1]
    assert change <= TOL and m["plateau_change"] == pytest.approx(change, 1e-12)
    assert m["plateau_settlement"] == s[-1] >= 0.01 * (1 - 1e-9)
    # No softening along the curve.
    assert np.all(np.diff(q) >= -1e-6 * q[1:])
    # The plateau sits just below the collapse load of the same mesh: the stop
    # rule leaves out at most 3 tol (measured 0.04-0.24 % over phi = 0-45).
    gap = m["bearing_factor"] / rigid_plastic(o) - 1
    assert -3 * TOL <= gap <= 1e-4


def test_resumed_run_takes_the_same_steps(tmp_path):
    # The rule reads only the step records and dt, which checkpoints keep.
    scene = get_scene("strip-footing")
    values = scene.resolve(overrides(20.0))
    a = scene.build(values, progress=False)
    a.simulation.checkpoint_dir, a.simulation.checkpoint_every = tmp_path, 3
    a.simulation.run(**a.run_kwargs)
    full = a.metrics(a.simulation)["load_curve"]
    assert len(full) > 9  # step 9 is past the first stage (8 steps)
    b = scene.build(values, progress=False)
    b.simulation.restore(checkpoint_path(tmp_path, 9))
    b.simulation.run(steps=b.run_kwargs["steps"] - 9, stop=b.run_kwargs["stop"])
    again = b.metrics(b.simulation)["load_curve"]
    assert np.allclose(again, full, rtol=1e-10, atol=0)
    # Resuming the finished run (checkpoint of its last step) adds no step.
    c = scene.build(values, progress=False)
    c.simulation.restore(checkpoint_path(tmp_path, len(full)))
    c.simulation.run(steps=c.run_kwargs["steps"] - len(full), stop=c.run_kwargs["stop"])
    assert len(c.simulation.records) == len(full)


# --------------------------------------------------------------- the caps ----
def test_elastic_soil_hits_the_settlement_cap_with_a_warning():
    # c = 1e12: elastic, so q is proportional to s and never levels off.
    o = {"c": 1e12, "settlement": 0.001, "steps": 2, "max_settlement": 0.004}
    with pytest.warns(UserWarning, match="no load plateau within max_settlement") as w:
        m = run_scene("strip-footing", o)["metrics"]
    # The warning names this line, the caller's, not a line of the package
    # (it was skfem_npfem/scenes/methods.py, where the metrics are wrapped).
    assert [x.filename for x in w] == [__file__]
    s, q = np.array(m["load_curve"]).T
    # Equal steps to 0.001, then x1.5 while straight, landing on the cap.
    assert s == pytest.approx([0.0005, 0.001, 0.00175, 0.002875, 0.004], 1e-12)
    assert np.ptp(q / s) <= 1e-6 * q[0] / s[0]  # linear elasticity
    assert m["plateau_change"] == pytest.approx(0.5, abs=1e-6)
    assert m["plateau_reached"] is False and m["stopped_by"] == "max_settlement"
    assert m["plateau_settlement"] is None
    assert len(m["warnings"]) == 1 and "50.00%" in m["warnings"][0]


def run_cli(argv: list[str]) -> tuple[int, str]:
    err, out = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(out):
        code = main(argv)
    return code, err.getvalue()


def test_cli_prints_one_warning_line_when_the_step_cap_stops_the_run(tmp_path):
    summary = tmp_path / "s.json"
    argv = ["run", "strip-footing", "--quiet", "--summary", str(summary)]
    for item in ("material=mohr-coulomb", "phi=40", "max_steps=10"):
        argv += ["--set", item]
    code, err = run_cli(argv)
    assert code == 0
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("warning: strip-footing: no load plateau within ")
    assert "max_steps = 10" in lines[0]
    assert "UserWarning" not in err and "warnings.warn" not in err
    m = json.loads(summary.read_text())["metrics"]
    assert m["warnings"] == [lines[0].removeprefix("warning: ")]
    assert m["plateau_reached"] is False and m["stopped_by"] == "max_steps"
    assert len(m["load_curve"]) == 10
    # Stopped on the rising branch: well below the collapse load of the mesh
    # (measured 56.1 vs 72.7) and still rising (> 40 % per doubling).
    assert m["bearing_factor"] < 0.85 * rigid_plastic(overrides(40.0))
    assert m["plateau_change"] > 0.4


def test_detection_off_runs_exactly_the_given_steps():
    # plateau_tol = 0 (and the default with large_deformation): `steps` equal
    # steps to `settlement`, the old behaviour; no plateau claim, no warning.
    for o in ({"plateau_tol": 0.0}, {"large_deformation": True}):
        m = run_scene("strip-footing", o | {"steps": 2, "settlement": 0.004})["metrics"]
        s = [p[0] for p in m["load_curve"]]
        assert s == pytest.approx([0.002, 0.004], rel=1e-12)
        assert m["plateau_reached"] is None and m["stopped_by"] == "steps"
        assert m["plateau_tolerance"] == 0.0 and m["warnings"] == []


# -------------------------------------------------------------- bad input ----
@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("plateau_tol", -1e-3),
        ("plateau_tol", 0.6),
        ("plateau_tol", "nan"),
        ("growth", 0.9),
        ("growth", 5.0),
        ("max_steps", 0),
        ("max_steps", 2.5),
        ("max_settlement", 0.0),
        ("max_settlement", "-1"),
    ],
)
def test_new_parameters_out_of_range(name, value):
    with pytest.raises(ParameterError) as info:
        get_scene("strip-footing").resolve({name: value})
    assert info.value.name == name


@pytest.mark.parametrize(
    ("sets", "name", "needle"),
    [
        (["settlement=0.02", "max_settlement=0.01"], "max_settlement", "0.02"),
        (["steps=12", "max_steps=10"], "max_steps", "steps = 12"),
    ],
)
def test_caps_below_the_first_stage(sets, name, needle):
    o = dict(s.split("=") for s in sets)
    with pytest.raises(ParameterError) as info:
        run_scene("strip-footing", o)
    assert info.value.name == name and needle in str(info.value)
    argv = ["run", "strip-footing", "--quiet"]
    for s in sets:
        argv += ["--set", s]
    code, err = run_cli(argv)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1
    assert lines[0].startswith(f"error: invalid {name}=") and needle in lines[0]


def test_fem_remap_p1_load_is_called_locking_inflated_not_a_lower_estimate():
    """fem-remap (P1) under Tresca flow locks: its load is far above Prandtl.

    Its warning used to call the capped load a lower estimate of the collapse
    load, while the load (q/c = 6.6 here after 4 steps, 15.5 at the default
    caps) already exceeds Prandtl's exact 2 + pi.
    """
    from skfem_npfem.scenes.footing.strip import locking_note

    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        s = run_scene(
            "strip-footing", {"method": "fem-remap", "steps": 3, "max_steps": 4}
        )
    m = s["metrics"]
    assert m["bearing_factor"] > 1.2 * (2 + math.pi)  # above the exact load
    [note] = m["warnings"]
    assert "no load plateau" in note
    assert "the reported load is a lower estimate" not in note
    assert "fem-remap with P1 elements under isochoric plastic flow (tresca)" in note
    assert "inflated by locking and unreliable" in note
    base = {"method": "fem-remap", "element": None, "psi": None}
    assert locking_note({**base, "material": "tresca"}, 0.0)
    assert locking_note({**base, "material": "mohr-coulomb", "psi": 0.0}, 30.0)
    # Dilatant (associated) flow, P2 elements and N-PFEM: no locking note.
    assert not locking_note({**base, "material": "mohr-coulomb"}, 30.0)
    assert not locking_note({**base, "material": "tresca", "element": "p2"}, 0.0)
    assert not locking_note({**base, "material": "tresca", "method": "npfem"}, 0.0)


def test_density_is_rho_and_gravity_as_in_the_other_scenes():
    """strip-footing takes the density rho and gravity, as the other scenes do."""
    names = {
        s: {p.name for p in get_scene(s).params}
        for s in ("strip-footing", "column-collapse", "elastic-column")
    }
    for params in names.values():
        assert {"rho", "gravity"} <= params and "gamma" not in params
    heavy = {"material": "mohr-coulomb", "c": 0, "phi": 30, "spacing": 0.25}
    heavy |= {"steps": 2, "plateau_tol": 0}
    new = run_scene("strip-footing", {**heavy, "rho": 18000 / 9.81})
    # N_gamma = q / (rho g b): the same load on the Moon is 6 times lighter.
    moon = run_scene("strip-footing", {**heavy, "rho": 18000 / 9.81, "gravity": 1.635})
    q_ratio = moon["metrics"]["q_ult"] / new["metrics"]["q_ult"]
    assert q_ratio == pytest.approx(1.635 / 9.81, rel=1e-6)
    assert moon["metrics"]["bearing_factor"] == pytest.approx(
        new["metrics"]["bearing_factor"], rel=1e-6
    )
    with pytest.raises(ParameterError, match="has parameters"):
        get_scene("strip-footing").resolve({"gamma": 1.0})
