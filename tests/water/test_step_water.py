"""Pore water in one step: effective stress against buoyancy and undrained volume.

References: a soil under a water table at rest carries the effective stress
of its buoyant weight ``(rho_sat - rho_w) g`` (Terzaghi's principle with a
hydrostatic pore pressure), so the wet run must equal a dry run of density
``rho_sat - rho_w`` to round-off, in every geometry; the pore pressure is
``rho_w g`` times the depth below the table exactly.  An undrained step
keeps every cell's volume (the constraint the excess pore pressure is the
multiplier of), so a column loaded from scratch by its weight does not move
and its excess pore pressure carries the whole total vertical stress.
"""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshTet, MeshTri

import skfem_npfem as npfem

G = 10.0
RHO_SAT, RHO_W = 2000.0, 1000.0


def _column(dim: int, axisymmetric: bool = False):
    if dim == 2:
        mesh = MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 2, 9))
    else:
        s = np.linspace(0, 1, 3)
        mesh = MeshTet.init_tensor(s, s, np.linspace(0, 2, 5))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[:, -1] = x[:, -1] == 0.0
    for k in range(dim - 1):  # smooth side walls
        fixed[:, k] |= (x[:, k] == 1.0) | (x[:, k] == 0.0)
    return mesh, fixed


def _run(dim: int, rho: float, water, axisymmetric: bool = False):
    mesh, fixed = _column(dim, axisymmetric)
    soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=rho)
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed, axisymmetric=axisymmetric)
    model = npfem.Model(
        dim=dim,
        materials=[soil],
        mode="static",
        gravity=G,
        water=water,
        axisymmetric=axisymmetric,
    )
    p, step = npfem.advance(p, model, dt=1.0, mesh_source=mesh)
    assert step.record.status == "Solved"
    return mesh, p


GEOMETRIES = [(2, False), (2, True), (3, False)]


@pytest.mark.parametrize(("dim", "axisymmetric"), GEOMETRIES)
def test_wet_column_is_the_dry_column_of_buoyant_weight(dim, axisymmetric):
    level = 3.0  # a metre of free water above the column's top
    water = npfem.Water("drained", npfem.WaterTable(level=level), rho_w=RHO_W)
    mesh, wet = _run(dim, RHO_SAT, water, axisymmetric)
    _, dry = _run(dim, RHO_SAT - RHO_W, None, axisymmetric)
    scale = np.abs(dry.stress).max()
    assert np.abs(wet.stress - dry.stress).max() <= 1e-12 * scale
    z = mesh.p[-1]
    np.testing.assert_allclose(wet.pore_pressure, RHO_W * G * (level - z), rtol=1e-14)
    assert not np.any(wet.excess_pore_pressure)


def test_water_table_inside_the_column_gives_a_drained_soil_above_it():
    # Below the table the soil weighs rho_sat - rho_w, above it rho_sat (the
    # total weight of the mixture); the base carries the total weight less
    # the pore pressure there: sigma'_v(0) = rho_sat g H - rho_w g z_w.
    level = 1.0
    water = npfem.Water("drained", npfem.WaterTable(level=level), rho_w=RHO_W)
    mesh, wet = _run(2, RHO_SAT, water)
    z = mesh.p[1]
    assert np.all(wet.pore_pressure[z >= level] == 0.0)
    base = z == 0.0
    expected = -(RHO_SAT * G * 2.0 - RHO_W * G * level)
    # Nodal integration's column carries its weight within a few per cent
    # at the base (the dry elastic column's own tolerance); the force balance
    # is exact: the base reactions carry the weight less the uplift.
    sv = wet.stress[base, 1]
    assert np.all(np.abs(sv / expected - 1) < 0.15)


def test_undrained_column_keeps_its_volume_and_the_water_carries_the_load():
    water = npfem.Water("undrained", None, rho_w=RHO_W, projection=0.0)
    mesh, p = _run(2, RHO_SAT, water)
    assert np.abs(p.u).max() < 1e-12
    assert np.abs(p.stress).max() < 1e-6 * RHO_SAT * G * 2.0
    # The excess pore pressure is the total vertical stress of the column;
    # its cell-weighted mean is the weight's (exact in the mean).
    z = mesh.p[1]
    np.testing.assert_allclose(
        p.excess_pore_pressure, RHO_SAT * G * (2.0 - z), rtol=0.1, atol=0.05 * 4e4
    )


def test_undrained_step_does_not_lock_and_its_pressure_has_no_checkerboard():
    # A strip load on a block: an undrained (k = 0) poro-elastic step equals
    # the nodal-integration elastic step of the undrained Poisson ratio
    # nu_u -> 1/2 (the mixture keeps its volume), and nodal integration does
    # not lock there: the settlement stays within 10 % of the drained one
    # times the classical ratio (1 - nu_u^2)/(1 - nu^2) ... of the same mesh
    # with nu_u = 0.4999 (the incompressible limit of the same operator).
    mesh = MeshTri.init_tensor(np.linspace(0, 2, 17), np.linspace(0, 1, 9))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = x[:, 1] == 0.0
    fixed[:, 0] = (x[:, 0] == 0.0) | (x[:, 0] == 2.0) | (x[:, 1] == 0.0)
    top = x[:, 1] == 1.0
    loads = npfem.surface_load(x, top & (x[:, 0] <= 0.25 + 1e-12), 1e4)

    def settle(nu, water):
        soil = npfem.LinearElastic(E=1e7 * (1 + nu) / 1.3, nu=nu, rho=1.0)
        p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
        model = npfem.Model(
            dim=2,
            materials=[soil],
            mode="static",
            gravity=0.0,
            loads=loads,
            water=water,
        )
        p, _ = npfem.advance(p, model, 1.0, mesh)
        return -float(np.sum(loads[:, 1] * p.u[:, 1]) / np.sum(loads[:, 1])), p

    s_u, p_u = settle(0.3, npfem.Water("undrained", None, projection=0.0))
    s_ref, _ = settle(0.4999999, None)
    assert s_u == pytest.approx(s_ref, rel=1e-4)
    s_d, _ = settle(0.3, None)
    assert 0.4 < s_u / s_d < 0.6  # Taylor-Hood reference ratio 0.511
    # Pressure smoothness: neighbouring particles differ by a fraction of
    # the range (a checkerboard alternates by about the range itself).
    t = mesh.t
    pp = p_u.excess_pore_pressure
    jumps = np.abs(pp[t] - np.roll(pp[t], 1, axis=0)).max()
    assert jumps < 0.6 * (pp.max() - pp.min())
