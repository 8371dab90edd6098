"""``--set method=`` on the scenes: the baselines through the CLI and Python.

References: the elastic column (``s_v = -rho g (H - z)``,
top settlement ``rho g H^2 / (2 M)``; P2 elements hold the exact solution,
so FEM-remap P2 reproduces it to round-off; SPFEM with ``alpha = 2 omega_1``
settles to it within 1 % / 0.5 %), the Prandtl footing (``2 + pi``;
FEM P2 at 8 elements across ``b`` measured +3.1 %), mass
conservation and the same outputs for every method in the column collapse,
bit-identical resumes (checkpoints, VTU series and step records), and one
``error:`` line before any step for bad input.
"""

from __future__ import annotations

import io
import json
import math
from contextlib import redirect_stderr, redirect_stdout

import numpy as np
import pytest

from skfem_npfem.cli import main
from skfem_npfem.io import load_checkpoint, read_pvd, read_step
from skfem_npfem.scenes import get_scene, run_scene
from skfem_npfem.scenes.methods import METHOD_METRICS

RHO, G, E, NU = 2000.0, 9.81, 1.0e7, 0.3


def run_cli(argv: list[str]) -> tuple[int, str]:
    err, out = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(out):
        code = main(argv)
    return code, err.getvalue()


def test_fem_remap_p2_elastic_column_through_the_cli_is_exact(tmp_path):
    summary = tmp_path / "s.json"
    argv = ["run", "elastic-column", "--set", "spacing=0.25", "--quiet"]
    argv += ["--set", "method=fem-remap", "--set", "element=p2"]
    assert main([*argv, "--summary", str(summary)]) == 0
    m = json.loads(summary.read_text())["metrics"]
    # The exact linear stress is in the P2 space (measured 2e-12).
    assert m["sigma_v_rel_l2"] < 1e-9 and m["sigma_h_rel_l2"] < 1e-9
    assert abs(m["settlement"] / m["settlement_exact"] - 1) < 1e-9
    assert m["remapped_steps"] == 0  # a fixed mesh is never remapped
    assert m["explicit_steps"] is None  # (spfem only: null)
    assert m["stress_roughness"] < 1e-6  # linear field on a lattice


def test_spfem_dynamic_elastic_column_settles_to_the_static_solution():
    H, spacing = 4.0, 0.25
    M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))
    omega1 = 2 * math.pi / (4 * H / math.sqrt(M / RHO))
    res = run_scene(
        "elastic-column",
        {
            "spacing": spacing,
            "mode": "dynamic",
            "steps": 60,
            "method": "spfem",
            "damping": 2 * omega1,
        },
    )
    m = res["metrics"]
    assert m["sigma_v_rel_l2"] < 0.01 and m["sigma_h_rel_l2"] < 0.01
    assert abs(m["settlement"] / m["settlement_exact"] - 1) < 0.005
    # 0.6 s in steps of 10 ms, each in explicit substeps below the stable step.
    assert res["solver"]["steps"] == 60
    assert m["explicit_steps"] > 60
    assert m["explicit_dt"] <= 0.9 * m["stable_dt"] * (1 + 1e-12)


def test_fem_remap_p2_footing_through_python():
    res = run_scene(
        "strip-footing",
        {
            "spacing": 0.125,
            "steps": 1,
            "plateau_tol": 0.0,
            "method": "fem-remap",
            "element": "p2",
        },
    )
    # Measured +3.12 % (converges from above: +1.6 % at 16 elements across b).
    assert 0.0 < res["metrics"]["relative_error"] < 0.04


def collapse(method: dict, out=None, **over) -> dict:
    values = {
        "spacing": 0.04,  # 66 particles
        "t_end": 0.06,
        "output_every": 2,
        "checkpoint_every": 4,
        "rest_fraction": 0.0,
        **method,
        **over,
    }
    return run_scene("column-collapse", values, out=out)


METHODS = [
    {"method": "npfem"},
    {"method": "fem-remap", "element": "p1", "transfer": "nearest"},
    {"method": "fem-remap", "element": "p2"},
    {"method": "spfem"},
]


@pytest.fixture(scope="module")
def collapses(tmp_path_factory):
    out = tmp_path_factory.mktemp("methods")
    return {
        m["method"] + m.get("element", ""): (collapse(m, out / str(k)), out / str(k))
        for k, m in enumerate(METHODS)
    }


def test_every_method_gives_the_same_outputs(collapses):
    keys = None
    for res, folder in collapses.values():
        m = res["metrics"]
        assert res["solver"]["steps"] == 12  # same time stepping
        assert m["mass_change"] == 0.0  # the particles carry the mass
        assert m["runout"] >= 0.2 * (1 - 1e-9)  # the front does not retreat
        assert set(METHOD_METRICS) <= set(m)
        keys = keys or set(m)
        assert set(m) == keys  # the same summary keys
        series = read_pvd(folder / "result.pvd")
        assert len(series) == 7  # the initial state and every 2nd of 12 steps
        data = read_step(series[-1][1]).point_data
        assert {"displacement", "velocity", "stress", "plastic_strain_eq"} <= set(data)
        assert np.all(np.isfinite(data["stress"]))


