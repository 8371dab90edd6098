"""Limit analysis as one cone program (skfem_npfem.limit).

References: the exact bearing factor N_c of a smooth strip footing on a
weightless Mohr-Coulomb soil (Prandtl 1920, Reissner 1924; ``laws.prandtl_nc``),
the proportionality of a purely cohesive collapse load to ``c``, and strong
duality (the dissipated power of the mechanism equals the multiplier's work).
The 2 % gate at the limit mode's default spacing and the convergence with the
spacing are measured by ``demos/studies/limit_footing.py`` (docs/validation).
"""

from __future__ import annotations

import contextlib
import io
import math

import numpy as np
import pytest
from helpers import check_cli_error, run_cli

import skfem_npfem as npfem
from skfem_npfem.cli import main
from skfem_npfem.laws import prandtl_depth, prandtl_nc
from skfem_npfem.limit.program import limit_hint
from skfem_npfem.scenes.footing.mesh import soil_mesh
from skfem_npfem.scenes.footing.strip import PARAMS
from skfem_npfem.scenes.limit_mode import (
    MECHANISM_MARGIN,
    check_limit_method,
    limit_metrics,
)

#: Largest |N/N_c - 1| at the coarse spacing 0.125 b, block 5 b: the O(h)
#: discretisation error of the mixed program (measured -3.9 % at phi = 35).
COARSE_TOL = 0.045


def footing_problem(spacing: float = 0.125, domain: float = 5.0):
    """Mesh, supports, rigid-footing tie and unit-pressure load of the half model."""
    values = {p.name: p.default for p in PARAMS}
    values.update(spacing=spacing, domain_width=domain, size_check=False)
    mesh = soil_mesh(values)
    x = mesh.p.T
    n = x.shape[0]
    fixed = np.zeros((n, 2), bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    fixed[np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], domain), 0] = True
    foot = np.flatnonzero(np.isclose(x[:, 1], domain) & (x[:, 0] <= 1 + 1e-9))
    load = np.zeros((n, 2))
    load[foot, 1] = -1.0 / foot.size  # unit total force: multiplier = q b / c b
    return mesh, fixed, foot, load


@pytest.mark.parametrize("phi", [0.0, 10.0, 20.0, 30.0, 35.0, 40.0])
def test_bearing_factor_table_coarse(phi):
    """N_c(phi) from one program each, within 4.5 % of Prandtl at 0.125 b."""
    mesh, fixed, foot, load = footing_problem()
    c = 1.0e4
    mat = npfem.MohrCoulomb(1e8, 0.3, c=c, phi=phi)
    res = npfem.limit_analysis(
        mesh, [mat], np.zeros(mesh.p.shape[1], int), c * load,
        fixed=fixed, tied=[2 * foot + 1],
    )  # fmt: skip
    assert res.status == "Solved"
    assert abs(res.multiplier / prandtl_nc(phi) - 1) < COARSE_TOL


def test_duality_and_mechanism():
    """Dissipation = multiplier (to 1e-6); the footing moves down at unit power."""
    mesh, fixed, foot, load = footing_problem()
    mat = npfem.MohrCoulomb(1e8, 0.3, c=1.0, phi=20.0)
    res = npfem.limit_analysis(
        mesh, [mat], np.zeros(mesh.p.shape[1], int), load,
        fixed=fixed, tied=[2 * foot + 1],
    )  # fmt: skip
    assert float(np.sum(load * res.velocity)) == pytest.approx(1.0, rel=1e-9)
    assert res.dissipation.sum() == pytest.approx(res.multiplier, rel=1e-6)
    v = res.velocity[foot, 1]
    assert np.allclose(v, v[0]) and v[0] < 0  # rigid footing, downwards
    assert np.all(res.velocity[fixed] == 0.0)
    # The plastic zone touches the footing edge and stays off the far corner.
    x = mesh.p.T
    edge = np.argmin(np.hypot(x[:, 0] - 1.0, x[:, 1] - 5.0))
    corner = np.argmin(np.hypot(x[:, 0] - 5.0, x[:, 1]))
    assert res.plastic[edge] and not res.plastic[corner]


