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
import scipy.sparse as sp
from skfem import (
    Basis,
    BilinearForm,
    ElementTriP1,
    ElementTriP2,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshTet,
    MeshTri,
    asm,
    condense,
    solve,
)
from skfem.helpers import ddot, div, sym_grad

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


def _strip_block(nx: int, ny: int):
    """A 2 x 1 half block, smooth sides, fixed base, q0 = 10 kPa on 0 <= x <= 0.25."""
    mesh = MeshTri.init_tensor(np.linspace(0, 2, nx + 1), np.linspace(0, 1, ny + 1))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = x[:, 1] == 0.0
    fixed[:, 0] = (x[:, 0] == 0.0) | (x[:, 0] == 2.0) | (x[:, 1] == 0.0)
    top = x[:, 1] == 1.0
    loads = npfem.surface_load(x, top & (x[:, 0] <= 0.25 + 1e-12), 1e4)
    return mesh, fixed, loads


SHEAR = 1e7 / 2.6  # G of E = 10 MPa, nu = 0.3


def _settle(mesh, fixed, loads, nu, water):
    """Work-conjugate settlement f . u / (q0 b) of one static step, m."""
    soil = npfem.LinearElastic(E=2 * SHEAR * (1 + nu), nu=nu, rho=1.0)
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    model = npfem.Model(
        dim=2, materials=[soil], mode="static", gravity=0.0, loads=loads, water=water
    )
    p, _ = npfem.advance(p, model, 1.0, mesh)
    return float(np.sum(loads * p.u) / np.sum(loads[:, 1])), p


def _taylor_hood_settlement(nx: int, ny: int) -> float:
    """The incompressible strip-load settlement with Taylor-Hood P2/P1 (scikit-fem).

    An independent discretisation of the same problem (displacement P2,
    pressure P1, exactly incompressible): the reference the undrained step
    converges to.
    """
    m = MeshTri.init_tensor(np.linspace(0, 2, nx + 1), np.linspace(0, 1, ny + 1))
    ub = Basis(m, ElementVector(ElementTriP2()), intorder=4)
    pb = Basis(m, ElementTriP1(), intorder=4)

    @BilinearForm
    def a(u, v, w):
        return 2 * SHEAR * ddot(sym_grad(u), sym_grad(v))

    @BilinearForm
    def b(u, q, w):
        return -q * div(u)

    @LinearForm
    def load(v, w):
        return -1e4 * v[1]

    B = asm(b, ub, pb)
    K = sp.bmat([[asm(a, ub), B.T], [B, None]], "csr")
    strip = m.facets_satisfying(lambda x: (x[1] > 1 - 1e-9) & (x[0] < 0.25 + 1e-9))
    f_u = asm(load, FacetBasis(m, ub.elem, facets=strip))
    f = np.concatenate([f_u, np.zeros(pb.N)])
    sides = ub.get_dofs(lambda x: (x[0] < 1e-9) | (x[0] > 2 - 1e-9)).all("u^1")
    base = ub.get_dofs(lambda x: x[1] < 1e-9).all()
    D = np.unique(np.concatenate([sides, base]))
    x = solve(*condense(K, f, D=D))
    return float(f_u @ x[: ub.N] / (-1e4 * 0.25))


def test_undrained_step_does_not_lock_and_converges_to_taylor_hood():
    # An undrained (k = 0) poro-elastic step of a strip load: the mixture
    # keeps its volume, so it equals the nodal elastic step of nu -> 1/2
    # (nodal integration does not lock there), and it converges from above
    # to the exactly incompressible Taylor-Hood solution of the same problem.
    reference = _taylor_hood_settlement(64, 32)
    errors = []
    for nx, ny in ((16, 8), (32, 16)):
        mesh, fixed, loads = _strip_block(nx, ny)
        no_projection = npfem.Water("undrained", None, projection=0.0)
        s_u, _ = _settle(mesh, fixed, loads, 0.3, no_projection)
        s_nu, _ = _settle(mesh, fixed, loads, 0.4999999, None)
        assert s_u == pytest.approx(s_nu, rel=1e-5)
        errors.append(s_u / reference - 1)
    assert 0 < errors[1] < 0.03
    assert errors[1] < 0.5 * errors[0]
    # ... and about half the drained settlement (undrained / drained 0.511
    # for this block by Taylor-Hood at nu = 0.3).
    s_d, _ = _settle(mesh, fixed, loads, 0.3, None)
    assert s_u / s_d == pytest.approx(0.511, abs=0.01)


def test_pressure_projection_keeps_the_undrained_pressure_in_its_range():
    # Under a strip load the exact excess pore pressure lies between 0 and
    # the load q0 (it is minus the change of the total mean stress of an
    # incompressible elastic half-plane under a strip, which lies in
    # [-q0, 0]).  The raw nodal pressure overshoots both bounds on a lattice
    # of parallel diagonals (its checkerboard); the projection pulls it in.
    mesh, fixed, loads = _strip_block(16, 8)
    _, raw = _settle(
        mesh, fixed, loads, 0.3, npfem.Water("undrained", None, projection=0.0)
    )
    _, proj = _settle(mesh, fixed, loads, 0.3, npfem.Water("undrained", None))
    for p, low, high in ((raw, -0.2, 1.05), (proj, -0.07, 0.95)):
        q = p.excess_pore_pressure / 1e4
        assert low < q.min() and q.max() < high
    assert proj.excess_pore_pressure.min() > raw.excess_pore_pressure.min()
