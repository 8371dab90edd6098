"""Steady seepage: Darcy's problem on the step's mesh and its pore pressure.

References:

* a sheet pile of penetration ``s`` in a permeable layer of thickness ``T``
  on an impermeable base, head ``H`` upstream and 0 downstream, passes
  ``q / (k H) = K(m') / (2 K(m))``, ``m = sin(pi s / (2 T))``,
  ``m'^2 = 1 - m^2`` (Harr, "Groundwater and Seepage", 1962, the sheet pile
  in a layer of finite depth; derived by conformal mapping in
  ``demos/studies/seepage_sheet_pile.py``).  Limits: ``s -> 0`` an unbounded
  flow, ``s -> T`` none; ``s = T / 2`` exactly ``k H / 2``.  The P1 flow
  converges at O(h) (the head's ``r^(1/2)`` singularity at the tip), so the
  coarse mesh is held to 5 % and its Richardson extrapolation to 0.5 %;
* between two heads a column carries the linear head and the uniform flux
  ``k dh / L`` (Darcy), which P1 reproduces exactly on any mesh;
* water conservation: the flows through all head boundaries sum to zero;
* a soil under a uniform head is at rest in hydrostatic water: its pore
  pressure and effective stresses are those of the water table at that head
  to round-off; an upward flow with gradient ``i`` lightens the soil by the
  seepage force ``rho_w g i`` per unit volume (Terzaghi), so the column
  equals a dry column of density ``rho_sat - rho_w (1 + i)``.
"""

from __future__ import annotations

import numpy as np
import pytest
from seepage_sheet_pile import reference, sheet_pile_mesh, sheet_pile_seepage
from skfem import MeshTri

import skfem_npfem as npfem
from skfem_npfem.errors import ParameterError
from skfem_npfem.water import HeadBoundary, Seepage, solve_heads

G = 10.0
RHO_SAT, RHO_W = 2000.0, 1000.0


@pytest.mark.parametrize("ratio", [0.25, 0.5])
def test_sheet_pile_flow_matches_the_conformal_mapping(ratio):
    assert reference(0.5) == pytest.approx(0.5, rel=1e-14)
    flows = {}
    for n in (8, 16):
        x, t = sheet_pile_mesh(1.0, ratio, n)
        field = sheet_pile_seepage(1.0, 1.0).solve(x, t)
        inflow = field.inflow
        assert abs(inflow["upstream"] + inflow["downstream"]) <= 1e-10
        flows[n] = inflow["upstream"]
    ref = reference(ratio)
    assert flows[16] == pytest.approx(ref, rel=0.05)
    assert 2.0 * flows[16] - flows[8] == pytest.approx(ref, rel=0.005)


def _strip(width: float, height: float, nx: int, nz: int, seed: int = 0):
    """A rectangle of triangles with its interior nodes shaken (not a grid)."""
    mesh = MeshTri.init_tensor(
        np.linspace(0, width, nx + 1), np.linspace(0, height, nz + 1)
    )
    x = mesh.p.T.copy()
    inner = (x[:, 0] > 0) & (x[:, 0] < width) & (x[:, 1] > 0) & (x[:, 1] < height)
    rng = np.random.default_rng(seed)
    x[inner] += rng.uniform(-0.2, 0.2, (inner.sum(), 2)) * [width / nx, height / nz]
    return x, mesh.t


def test_column_between_two_heads_has_the_linear_head_and_darcy_flux():
    width, length, k = 0.5, 2.0, 3e-5
    x, t = _strip(width, length, 3, 8)
    base = HeadBoundary([[0.0, 0.0], [width, 0.0]], head=5.0, name="base")
    top = HeadBoundary([[0.0, length], [width, length]], head=2.0, name="top")
    field = Seepage([base, top], k=k).solve(x, t)
    exact = 5.0 - 3.0 * x[:, 1] / length
    np.testing.assert_allclose(field.head, exact, rtol=0, atol=1e-13)
    q = k * 3.0 / length * width
    assert field.inflow["base"] == pytest.approx(q, rel=1e-12)
    assert field.inflow["top"] == pytest.approx(-q, rel=1e-12)


def test_solve_heads_takes_element_conductivities():
    # Two layers in series, the interface on a grid line: the flux is
    # dh / (L1 / k1 + L2 / k2) and the head is linear in each layer.
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 2, 9))
    x, t = mesh.p.T, mesh.t
    k_e = np.where(x[t, 1].mean(axis=0) < 1.0, 1.0, 4.0)
    bottom, top = np.flatnonzero(x[:, 1] == 0), np.flatnonzero(x[:, 1] == 2)
    nodes = np.concatenate([bottom, top])
    heads = np.concatenate([np.full(bottom.size, 1.0), np.zeros(top.size)])
    h = solve_heads(x, t, nodes, heads, k_e)
    q = 1.0 / (1.0 / 1.0 + 1.0 / 4.0)  # flux per unit width
    z = x[:, 1]
    exact = np.where(z < 1.0, 1.0 - q * z, q / 4.0 * (2.0 - z))
    np.testing.assert_allclose(h, exact, rtol=0, atol=1e-13)


def test_a_node_outside_the_mesh_has_no_pore_pressure():
    x, t = _strip(1.0, 2.0, 2, 4)
    x = np.vstack([x, [[0.5, 3.0]]])  # a particle flying above the soil
    base = HeadBoundary([[0.0, 0.0], [1.0, 0.0]], 4.0)
    p = Seepage([base]).pressure(x, t, None, RHO_W, G)
    np.testing.assert_allclose(p[:-1], RHO_W * G * (4.0 - x[:-1, 1]), rtol=1e-12)
    assert p[-1] == 0.0