def test_matches_the_incremental_plateau():
    """Same mesh: the one program equals the settlement steps' plateau (0.15 %)."""
    limit = npfem.run_scene(
        "strip-footing", {"analysis": "limit", "refine": "none", "spacing": 0.125}
    )
    steps = npfem.run_scene("strip-footing", {"spacing": 0.125})
    n_limit = limit["metrics"]["bearing_factor"]
    n_steps = steps["metrics"]["bearing_factor"]
    assert limit["metrics"]["cone_programs"] == 1
    assert limit["parameters"]["domain_width"] == 10.0  # the limit mode's default block
    assert n_limit == pytest.approx(n_steps, rel=1.5e-3)


def test_scene_limit_mode_phi30():
    """analysis=limit at half the incremental spacing: N_c(30) within 2 %."""
    s = npfem.run_scene(
        "strip-footing",
        {
            "analysis": "limit",
            "refine": "none",
            "material": "mohr-coulomb",
            "phi": 30.0,
            "spacing": 0.0625,
            "domain_width": 5.0,
        },
    )
    m = s["metrics"]
    assert s["history"] == []
    assert m["collapse_multiplier"] == m["bearing_factor"]
    assert abs(m["relative_error"]) < 0.02
    assert m["q_ult"] == pytest.approx(m["bearing_factor"] * 1.0e4)


def test_strength_reduction_cohesive_is_exact_in_two_programs():
    """Tresca: lambda(F) = lambda(1)/F, so F = lambda(1) after two programs."""
    mesh, fixed, _foot, load = footing_problem(spacing=0.25)
    mat = npfem.Tresca(1e8, 0.3, c=1.0)
    n = mesh.p.shape[1]
    one = npfem.limit_analysis(mesh, [mat], np.zeros(n, int), load, fixed=fixed)
    fos = npfem.strength_reduction(
        mesh, [mat], np.zeros(n, int), load, fixed=fixed, tol=1e-6
    )
    assert fos.programs == 2
    assert fos.factor_of_safety == pytest.approx(one.multiplier, rel=1e-6)


def test_strength_reduction_frictional_converges():
    """Mohr-Coulomb: the last iterate carries the load (multiplier 1 to 1e-4)."""
    mesh, fixed, _foot, load = footing_problem(spacing=0.25)
    mat = npfem.MohrCoulomb(1e8, 0.3, c=1.0, phi=30.0)
    n = mesh.p.shape[1]
    fos = npfem.strength_reduction(mesh, [mat], np.zeros(n, int), load, fixed=fixed)
    assert abs(math.log(fos.limit.multiplier)) <= 1e-4
    assert fos.programs <= 8
    assert fos.factor_of_safety > 1.0
    reduced = npfem.reduced_strength(mat, fos.factor_of_safety)
    assert math.tan(math.radians(reduced.phi)) == pytest.approx(
        math.tan(math.radians(30.0)) / fos.factor_of_safety
    )


def test_strength_reduction_that_finds_no_factor_says_why():
    """Out of programs: a message about the body, not an argument ``--set`` lacks."""
    mesh, fixed, _foot, load = footing_problem(spacing=0.25)
    mat = npfem.MohrCoulomb(1e8, 0.3, c=1.0, phi=30.0)
    n = mesh.p.shape[1]
    with pytest.raises(npfem.NpfemError) as err:
        npfem.strength_reduction(
            mesh, [mat], np.zeros(n, int), load, fixed=fixed, max_programs=1
        )
    assert not isinstance(err.value, npfem.ParameterError)
    assert "in 1 cone programs" in str(err.value) and "supports" in str(err.value)


