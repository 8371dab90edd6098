"""Limit analysis as one cone program (skfem_npfem.limit).

References: the exact bearing factor N_c of a smooth strip footing on a
weightless Mohr-Coulomb soil (Prandtl 1920, Reissner 1924; ``laws.prandtl_nc``),
the proportionality of a purely cohesive collapse load to ``c``, and strong
duality (the dissipated power of the mechanism equals the multiplier's work).
The 2 % gate at the limit mode's default spacing and the convergence with the
spacing are measured by ``demos/studies/limit_footing.py`` (docs/validation).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import skfem_npfem as npfem
from skfem_npfem.laws import prandtl_nc
from skfem_npfem.scenes.footing.mesh import soil_mesh
from skfem_npfem.scenes.footing.strip import PARAMS

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
    limit = npfem.run_scene("strip-footing", {"analysis": "limit", "spacing": 0.125})
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
            {"analysis": "limit", "method": "fem-remap", "spacing": 0.25},
        )
