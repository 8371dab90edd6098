"""An axisymmetric column: the base carries the weight of the cylinder
===================================================================

A solid elastic cylinder (radius R, height H) stands on a smooth floor.  With
``Model(axisymmetric=True)`` the mesh is the (r, z) half-section and every
particle stands for a ring: cells are weighted by 2 pi r and the stress has a
hoop component.  Equilibrium fixes the sum of the floor's reactions to the
weight of the whole cylinder, rho g pi R^2 H, whatever the mesh; away from the
floor the axial stress is the free column's sigma_zz = -rho g (H - z).
"""

# %%
# The half-section is a scikit-fem mesh of [0, R] x [0, H]; x is the radius r
# and y the height z.  Ring particles carry the mass of their whole ring,
# `rho V_i` with `V_i` the integral of `2 pi r` times the hat function of node
# `i` (a scikit-fem linear form).
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from skfem import Basis, ElementTriP1, LinearForm, MeshTri

import skfem_npfem as npfem

OUT = Path(os.environ.get("NPFEM_GALLERY_OUT", "out/gallery")) / "axisymmetric_column"
OUT.mkdir(parents=True, exist_ok=True)

R, H, rho, g = 0.5, 2.0, 2000.0, 9.81
mesh = MeshTri.init_tensor(np.linspace(0, R, 9), np.linspace(0, H, 33))
ring = LinearForm(lambda v, w: 2 * np.pi * w.x[0] * v)
volumes = ring.assemble(Basis(mesh, ElementTriP1()))
print(f"ring volumes sum to {volumes.sum():.6f} m^3; pi R^2 H = {np.pi * R**2 * H:.6f}")

# %%
# A roller floor (vertical displacement fixed at z = 0) and the axis (radial
# displacement fixed at r = 0); the lateral surface is free.
x = mesh.p.T
fixed = np.zeros_like(x, dtype=bool)
fixed[x[:, 1] == 0.0, 1] = True
fixed[x[:, 0] == 0.0, 0] = True
soil = npfem.LinearElastic(E=5e7, nu=0.25, rho=rho)
particles = npfem.Particles.create(x, rho * volumes, fixed=fixed)
model = npfem.Model(dim=2, materials=[soil], mode="static", axisymmetric=True)
particles, step = npfem.advance(particles, model, 1.0, npfem.FixedMesh(mesh.t))
print(step.record.status)

# %%
# The reactions of the fixed degrees of freedom are in the step's solution
# (one row per particle of the step's mesh). Their vertical sum on the floor
# is the cylinder's weight.
floor = x[step.active, 1] == 0.0
base_force = float(step.solution.reaction[floor, 1].sum())
weight = rho * g * np.pi * R**2 * H
reaction_error = abs(base_force / weight - 1)
print(
    f"floor reaction {base_force:.2f} N, weight {weight:.2f} N ({reaction_error:.1e})"
)

# %%
# The axial stress against the free column's -rho g (H - z): exact away from the
# floor, where the roller base disturbs it. Stresses are (rr, zz, tt, rz).
z = x[:, 1]
above = z > 0.25 * H
sigma_zz_error = np.linalg.norm(
    particles.stress[above, 1] + rho * g * (H - z[above])
) / np.linalg.norm(rho * g * (H - z[above]))
print(f"sigma_zz relative L2 error above z = H/4: {sigma_zz_error:.1e}")
fig, ax = plt.subplots(figsize=(4.5, 4))
ax.plot(-particles.stress[:, 1] / 1e3, z, ".", ms=3, label="σ_zz")
ax.plot(-particles.stress[:, 2] / 1e3, z, "x", ms=3, label="σ_θθ (hoop)")
ax.plot([rho * g * H / 1e3, 0], [0, H], "k-", label="ρ g (H − z)")
ax.set(xlabel="compression (kPa)", ylabel="z (m)", title="Standing cylinder")
ax.legend()
fig.tight_layout()
fig.savefig(OUT / "axial_stress.png", dpi=100)