def test_strength_reduction_counts_the_iterations_of_every_program():
    """Each iterate solved again on its own: the same statuses and iterations."""
    mesh, fixed, _foot, load = footing_problem(spacing=0.25)
    mat = npfem.MohrCoulomb(1e8, 0.3, c=1.0, phi=30.0)
    n = mesh.p.shape[1]
    fos = npfem.strength_reduction(mesh, [mat], np.zeros(n, int), load, fixed=fixed)
    again = [
        npfem.limit_analysis(
            mesh,
            [npfem.reduced_strength(mat, F)],
            np.zeros(n, int),
            load,
            fixed=fixed,
            max_multiplier=1.0e3,
        )
        for F, _ in fos.iterates
    ]
    assert fos.statuses == [r.status for r in again]
    assert fos.iterations == sum(r.iterations for r in again) > fos.programs


def test_a_limit_run_reports_its_cone_programs_not_zero_steps():
    """Reproducer: a limit run's headline said "0 steps, 0 IPM iterations"."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        argv = (
            "run slope --set analysis=limit --set refine=none --set spacing=1.0".split()
        )
        assert main(argv) == 0
    head = out.getvalue().splitlines()[0]
    metrics = dict(
        line.strip().split(" = ", 1) for line in out.getvalue().splitlines()[1:]
    )
    programs, iterations = int(metrics["cone_programs"]), metrics["limit_iterations"]
    assert head.startswith(
        f"scene slope: limit analysis, {programs} cone programs, "
        f"{iterations} IPM iterations, "
    )
    assert programs >= 2 and int(iterations) > programs and "0 steps" not in head


def test_almost_solved_says_what_it_means_for_the_result():
    """An AlmostSolved program is warned and noted: F good to about 1e-4."""
    mesh, fixed, _foot, load = footing_problem(spacing=0.25)
    mat = npfem.Tresca(1e8, 0.3, c=1.0)
    n = mesh.p.shape[1]
    res = npfem.limit_analysis(mesh, [mat], np.zeros(n, int), load, fixed=fixed)
    vol = np.ones(n)
    assert limit_metrics(res, vol, 1)["limit_note"] is None  # Solved: no note
    statuses = ["Solved", "AlmostSolved", "Solved"]
    with pytest.warns(UserWarning, match="1 of the 3 limit program") as w:
        m = limit_metrics(res, vol, 3, statuses=statuses, what="the factor of safety")
    assert m["limit_note"] == str(w[0].message)
    assert "reduced tolerances" in m["limit_note"]
    assert "the factor of safety is certain only to about 1e-4" in m["limit_note"]
    assert m["limit_iterations"] == res.iterations


def test_bad_input():
    """Clear errors: elastic materials, load shapes, limit with a baseline method."""
    mesh, _fixed, _foot, load = footing_problem(spacing=0.25)
    n = mesh.p.shape[1]
    with pytest.raises(npfem.ParameterError, match="plastic materials"):
        npfem.limit_analysis(
            mesh, [npfem.LinearElastic(1e8, 0.3)], np.zeros(n, int), load
        )
    with pytest.raises(npfem.ParameterError, match="load"):
        npfem.limit_analysis(
            mesh, [npfem.Tresca(1e8, 0.3, c=1.0)], np.zeros(n, int), load[:3]
        )
    with pytest.raises(npfem.ParameterError, match="method"):
        npfem.run_scene(
            "strip-footing",
            {
                "analysis": "limit",
                "refine": "none",
                "method": "fem-remap",
                "spacing": 0.25,
            },
        )


# -- a block deep enough for the mechanism, and the hints of a failed program -----
# Reproducer: ``strip-footing --set analysis=limit --set material=mohr-coulomb
# --set phi=60`` finished with status Solved and N_c = 3123 against the exact
# (N_q - 1) cot phi = 1855 (+68 %).  The cause: Prandtl's mechanism is 18.6 b
# deep at 60 degrees and the default block 10 b, so its fixed base cuts the
# mechanism off.  The scenes refuse such a block, and a failed limit program
# advises on limit analysis, not on the load steps it does not have.
STATUSES = (
    "PrimalInfeasible",
    "AlmostPrimalInfeasible",
    "DualInfeasible",
    "AlmostDualInfeasible",
    "MaxIterations",
    "MaxTime",
    "NumericalError",
    "InsufficientProgress",
)


@pytest.mark.parametrize("phi", [0.0, 30.0, 50.0, 60.0])
def test_prandtl_depth_is_the_deepest_point_of_the_mechanism(phi):
    """Against the fan sampled finely (the wedges are shallower than the fan)."""
    f = math.radians(phi)
    a = math.pi / 4 + f / 2
    theta = np.linspace(0.0, math.pi / 2, 200001)
    fan = np.exp(theta * math.tan(f)) * np.sin(a + theta) / math.cos(a)
    assert prandtl_depth(phi) == pytest.approx(fan.max(), rel=1e-9)
    assert prandtl_depth(phi) >= math.tan(a)  # the active wedge's apex


def test_a_block_shallower_than_the_mechanism_overestimates():
    """phi = 50: mechanism 8.1 b deep; a 5 b block is far off, a 10 b one is not."""
    c, phi = 1.0e4, 50.0
    mat = npfem.MohrCoulomb(1e8, 0.3, c=c, phi=phi)
    err = {}
    for domain in (5.0, MECHANISM_MARGIN * prandtl_depth(phi)):
        mesh, fixed, foot, load = footing_problem(domain=domain)
        res = npfem.limit_analysis(
            mesh, [mat], np.zeros(mesh.p.shape[1], int), c * load,
            fixed=fixed, tied=[2 * foot + 1],
        )  # fmt: skip
        assert res.status == "Solved"
        err[domain] = res.multiplier / prandtl_nc(phi) - 1
    shallow, deep = err.values()
    assert shallow > 0.1
    assert abs(deep) < COARSE_TOL


@pytest.mark.parametrize("phi", [60.0, 70.0, 80.0, 85.0])
def test_strip_footing_refuses_a_block_the_mechanism_does_not_fit(phi):
    code, err = run_cli(
        ["run", "strip-footing", "--set", "analysis=limit", "--set", "refine=none",
         "--set", "material=mohr-coulomb", "--set", f"phi={phi:g}"]
    )  # fmt: skip
    need = MECHANISM_MARGIN * prandtl_depth(phi)
    check_cli_error(code, err, "domain_width=10.0", f"at least {need:.3g} half-widths")


def test_the_refusal_names_a_block_and_a_phi_that_hold_the_mechanism():
    """phi = 55 in a 10 b block: refused; in the block the message names, N_c holds."""
    code, err = run_cli(
        ["run", "strip-footing", "--set", "analysis=limit", "--set", "refine=none",
         "--set", "material=mohr-coulomb", "--set", "phi=55"]
    )  # fmt: skip
    line = check_cli_error(
        code, err, "set domain_width=14", "phi <= 50.5 for this block"
    )
    assert (
        MECHANISM_MARGIN * prandtl_depth(50.5)
        <= 10
        < MECHANISM_MARGIN * (prandtl_depth(50.6))
    ), line
    res = npfem.run_scene(
        "strip-footing",
        {"analysis": "limit", "refine": "none", "material": "mohr-coulomb", "phi": 55.0,
         "domain_width": 14.0, "spacing": 0.125},
    )  # fmt: skip
    assert res["metrics"]["limit_status"] == "Solved"
    assert abs(res["metrics"]["bearing_factor"] / prandtl_nc(55.0) - 1) < COARSE_TOL


def test_the_block_check_leaves_tresca_alone():
    """Tresca has no friction angle: a 2 b block is not refused for Tresca,
    though it is for Mohr-Coulomb at phi = 20 (needs 1.2 x 2.32 b)."""
    scene = npfem.get_scene("strip-footing")
    shallow = {"analysis": "limit", "refine": "none", "domain_width": 2.0}
    check_limit_method(scene.resolve({**shallow, "material": "tresca"}))
    frictional = {**shallow, "material": "mohr-coulomb", "phi": 20.0}
    with pytest.raises(npfem.ParameterError, match="domain_width"):
        check_limit_method(scene.resolve(frictional))


@pytest.mark.parametrize("status", STATUSES)
def test_limit_hints_name_no_steps(status):
    """A limit program has no time or load steps: its hints never name them."""
    hint = limit_hint(status)
    assert hint
    for step_advice in ("dt", "load steps (more", "smaller load", "adaptive"):
        assert step_advice not in hint


def test_a_failed_limit_program_carries_the_limit_hint(monkeypatch):
    """The hint of a failed program is :func:`limit_hint`'s (forced NumericalError)."""
    import skfem_npfem.limit.program as program

    real = program.solve_clarabel

    def failing(*args, **kwargs):
        res = real(*args, **kwargs)
        res.status = "NumericalError"
        return res

    monkeypatch.setattr(program, "solve_clarabel", failing)
    mesh, fixed, foot, load = footing_problem(spacing=0.5)
    mat = npfem.MohrCoulomb(1e8, 0.3, c=1e4, phi=30.0)
    with pytest.raises(npfem.SolverError) as err:
        npfem.limit_analysis(
            mesh, [mat], np.zeros(mesh.p.shape[1], int), 1e4 * load,
            fixed=fixed, tied=[2 * foot + 1],
        )  # fmt: skip
    assert limit_hint("NumericalError") in str(err.value)
    assert "load steps" not in str(err.value)


