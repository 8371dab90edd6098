"""One quasi-static step by hand: an elastic column under gravity
==============================================================

The smallest complete N-PFEM program: particles on the nodes of a scikit-fem
mesh, nodal smoothing cells, one quasi-static step solved as a cone program,
and the vertical stress checked against the closed form
``sigma_yy = -rho g (H - y)`` of a column between smooth walls.
"""

# %%
# Particles are the nodes of a P1 mesh. A 1 m x 4 m soil column: nine nodes
# across, 33 up. The smoothing cells give each particle its volume `V_i`, and
# the particle masses are `rho V_i`.
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from skfem import MeshTri

import skfem_npfem as npfem

OUT = Path(os.environ.get("NPFEM_GALLERY_OUT", "out/gallery")) / "one_step_by_hand"
OUT.mkdir(parents=True, exist_ok=True)

H, W = 4.0, 1.0
mesh = MeshTri.init_tensor(np.linspace(0, W, 9), np.linspace(0, H, 33))
soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=2000.0)
cells = npfem.nodal_integration(mesh)
print(f"{mesh.nvertices} particles, total volume {cells.volumes.sum():.6f} m^2")

# %%
# Boundary conditions are fixed degrees of freedom per particle: a fixed base
# and smooth side walls (horizontal displacement fixed).
x = mesh.p.T
fixed = np.zeros_like(x, dtype=bool)
fixed[x[:, 1] == 0.0] = True
fixed[(x[:, 0] == 0.0) | (x[:, 0] == W), 0] = True
particles = npfem.Particles.create(x, soil.rho * cells.volumes, fixed=fixed)

# %%
# One step: `advance` builds the cone program of the step (an elastic program
# is one linear solve), solves it with Clarabel and returns the updated
# particles. `FixedMesh` keeps the scikit-fem connectivity instead of
# remeshing.
model = npfem.Model(dim=2, materials=[soil], mode="static")
particles, step = npfem.advance(
    particles, model, dt=1.0, mesh_source=npfem.FixedMesh(mesh.t)
)
print(step.record.status, f"{step.record.iterations} interior-point iterations")

# %%
# The closed form of a column between smooth walls under its own weight.
y = x[:, 1]
exact = -soil.rho * 9.81 * (H - y)
sigma_yy_error = float(
    np.linalg.norm(particles.stress[:, 1] - exact) / np.linalg.norm(exact)
)
print(f"sigma_yy relative L2 error: {sigma_yy_error:.2e}")

fig, ax = plt.subplots(figsize=(4.5, 4))
ax.plot(-particles.stress[:, 1] / 1e3, y, ".", ms=4, label="particles")
ax.plot(
    soil.rho * 9.81 * (H - np.array([0, H])) / 1e3, [0, H], "k-", label="ρ g (H − y)"
)
ax.set(xlabel="−σ_yy (kPa)", ylabel="y (m)", title="Column under gravity")
ax.legend()
fig.tight_layout()
fig.savefig(OUT / "sigma_yy.png", dpi=100)