def test_method_metrics_are_the_methods_own(collapses):
    fem = collapses["fem-remapp1"][0]["metrics"]
    assert fem["remapped_steps"] >= 1 and fem["yield_violations"] >= 0
    assert fem["explicit_steps"] is None
    sp = collapses["spfem"][0]["metrics"]
    assert sp["explicit_steps"] >= 12 and 0 < sp["explicit_dt"] < sp["stable_dt"]
    assert sp["remapped_steps"] is None
    for res, _ in collapses.values():
        hist = [h["stress_roughness"] for h in res["history"]]
        assert res["metrics"]["stress_roughness"] == hist[-1]


@pytest.mark.parametrize(
    "method", [{"method": "fem-remap", "element": "p2"}, {"method": "spfem"}]
)
def test_resume_reproduces_the_uninterrupted_run(tmp_path, method):
    full = collapse(method, tmp_path / "full")
    collapse(method, tmp_path / "cut", t_end=0.03)  # stops after 6 steps
    resumed = run_scene(
        "column-collapse",
        {
            "spacing": 0.04,
            "t_end": 0.06,
            "output_every": 2,
            "checkpoint_every": 4,
            "rest_fraction": 0.0,
            **method,
        },
        out=tmp_path / "cut",
        resume=True,
    )
    assert resumed["solver"]["steps"] == full["solver"]["steps"] == 12
    a, _ = load_checkpoint(tmp_path / "full" / "checkpoint_000012.npz")
    b, _ = load_checkpoint(tmp_path / "cut" / "checkpoint_000012.npz")
    assert set(a) == set(b)
    if method["method"] == "fem-remap":
        assert {"cells", "gp_stress", "gp_eps_p"} <= set(a)
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)
    last_a = read_step(read_pvd(tmp_path / "full" / "result.pvd")[-1][1])
    last_b = read_step(read_pvd(tmp_path / "cut" / "result.pvd")[-1][1])
    np.testing.assert_array_equal(
        last_a.point_data["stress"], last_b.point_data["stress"]
    )
    strip = ("timings", "wall_time")
    for ha, hb in zip(full["history"], resumed["history"], strict=True):
        assert {k: v for k, v in ha.items() if k not in strip} == {
            k: v for k, v in hb.items() if k not in strip
        }
    for key in ("runout", "stress_roughness", "stress_roughness_max"):
        assert resumed["metrics"][key] == full["metrics"][key]


def test_each_scene_lists_only_the_methods_and_options_it_runs():
    """strip-footing is quasi-static: spfem (explicit dynamics) is not offered.

    ``--set method=spfem`` there used to say spfem "needs inertia
    (mode=dynamic)", a parameter the scene does not have, while the scene
    catalogue listed spfem and its parameters for it.
    """
    from skfem_npfem.cli import scenes_markdown

    for name, methods, spfem_options in (
        ("strip-footing", ("npfem", "fem-remap"), False),
        ("elastic-column", ("npfem", "fem-remap", "spfem"), True),
        ("column-collapse", ("npfem", "fem-remap", "spfem"), True),
    ):
        params = {p.name: p for p in get_scene(name).params}
        assert params["method"].choices == methods
        assert ("spfem" in params["method"].help) == spfem_options
        assert {"damping", "explicit_dt"} <= set(params) or not spfem_options
        assert not {"damping", "explicit_dt"} & set(params) or spfem_options
    footing = scenes_markdown().split("## `strip-footing`")[1].split("## ")[0]
    method_row = next(r for r in footing.splitlines() if r.startswith("| `method`"))
    assert "one of npfem, fem-remap (spfem is not available" in method_row
    assert "| `damping`" not in footing and "mode=dynamic" not in footing


@pytest.mark.parametrize(
    ("scene", "sets", "needles"),
    [
        ("elastic-column", ["method=fem"], ["invalid method='fem'", "npfem"]),
        ("elastic-column", ["element=p2"], ["element", "npfem has no option"]),
        (
            "column-collapse",
            ["method=spfem", "transfer=nearest"],
            ["transfer", "spfem has no option"],
        ),
        (
            "elastic-column",
            ["method=fem-remap", "damping=5"],
            ["damping", "fem-remap has no option"],
        ),
        (
            "strip-footing",
            ["method=fem-remap", "damping=5"],
            ["parameter='damping'", "has parameters"],
        ),
        ("elastic-column", ["explicit_dt=1e-4"], ["explicit_dt", "npfem"]),
        (
            "strip-footing",
            ["method=spfem"],
            ["method='spfem'", "one of npfem, fem-remap", "not available in strip"],
        ),
        ("elastic-column", ["method=spfem"], ["method='spfem'", "mode=dynamic"]),
        (
            "column-collapse",
            ["method=spfem", "explicit_dt=1e-3"],
            ["explicit_dt", "stable explicit step"],
        ),
    ],
)
def test_bad_method_input_is_one_error_line_before_any_step(
    tmp_path, scene, sets, needles
):
    argv = ["run", scene, "--quiet", "--out", str(tmp_path)]
    for s in sets:
        argv += ["--set", s]
    code, err = run_cli(argv)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    assert not list(tmp_path.glob("checkpoint_*.npz"))
    assert not list(tmp_path.glob("result_*.vtu"))