def test_a_velocity_map_says_the_same_kinematics_in_any_basis():
    """The multiplier is a property of the admissible velocities, not of their basis.

    The smooth footing's tie as a velocity map gives the tied program's
    multiplier; the same velocities in another basis (each free node's two
    dofs rotated by 30 degrees, the footing's unknown scaled by 3) give it
    too; a map beside ``tied``, or of the wrong size, is refused.
    """
    import scipy.sparse as sp

    from skfem_npfem.limit.program import dof_map

    mesh, fixed, foot, load = footing_problem()
    mat = npfem.MohrCoulomb(1e8, 0.3, c=1.0, phi=20.0)
    zero = np.zeros(mesh.p.shape[1], int)
    tied = npfem.limit_analysis(
        mesh, [mat], zero, load, fixed=fixed, tied=[2 * foot + 1]
    ).multiplier
    T, _ = dof_map(fixed.size, fixed.reshape(-1), [2 * foot + 1])
    same = npfem.limit_analysis(mesh, [mat], zero, load, fixed=fixed, velocity_map=T)
    assert same.multiplier == pytest.approx(tied, rel=1e-9)
    # Another basis: free nodes rotated, the footing's column scaled.
    n = fixed.shape[0]
    rot = np.eye(2 * n)
    c, s = math.cos(math.pi / 6), math.sin(math.pi / 6)
    for k in np.flatnonzero(~fixed.any(axis=1) & ~np.isin(np.arange(n), foot)):
        rot[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] = [[c, -s], [s, c]]
    scale = np.ones(T.shape[1])
    scale[np.flatnonzero(T[2 * foot[0] + 1].toarray())] = 3.0
    other = sp.csc_matrix(rot) @ T @ sp.diags(scale)
    turned = npfem.limit_analysis(
        mesh, [mat], zero, load, fixed=fixed, velocity_map=other
    )
    assert turned.multiplier == pytest.approx(tied, rel=1e-6)
    with pytest.raises(npfem.ParameterError, match="tied"):
        npfem.limit_analysis(
            mesh, [mat], zero, load, fixed=fixed, tied=[2 * foot + 1], velocity_map=T
        )
    with pytest.raises(npfem.ParameterError, match="velocity_map"):
        npfem.limit_analysis(mesh, [mat], zero, load, velocity_map=T[:-2])
