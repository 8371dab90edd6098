"""Scenes against analytic and published references.

The elastic column under self-weight, sudden gravity (a 1-D wave) and the
Prandtl strip footing (q/c = 2 + π).  Reference values are
computed here from the closed forms, not read from the scene's own metrics; the
scene metrics are checked against them as well.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skfem_npfem import get_scene, run_scene

RHO, G, NU, H = 2000.0, 9.81, 0.3, 4.0  # elastic-column defaults
PRANDTL = 2.0 + math.pi


def run_built(name: str, overrides: dict):
    """Build and run a scene; return (simulation, metrics, history)."""
    scene = get_scene(name)
    values = scene.resolve(overrides)
    srun = scene.build(values, out=None, progress=False)
    sim = srun.simulation
    sim.run(**srun.run_kwargs)
    # Per-step top settlement, as recorded by the scene on each step record.
    history = [
        (r.time, r.extra["settlement_top"])
        for r in sim.records
        if "settlement_top" in r.extra
    ]
    return sim, srun.metrics(sim), history


def constrained_modulus(E: float, nu: float = NU) -> float:
    return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))


def column_errors(overrides: dict) -> dict:
    """Independent elastic-column errors from the particles of a run."""
    sim, metrics, _ = run_built("elastic-column", overrides)
    p = sim.particles
    dim = p.dim
    E = overrides.get("E", 1.0e7)
    z0 = p.x[:, -1] - p.u[:, -1]  # reference coordinate (static mode moves x)
    sv_ex = -RHO * G * (H - z0)
    sh_ex = NU / (1 - NU) * sv_ex
    sv = p.stress[:, 1] if dim == 2 else p.stress[:, 2]
    sh = p.stress[:, 0]
    top = np.isclose(z0, H)
    base = np.isclose(z0, 0.0)
    us_ex = RHO * G * H**2 / (2 * constrained_modulus(E))
    out = {
        "sv": np.linalg.norm(sv - sv_ex) / np.linalg.norm(sv_ex),
        "sh": np.linalg.norm(sh - sh_ex) / np.linalg.norm(sh_ex),
        "settle": abs(-p.u[top, -1].mean() / us_ex - 1),
        "base": abs(sv[base].mean() / (-RHO * G * H) - 1),
        "metrics": metrics,
    }
    if dim == 3:  # σ_yy is horizontal too in 3D
        out["sh"] = max(
            out["sh"], np.linalg.norm(p.stress[:, 1] - sh_ex) / np.linalg.norm(sh_ex)
        )
    return out


# ---------------------------------------------------- elastic column, static ----
def test_elastic_column_static_2d_accuracy_and_convergence():
    errs = {s: column_errors({"spacing": s}) for s in (0.25, 0.125, 0.0625)}
    e = errs[0.125]
    # Default spacing 0.125 (9 x 33 = 297 nodes): σ_v, σ_h relative L2 ≤ 0.5 %
    # (measured 0.34 % and 0.20 %), settlement and base σ_v ≤ 0.5 %.
    assert e["sv"] <= 5e-3
    assert e["sh"] <= 5e-3
    assert e["settle"] <= 5e-3
    assert e["base"] <= 5e-3
    # The scene's own metrics agree with this recomputation (1e-10 relative).
    m = e["metrics"]
    assert m["sigma_v_rel_l2"] == pytest.approx(e["sv"], rel=1e-10)
    assert m["sigma_h_rel_l2"] == pytest.approx(e["sh"], rel=1e-10)
    assert m["settlement_exact"] == pytest.approx(
        RHO * G * H**2 / (2 * constrained_modulus(1e7)), rel=1e-12
    )
    # Errors decrease under refinement 0.25 -> 0.125 -> 0.0625.
    for key in ("sv", "sh", "settle"):
        values = [errs[s][key] for s in (0.25, 0.125, 0.0625)]
        assert values[0] > values[1] > values[2], (key, values)
    # Roughly first order in the L2 stress error (ratio ≥ 1.8 per halving).
    assert errs[0.25]["sv"] / errs[0.0625]["sv"] > 1.8**2


def test_elastic_column_independent_of_cells_across():
    # Elastic column: 1, 2 or 8 cells across the width give the same settlement (0.1 %).
    s = [column_errors({"width": w})["metrics"]["settlement"] for w in (0.125, 1.0)]
    assert s[0] == pytest.approx(s[1], rel=1e-3)


def test_elastic_column_static_3d():
    errs = {s: column_errors({"dim": 3, "spacing": s}) for s in (0.25, 0.125)}
    # Finest 3D mesh (2673 nodes): σ_v, σ_h, settlement within 1 %
    # (measured 0.46 %, 0.31 %, 7e-6); 0.25 gives 1.17 % on σ_v.
    for key in ("sv", "sh", "settle", "base"):
        assert errs[0.125][key] <= 1e-2, key
        assert errs[0.125][key] < errs[0.25][key], key


# ------------------------------------------------ column period, dynamic ----
def test_elastic_column_sudden_gravity_period():
    E = 1.0e8
    M = constrained_modulus(E)
    T = 4 * H / math.sqrt(M / RHO)  # first oedometric period
    u_s = RHO * G * H**2 / (2 * M)
    _, m, hist = run_built(
        "elastic-column",
        {
            "E": E,
            "mode": "dynamic",
            "theta1": 0.5,
            "theta2": 0.5,
            "dt": T / 40,
            "steps": 100,
        },
    )
    assert m["period_exact"] == pytest.approx(T, rel=1e-12)
    # Trapezoidal period elongation h/(2 atan(h/2)), h = 2π/40: +0.21 %.
    h = 2 * math.pi / 40
    T_num = T * h / (2 * math.atan(h / 2))
    # Scene metric within 3 % of T (measured +0.32 %) and within 1 % of the
    # time integrator's own period.
    assert abs(m["period"] / T - 1) < 0.03
    assert abs(m["period"] / T_num - 1) < 0.01
    # Independent estimate: the exact top settlement crosses its mean u_s at
    # T/4, 3T/4, 5T/4, ... ; fit the crossing times of the history.
    t = np.array([0.0] + [a for a, _ in hist])
    w = np.array([0.0] + [b for _, b in hist]) - u_s
    idx = np.flatnonzero(np.sign(w[:-1]) * np.sign(w[1:]) < 0)
    tc = t[idx] - w[idx] * (t[idx + 1] - t[idx]) / (w[idx + 1] - w[idx])
    assert tc.size >= 4
    slope, first = np.polyfit(np.arange(tc.size), tc, 1)
    assert abs(2 * slope / T - 1) < 0.03
    assert abs(first / (T / 4) - 1) < 0.05  # phase: first crossing at T/4
    # Peak settlement 2 u_s (dynamic amplification 2) within 3 % (measured 0.4 %).
    assert abs(w.max() + u_s - 2 * u_s) < 0.03 * 2 * u_s


# ----------------------------------------------------------------- Prandtl ----
def footing(overrides: dict) -> tuple[float, list]:
    m = run_scene("strip-footing", overrides)["metrics"]
    return m["bearing_factor"], m["load_curve"]


def test_prandtl_smooth_tresca_and_drucker_prager():
    nc, curve = footing({})
    # Smooth footing, Tresca, weightless: q/c within 1 % of 2 + π (5.1615 at
    # spacing 0.125, +0.39 %), approached from above (nodal integration).
    assert abs(nc / PRANDTL - 1) < 0.01
    assert nc > PRANDTL
    q = [v for _, v in curve]
    # Plateau: last two loads within 0.2 %, no softening along the curve.
    assert abs(q[-1] / q[-2] - 1) < 2e-3
    assert np.all(np.diff(q) >= -1e-6 * np.abs(q[1:]))
    # Settlement axis: equal steps of settlement/steps = 0.01/8 m (1e-9).
    assert curve[-1][0] == pytest.approx(0.01, rel=1e-9)
    # Drucker-Prager with φ = 0 (plane-strain match: α = 0, k = c) is von Mises
    # = Tresca in plane strain: the same q/c within 1 % of 2 + π and within
    # 0.1 % of the Tresca run (measured 6e-5).
    nc_dp, _ = footing({"material": "drucker-prager"})
    assert abs(nc_dp / PRANDTL - 1) < 0.01
    assert abs(nc_dp / nc - 1) < 1e-3


def test_prandtl_rough_footing():
    nc, curve = footing({"interface": "rough"})
    # Rough footing: same exact value 2 + π; within 2 % (measured +1.65 %).
    assert abs(nc / PRANDTL - 1) < 0.02
    q = [v for _, v in curve]
    assert abs(q[-1] / q[-2] - 1) < 2e-3


@pytest.mark.slow
def test_prandtl_convergence():
    spacings = (0.125, 0.0625, 0.03125)
    errors = [abs(footing({"spacing": s})[0] / PRANDTL - 1) for s in spacings]
    # |error| decreases (measured 0.39 %, 0.073 %, 0.009 %); finest ≤ 0.2 %.
    assert errors[0] > errors[1] > errors[2]
    assert errors[-1] < 2e-3


def test_lengths_are_limited_like_the_other_lengths():
    # spacing, radius and depth accepted any positive value, although every
    # other length is limited to [1e-4, 1e4] m (docs/output.md); a spacing may
    # go down to 1e-6 m, so that a body of the smallest size can be resolved.
    from skfem_npfem import ParameterError

    for scene, name, lo in (
        ("column-collapse", "spacing", 1e-6),
        ("column-collapse", "radius", 1e-4),
        ("column-collapse", "depth", 1e-4),
        ("strip-footing", "spacing", 1e-6),
        ("elastic-column", "spacing", 1e-6),
    ):
        param = {p.name: p for p in get_scene(scene).params}[name]
        assert param.allowed() == f"a finite number in [{lo:g}, 10000]"
        for bad in (lo / 10, 2e4):
            with pytest.raises(ParameterError) as info:
                get_scene(scene).resolve({name: bad})
            assert info.value.name == name
        assert param.check(lo) == lo and param.check(1e4) == 1e4


def test_a_text_parameter_is_not_described_as_a_number():
    # The slope's cross-section file was listed as "a finite number in
    # (-inf, inf)" by `skfem-npfem scenes` and in docs/scenes.md.
    from skfem_npfem.scenes import SCENES

    texts = [
        (name, p)
        for name, scene in SCENES.items()
        for p in scene.params
        if p.kind is str and p.choices is None
    ]
    assert texts  # the slope's geometry at least
    for name, p in texts:
        assert "number" not in p.allowed(), (name, p.name, p.allowed())
    geometry = {p.name: p for p in get_scene("slope").params}["geometry"]
    assert geometry.allowed() == "a text (the path of a JSON cross-section file)"


def test_parameter_help_says_what_each_scene_does():
    names = ("elastic-column", "strip-footing", "column-collapse")
    params = {s: {p.name: p for p in get_scene(s).params} for s in names}
    # The stabilisation's default is said once where it is 0 for every method.
    for s in ("elastic-column", "strip-footing"):
        text = params[s]["stabilisation"].help
        assert "default 0: off; > 0 with method=npfem only" in text
        assert "0 for the other methods" not in text
    assert (
        "default 30 for method=npfem" in params["column-collapse"]["stabilisation"].help
    )
    # `steps` means different things: each scene says exactly what.
    assert "run exactly" in params["elastic-column"]["steps"].help
    footing_steps = params["strip-footing"]["steps"].help
    assert "first stage" in footing_steps and "max_steps counting all" in footing_steps
    assert "steps" not in params["column-collapse"]  # the collapse runs to t_end
    # K0: every scene's default follows phi (Jaky's 1 - sin phi).
    for s in ("column-collapse", "strip-footing"):
        assert "1 - sin phi" in params[s]["K0"].help
        assert params[s]["K0"].default is None


def test_resolved_values_are_read_only_with_derived_defaults_filled():
    # Each scene resolves its derived defaults once, before its run is built;
    # the stages read the values and none can write one.
    slope = get_scene("slope").resolve({})
    assert slope["spacing"] == slope.spacing == 10.0 / 10
    assert slope["dt"] is not None and slope["t_end"] is not None
    footing = get_scene("strip-footing").resolve({"analysis": "limit"})
    assert footing["spacing"] is not None and footing["domain_width"] is not None
    column = get_scene("column-collapse").resolve({"geometry": "box"})
    assert column["depth"] is not None
    for values in (slope, footing, column):
        with pytest.raises(TypeError):
            values["spacing"] = 1.0  # type: ignore[index]
        with pytest.raises(AttributeError):
            values.spacing = 1.0  # type: ignore[misc]
    # The summary's parameters are the resolved values, as a plain dict, with
    # the defaults the build derived at the values it used (the slope's
    # stabilisation and volume correction: off, its documented defaults).
    given = {"analysis": "limit", "spacing": 2.0}
    params = run_scene("slope", given)["parameters"]
    resolved = dict(get_scene("slope").resolve(given))
    assert params.keys() == resolved.keys()
    assert all(params[k] == v for k, v in resolved.items() if v is not None)
    assert params["stabilisation"] == 0.0 and params["volume_correction"] == 0.0


def test_a_collapse_summary_records_the_spacing_and_fidelity_it_used():
    # Left to their defaults: L0/22 (docs/scenes.md), and N-PFEM's default
    # stabilisation and volume correction of the plane-strain collapse.
    scene = get_scene("column-collapse")
    params = run_scene("column-collapse", {"t_end": 0.005})["parameters"]
    assert params["spacing"] == pytest.approx(0.2 / 22, rel=1e-15)
    defaults = scene.resolve({"t_end": 0.005})
    assert defaults["spacing"] is None and defaults["stabilisation"] is None
    assert params["stabilisation"] > 0 and params["volume_correction"] > 0
    fem = run_scene(
        "column-collapse", {"t_end": 0.005, "spacing": 0.05, "method": "fem-remap"}
    )["parameters"]
    assert fem["stabilisation"] == 0.0 and fem["volume_correction"] == 0.0


# ------------------------------------------------- the step-count message ----
def test_every_scene_s_step_count_advice_names_its_own_parameters():
    from skfem_npfem.scenes import SCENES

    for name, scene in SCENES.items():
        names = {p.name for p in scene.params}
        assert set(scene.time_params or ("steps",)) <= names, name


@pytest.mark.parametrize("name", ["cone-penetration", "footing-penetration"])
def test_too_many_steps_tells_a_penetration_user_what_to_change(name):
    # Reproducer: dt = 1e-9 s told a cone user to "raise dt or lower t_end";
    # the cone scene has no t_end (its run ends at penetration/speed).
    from skfem_npfem import ParameterError

    with pytest.raises(ParameterError, match="raise dt or lower penetration") as err:
        run_scene(name, {"dt": 1e-9})
    assert "t_end" not in str(err.value)
    assert "more than the 1e+06 a run may plan" in str(err.value)