def _column_run(water, rho: float, axisymmetric: bool = False):
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 2, 9))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = x[:, 1] == 0.0
    fixed[:, 0] = (x[:, 0] == 0.0) | (x[:, 0] == 1.0)
    soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=rho)
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed, axisymmetric=axisymmetric)
    model = npfem.Model(
        dim=2,
        materials=[soil],
        mode="static",
        gravity=G,
        water=water,
        axisymmetric=axisymmetric,
    )
    p, step = npfem.advance(p, model, dt=1.0, mesh_source=mesh)
    assert step.record.status == "Solved"
    return x, p


@pytest.mark.parametrize("drainage", ["drained", "undrained"])
def test_uniform_head_is_the_water_table_at_that_level(drainage):
    level = 3.0  # a metre of free water over the block's top at z = 2
    heads = [
        HeadBoundary([[0.0, 2.0], [1.0, 2.0]], level, "surface"),
        HeadBoundary([[0.0, 0.0], [0.0, 2.0]], level, "left side"),
    ]
    seep = npfem.Water(drainage, seepage=Seepage(heads, k=1e-4), rho_w=RHO_W)
    table = npfem.Water(drainage, npfem.WaterTable(level=level), rho_w=RHO_W)
    x, wet = _column_run(seep, RHO_SAT)
    _, ref = _column_run(table, RHO_SAT)
    scale = np.abs(ref.stress).max()
    assert np.abs(wet.stress - ref.stress).max() <= 1e-12 * scale
    static = wet.pore_pressure - wet.excess_pore_pressure
    np.testing.assert_allclose(static, RHO_W * G * (level - x[:, 1]), rtol=1e-13)
    excess = wet.excess_pore_pressure - ref.excess_pore_pressure
    assert np.abs(excess).max() <= 1e-12 * scale


def test_upward_flow_lightens_the_soil_by_the_seepage_force():
    top_head, gradient = 3.0, 0.4  # i = (h_base - h_top) / H, upward flow
    heads = [
        HeadBoundary([[0.0, 2.0], [1.0, 2.0]], top_head, "top"),
        HeadBoundary([[0.0, 0.0], [1.0, 0.0]], top_head + 2.0 * gradient, "base"),
    ]
    water = npfem.Water("drained", seepage=Seepage(heads, k=1e-4), rho_w=RHO_W)
    x, wet = _column_run(water, RHO_SAT)
    _, dry = _column_run(None, RHO_SAT - RHO_W * (1.0 + gradient))
    scale = np.abs(dry.stress).max()
    assert np.abs(wet.stress - dry.stress).max() <= 1e-11 * scale
    head = top_head + gradient * (2.0 - x[:, 1])
    np.testing.assert_allclose(
        wet.pore_pressure, RHO_W * G * (head - x[:, 1]), rtol=1e-12
    )


def test_head_below_the_point_gives_no_suction():
    x, t = _strip(1.0, 2.0, 2, 4)
    heads = [HeadBoundary([[0.0, 0.0], [1.0, 0.0]], 1.0)]  # head 1 m, soil to 2 m
    p = Seepage(heads).pressure(x, t, None, RHO_W, G)
    np.testing.assert_allclose(p, RHO_W * G * np.maximum(1.0 - x[:, 1], 0.0), atol=1e-9)
    assert np.all(p[x[:, 1] > 1.0 + 1e-9] == 0.0)  # clamped, not negative


def test_bad_input_is_refused_with_the_parameter_named():
    x, t = _strip(1.0, 2.0, 2, 4)
    line = [[0.0, 2.0], [1.0, 2.0]]
    with pytest.raises(ParameterError, match=r"heads.*at least one HeadBoundary"):
        Seepage([])
    with pytest.raises(ParameterError, match=r"k=0.*> 0"):
        Seepage([HeadBoundary(line, 1.0)], k=0.0)
    with pytest.raises(ParameterError, match=r"k\[1\]=-1"):
        Seepage([HeadBoundary(line, 1.0)], k=[1.0, -1.0])
    with pytest.raises(ParameterError, match="head boundary 'lake' head=nan"):
        HeadBoundary(line, float("nan"), "lake")
    with pytest.raises(ParameterError, match="conductivities > 0"):
        solve_heads(x, t, [0], [1.0], np.zeros(t.shape[1]))
    with pytest.raises(ParameterError, match="finite heads"):
        solve_heads(x, t, [0], [np.inf], np.ones(t.shape[1]))
    far = Seepage([HeadBoundary([[5.0, 5.0], [6.0, 5.0]], 1.0, "lake")])
    with pytest.raises(ParameterError, match=r"'lake'.*x in \[0, 1\], z in \[0, 2\]"):
        far.solve(x, t)
    with pytest.raises(ParameterError, match="one of a water table and a seepage"):
        npfem.Water("drained", npfem.WaterTable(level=1.0), seepage=far)
    wet = npfem.Water("drained", seepage=Seepage([HeadBoundary(line, 3.0)]))
    with pytest.raises(ParameterError, match=r"seepage.*plane-strain section"):
        _column_run(wet, RHO_SAT, axisymmetric=True)
    with pytest.raises(ParameterError, match="one conductivity per material"):
        Seepage([HeadBoundary(line, 1.0)], k=[1.0]).solve(x, t, np.ones(len(x), int))
