"""SPFEM verified on its own (elastic column, simple shear; explicit stability).

* The stable-step estimate (smallest smoothing-cell size / P-wave speed) is
  below the exact central-difference limit ``2 / omega_max`` of the nodally
  integrated stiffness (largest eigenvalue by ARPACK) on lattice, jittered,
  random and alpha-shape meshes in 2D and 3D.
* The elastic column under gravity, released from rest with
  mass-proportional damping ``alpha = 2 omega_1`` (first oedometric mode
  critically damped), settles to the static solution: sigma_yy and sigma_xx
  within 1 % (rel. L2), settlement within 0.5 %, and the state equals the
  library's static N-PFEM step on the same mesh (same discretisation) to 1e-4.
* Simple shear of a Tresca patch: tau reaches c and stays there.
* A time step above the stable one is refused before any step.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh
from scipy.spatial import Delaunay
from skfem import MeshTet, MeshTri

from skfem_npfem.baseline import SPFEM, stable_time_step
from skfem_npfem.errors import ParameterError
from skfem_npfem.materials import LinearElastic, Tresca, compliance_matrix
from skfem_npfem.mesh.delaunay import alpha_shape
from skfem_npfem.mesh.smoothing import nodal_integration
from skfem_npfem.mesh.sources import FixedMesh
from skfem_npfem.particles import Particles
from skfem_npfem.run.simulation import Simulation
from skfem_npfem.scenes import get_scene
from skfem_npfem.step.model import Model
from skfem_npfem.step.stages import advance

E, NU, RHO, G = 1.0e7, 0.3, 2000.0, 9.81


def meshes():
    rng = np.random.default_rng(0)
    out = {
        "tri-lattice": MeshTri.init_tensor(np.linspace(0, 1, 9), np.linspace(0, 4, 33))
    }
    m = MeshTri.init_tensor(np.linspace(0, 1, 11), np.linspace(0, 1, 11))
    p = m.p.copy()
    inner = np.setdiff1d(np.arange(p.shape[1]), m.boundary_nodes())
    p[:, inner] += 0.03 * rng.uniform(-1, 1, (2, inner.size))
    out["tri-jittered"] = MeshTri(p, m.t)
    x = rng.uniform(0, 1, (300, 2))
    t = Delaunay(x).simplices
    J = np.stack([x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]], axis=2)
    keep = np.abs(np.linalg.det(J)) > 2e-5
    out["tri-random"] = MeshTri(x.T.copy(), t[keep].T.copy())
    g = np.linspace(0, 1, 11)
    lat = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    out["tri-alpha"] = alpha_shape(lat, 0.1, 1.3, seed=3).mesh()
    out["tet-lattice"] = MeshTet.init_tensor(*[np.linspace(0, 1, 6)] * 3)
    out["tet-alpha"] = alpha_shape(
        rng.uniform(0, 1, (300, 3)), h=300 ** (-1 / 3), alpha=1.6
    ).mesh()
    return out


MESHES = meshes()


@pytest.mark.parametrize("name", list(MESHES))
def test_stable_step_is_below_the_exact_limit(name):
    mesh = MESHES[name]
    d = mesh.dim()
    ni = nodal_integration(mesh)
    D = np.linalg.inv(compliance_matrix(E, NU, d, ni.components))
    K = ni.G @ sp.block_diag([D / V for V in ni.volumes]) @ ni.G.T
    m = np.repeat(RHO * ni.volumes, d)
    S = sp.diags(1 / np.sqrt(m))
    lam = eigsh(S @ K @ S, k=1, which="LA", return_eigenvectors=False)[0]
    model = Model(dim=d, materials=[LinearElastic(E, NU, RHO)])
    est = stable_time_step(ni, model, RHO * ni.volumes, np.zeros(ni.n_nodes, int))
    exact = 2 / math.sqrt(lam)
    # Measured exact / estimate: 1.29 (tet-alpha) to 2.56 (tri-alpha).
    assert est < exact
    assert est > 0.2 * exact  # and not uselessly small


def column(height=4.0, spacing=0.125):
    scene = get_scene("elastic-column")
    values = scene.resolve({"height": height, "spacing": spacing, "mode": "dynamic"})
    sim = scene.build(values).simulation
    return sim.particles, sim.model, sim.mesh_source


def run(method: SPFEM, p, model, mesh_source, dt: float, t_end: float):
    """Steps of ``dt`` to ``t_end`` through the time loop; (particles, substeps)."""
    sim = Simulation(p, model, mesh_source, dt, stepper=method.advance)
    sim.run(t_end=t_end)
    return sim.particles, sum(r.extra["substeps"] for r in sim.records)


def test_elastic_column_settles_to_the_static_solution():
    p, model, ms = column()
    H = 4.0
    M = model.materials[0].p_wave_modulus
    omega1 = 2 * math.pi / (4 * H / math.sqrt(M / RHO))
    method = SPFEM(damping=2 * omega1)
    end, substeps = run(method, p, model, ms, 0.01, 0.6)
    # 0.6 s = 3 first-mode periods: 60 steps of 10 ms in 1080 substeps of
    # 0.56 ms (N-PFEM: 1 static step, or ~20 implicit steps of omega dt ~ 1).
    assert 1000 < substeps < 1200
    sv = -RHO * G * (H - p.x[:, 1])
    rel = np.linalg.norm
    assert rel(end.stress[:, 1] - sv) / rel(sv) < 0.01  # measured 3.4e-3
    assert rel(end.stress[:, 0] - NU / (1 - NU) * sv) / rel(sv) < 0.01  # 8.4e-4
    top = np.isclose(p.x[:, 1], H)
    us = RHO * G * H**2 / (2 * M)
    assert abs(-end.u[top, 1].mean() / us - 1) < 0.005  # measured -1.9e-3
    # Same discretisation as the library's static N-PFEM step on this mesh.
    static = Model(dim=2, materials=model.materials, gravity=G, mode="static")
    ref, _ = advance(p, static, 1.0, ms)
    assert rel(end.stress - ref.stress) / rel(ref.stress) < 1e-4
    assert np.max(np.abs(end.v)) < 1e-6 * G * 0.6


def test_tresca_simple_shear_saturates_at_c():
    c = 1.0e4
    m = MeshTri.init_tensor(np.linspace(0, 1, 6), np.linspace(0, 1, 6))
    ni = nodal_integration(m)
    x = m.p.T.copy()
    fixed = np.zeros_like(x, bool)
    fixed[m.boundary_nodes()] = True
    gamma_y = c / (E / (2 * (1 + NU)))
    rate = 5 * gamma_y / 0.5  # 5 gamma_y over 0.5 s (quasi-static)
    p = Particles.create(x, RHO * ni.volumes, fixed=fixed)
    vp = np.zeros_like(x)
    vp[:, 0] = rate * x[:, 1]
    p = p.replace(v_prescribed=vp, v=vp * fixed)
    model = Model(dim=2, materials=[Tresca(E, NU, RHO, c=c)], gravity=0.0)
    ms = FixedMesh(m.t)
    method = SPFEM(damping=200.0)
    end, _ = run(method, p, model, ms, 0.01, 0.5)
    s = end.stress
    R = np.hypot(0.5 * (s[:, 0] - s[:, 1]), s[:, 3])
    assert np.allclose(R, c, rtol=1e-9)  # on the yield surface
    assert np.allclose(s[:, 3], c, rtol=2e-3)  # and nearly pure shear (9e-4)
    # Plastic shear ~ imposed - elastic (4 gamma_y), reported as eps_p_eq =
    # gamma_p / sqrt(3) in plane strain; 5 % (explicit transients).
    assert abs(np.mean(end.eps_p) * math.sqrt(3) / (4 * gamma_y) - 1) < 0.05


def test_time_step_above_the_stable_one_is_refused_before_any_step():
    p, model, ms = column(spacing=0.25)
    stable = SPFEM().stable_dt(p, model, ms)
    assert SPFEM(explicit_dt=stable).check(p, model, ms) == stable
    with pytest.raises(ParameterError, match="stable explicit step"):
        SPFEM(explicit_dt=1.01 * stable).check(p, model, ms)
    # Mid-run (cells shrink) a step stops once it exceeds the margin.
    with pytest.raises(ParameterError, match="stable explicit step"):
        SPFEM(explicit_dt=1.3 * stable).advance(p, model, 0.01, ms, step=7)
    static = Model(dim=2, materials=model.materials, mode="static")
    with pytest.raises(ParameterError, match="SPFEM is explicit"):
        SPFEM().check(p, static, ms)
    with pytest.raises(ParameterError, match="damping"):
        SPFEM(damping=-1.0)
    with pytest.raises(ParameterError, match="explicit_dt"):
        SPFEM(explicit_dt=0.0)
