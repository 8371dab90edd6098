"""The scikit-fem shaped API: meshes in, meshes and P1 fields out.

References: the weight of a soil column (the base reaction, ``rho g H W``) for
the round trip; today's array path (``Particles.create`` with ``rho V_i`` and
``FixedMesh(mesh.t)``) for the mesh path, bit for bit; the particle arrays
themselves for the fields scikit-fem interpolates.
"""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest
from skfem import (
    Basis,
    ElementTriP1,
    ElementVector,
    MeshQuad,
    MeshTet,
    MeshTri,
)

import skfem_npfem as npfem

DEMO = Path(__file__).resolve().parents[2] / "demos" / "skfem_round_trip.py"
SOIL = npfem.LinearElastic(E=1e7, nu=0.3, rho=2000.0)


def _column(nx: int = 5, ny: int = 9) -> tuple[MeshTri, np.ndarray]:
    mesh = MeshTri.init_tensor(np.linspace(0, 1, nx), np.linspace(0, 2, ny))
    x = mesh.p.T
    fixed = np.zeros(x.shape, bool)
    fixed[x[:, 1] == 0.0] = True
    fixed[(x[:, 0] == 0.0) | (x[:, 0] == 1.0), 0] = True
    return mesh, fixed


def _same(a: npfem.Particles, b: npfem.Particles) -> None:
    for name, arr in a.arrays().items():
        other = b.arrays()[name]
        assert arr.dtype == other.dtype and np.array_equal(arr, other), name


def test_round_trip_demo_base_force_is_the_weight():
    # The demo integrates sigma_yy over the base with scikit-fem's FacetBasis;
    # the base carries the column's weight rho g H W.  Tolerance 1e-3: the base
    # particles' stresses are smoothing-cell averages (measured -6.9e-4 at 32
    # elements over the height, -2.3e-4 at 64); the nodal reactions of the cone
    # solution balance the weight to round-off.
    demo = runpy.run_path(str(DEMO))
    weight = demo["RHO"] * demo["G"] * demo["H"] * demo["W"]
    assert weight == pytest.approx(2000.0 * 9.81 * 4.0 * 1.0)
    assert demo["base_force"] == pytest.approx(weight, rel=1e-3)
    assert demo["reaction"] == pytest.approx(weight, rel=1e-9)
    # sigma_yy = -rho g (H - y) is linear: the P1 field is within 1 %.
    assert demo["l2_error"] < 1e-2


@pytest.mark.parametrize("axisymmetric", [False, True])
def test_from_mesh_is_todays_array_path_bit_for_bit(axisymmetric):
    mesh, fixed = _column()
    cells = (
        npfem.axisymmetric_integration(mesh)
        if axisymmetric
        else npfem.nodal_integration(mesh)
    )
    old = npfem.Particles.create(mesh.p.T, SOIL.rho * cells.volumes, fixed=fixed)
    new = npfem.Particles.from_mesh(mesh, SOIL, fixed=fixed, axisymmetric=axisymmetric)
    _same(old, new)
    model = npfem.Model(
        dim=2, materials=[SOIL], mode="static", axisymmetric=axisymmetric
    )
    a, step_a = npfem.advance(old, model, 1.0, npfem.FixedMesh(mesh.t))
    for source in (mesh, npfem.FixedMesh(mesh), mesh.t):
        b, step_b = npfem.advance(new, model, 1.0, source)
        _same(a, b)
        assert np.array_equal(step_a.solution.sigma, step_b.solution.sigma)


def test_from_mesh_3d_and_several_materials():
    mesh = MeshTet.init_tensor(*(np.linspace(0, 1, 3),) * 3)
    dense = npfem.LinearElastic(E=1e7, nu=0.3, rho=3000.0)
    ids = (mesh.p[2] > 0.5).astype(int)
    p = npfem.Particles.from_mesh(mesh, [SOIL, dense], material=ids)
    volumes = npfem.nodal_integration(mesh).volumes
    assert np.array_equal(p.mass, np.where(ids == 1, 3000.0, 2000.0) * volumes)
    # Masses add up to rho times the volume: 2000 * 1 + 1000 * (top slab).
    top = volumes[ids == 1].sum()
    assert p.mass.sum() == pytest.approx(2000.0 + 1000.0 * top, rel=1e-12)


def test_fields_are_the_active_particles_in_node_order():
    # A lattice plus one particle far away: the alpha shape leaves it out, so
    # the step's mesh has one node fewer than there are particles.
    g = np.linspace(0.0, 1.0, 5)
    x = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    x = np.vstack([x, [[5.0, 5.0]]])
    p = npfem.Particles.create(x, 1.0, fixed=x[:, 1:2].repeat(2, 1) == 0.0)
    model = npfem.Model(dim=2, materials=[SOIL], mode="static")
    new, step = npfem.advance(p, model, 0.01, npfem.AlphaShapeMesher(h=0.25))
    mesh, fields = step.to_skfem()
    assert mesh.nvertices == step.active.size == p.n - 1
    assert 25 not in step.active
    assert np.array_equal(mesh.p.T, new.x[step.active])
    assert np.array_equal(fields["stress_xy"], new.stress[step.active, 3])
    assert np.array_equal(fields["displacement_y"], new.u[step.active, 1])
    # The vector DOFs are in ElementVector(ElementTriP1)'s order: interpolating
    # them gives the interpolation of each component.
    vec = Basis(mesh, ElementVector(ElementTriP1())).interpolate(fields["velocity"])
    scalar = Basis(mesh, ElementTriP1())
    for k, c in enumerate("xy"):
        comp = scalar.interpolate(fields[f"velocity_{c}"])
        assert np.allclose(np.asarray(vec)[k], np.asarray(comp), rtol=0, atol=1e-14)


def test_non_simplex_meshes_and_mismatched_particles_are_refused():
    with pytest.raises(npfem.ParameterError, match=r"to_meshtri\(\)") as err:
        npfem.Particles.from_mesh(MeshQuad(), SOIL)
    assert err.value.name == "mesh" and err.value.value == "MeshQuad1"
    with pytest.raises(npfem.ParameterError, match="rho > 0"):
        npfem.Particles.from_mesh(MeshTri(), npfem.LinearElastic(E=1e7, nu=0.3))
    mesh, _ = _column()
    small = npfem.Particles.from_mesh(MeshTri(), SOIL)
    with pytest.raises(npfem.ParameterError, match="one particle per node"):
        npfem.FixedMesh(mesh)(small.x)
    with pytest.raises(npfem.ParameterError, match="mesh_source"):
        npfem.advance(small, npfem.Model(dim=2, materials=[SOIL]), 1.0, "mesh")
