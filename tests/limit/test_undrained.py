"""Undrained limit analysis in effective stress (skfem_npfem.limit.undrained).

Reference: a smooth strip footing on a weightless Tresca soil carries
``q = (2 + pi) s_u`` (Prandtl 1920); an associated Mohr-Coulomb soil under a
uniform isotropic effective stress ``p'_0`` has, undrained, the strength
``s_u = c' cos(phi') + p'_0 sin(phi')`` of its cone at that pressure (the
centre of the Mohr circle held at ``p'_0``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from limit.test_limit_analysis import footing_problem

import skfem_npfem as npfem
from skfem_npfem.errors import ParameterError
from skfem_npfem.limit import (
    UndrainedStrength,
    reduced_strength,
    undrained_materials,
    undrained_strength,
)
from skfem_npfem.mesh.axisymmetric import AxisymmetricMohrCoulomb

#: |q / ((2 + pi) s_u) - 1| at spacing 0.125 b (measured +0.44 %; +0.08 % at
#: 0.0625 b), the tolerance the undrained footing is held to.
UNDRAINED_TOL = 0.02


def _s_u(c: float, phi: float, p0: float) -> float:
    f = math.radians(phi)
    return c * math.cos(f) + p0 * math.sin(f)


@pytest.mark.parametrize("phi", [20.0, 30.0])
def test_undrained_footing_is_prandtl_with_the_implied_strength(phi):
    """q / s_u within 2 % of 2 + pi for s_u = c' cos phi' + p'_0 sin phi'."""
    mesh, fixed, foot, load = footing_problem()
    n = mesh.p.shape[1]
    c, p0 = 1.0e4, 5.0e4
    stress = np.zeros((n, 4))
    stress[:, :3] = -p0  # uniform isotropic effective stress
    mc = npfem.MohrCoulomb(1e8, 0.3, c=c, phi=phi)
    mats = undrained_materials([mc], np.zeros(n, int), stress)
    s_u = _s_u(c, phi, p0)
    res = npfem.limit_analysis(
        mesh, mats, np.zeros(n, int), s_u * load, fixed=fixed, tied=[2 * foot + 1]
    )
    assert res.status == "Solved"
    assert abs(res.multiplier / (2 + math.pi) - 1) < UNDRAINED_TOL


def test_strengths_per_kind():
    """Plane strain: the in-plane centre; axisymmetry: the mean; clamped at 0."""
    mc = npfem.MohrCoulomb(1e7, 0.3, c=2e3, phi=30.0)
    s = np.array([[-1e4, -3e4, -5e4, 1e3], [1e5, 1e5, 1e5, 0.0]])
    np.testing.assert_allclose(
        undrained_strength(mc, s), [_s_u(2e3, 30.0, 2e4), 0.0], rtol=1e-12
    )
    ax = AxisymmetricMohrCoulomb(1e7, 0.3, c=2e3, phi=30.0)
    np.testing.assert_allclose(
        undrained_strength(ax, s[:1]), [_s_u(2e3, 30.0, 3e4)], rtol=1e-12
    )
    rows = UndrainedStrength(ax, [3e4]).cone(2, (0, 1, 2, 3), np.zeros((1, 4)))
    s_u = _s_u(2e3, 30.0, 3e4)
    # Tresca in axisymmetry: R <= s_u and the two hoop cones with 2 s_u.
    assert [float(r.k[0]) for r in rows] == pytest.approx([s_u, 2 * s_u, 2 * s_u])


def test_strength_reduction_reduces_the_effective_parameters():
    """F divides c' and tan(phi'); s_u follows at the same s'_0."""
    mc = npfem.MohrCoulomb(1e7, 0.3, c=2e3, phi=30.0)
    u = reduced_strength(UndrainedStrength(mc, [1e4]), 2.0)
    phi_f = math.degrees(math.atan(math.tan(math.radians(30.0)) / 2))
    assert float(u.s_u[0]) == pytest.approx(_s_u(1e3, phi_f, 1e4), rel=1e-12)


def test_bad_input():
    """A point count that disagrees, and a material without c' and phi'."""
    mc = npfem.MohrCoulomb(1e7, 0.3, c=2e3, phi=30.0)
    with pytest.raises(ParameterError, match="pressure"):
        UndrainedStrength(mc, [1e4, 2e4]).cone(2, (0, 1, 3), np.zeros((3, 4)))
    with pytest.raises(ParameterError, match="material"):
        undrained_strength(npfem.VonMises(1e7, 0.3, sigma_y=1e3), np.zeros((1, 4)))
    with pytest.raises(ParameterError, match="stress"):
        undrained_materials([mc], np.zeros(3, int), np.zeros((2, 4)))


def test_undrained_drucker_prager_footing_is_von_mises_at_p0():
    """Drucker-Prager cut at p'_0: von Mises sqrt(J2) <= k + 3 alpha p'_0, and a
    plane-strain von Mises footing carries (2 + pi) times that (Prandtl)."""
    mesh, fixed, foot, load = footing_problem()
    n = mesh.p.shape[1]
    c, p0, phi = 1.0e4, 5.0e4, 30.0
    stress = np.zeros((n, 4))
    stress[:, :3] = -p0
    dp = npfem.DruckerPrager(1e8, 0.3, c=c, phi=phi)
    t = math.tan(math.radians(phi))
    root = math.sqrt(9 + 12 * t**2)  # the plane-strain match
    s_u = 3 * c / root + 3 * (t / root) * p0
    assert undrained_strength(dp, stress[:1])[0] == pytest.approx(s_u, rel=1e-12)
    mats = undrained_materials([dp], np.zeros(n, int), stress)
    res = npfem.limit_analysis(
        mesh, mats, np.zeros(n, int), s_u * load, fixed=fixed, tied=[2 * foot + 1]
    )
    assert abs(res.multiplier / (2 + math.pi) - 1) < UNDRAINED_TOL
