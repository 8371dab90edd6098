"""Your own scene: an embankment built from a scikit-fem mesh
==========================================================

A scene is geometry, material, walls and a time loop.  Here the geometry is a
scikit-fem quadrilateral mesh split into triangles and mapped onto a
trapezoidal embankment; the soil is Mohr-Coulomb; it stands on a rough floor;
and a loop of ``npfem.advance`` calls remeshes the particles every step and
lets the embankment settle under its own weight.  Once it is at rest the floor
pushes back with the embankment's weight, which we check.
"""

# %%
# Geometry: a 12 x 4 quadrilateral mesh of the unit square, split into
# triangles and mapped onto a 3 m wide, 0.6 m high embankment with a 1 m
# crest. The particles are its nodes.
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from skfem import MeshQuad, MeshTri

import skfem_npfem as npfem

OUT = Path(os.environ.get("NPFEM_GALLERY_OUT", "out/gallery")) / "own_scene"
OUT.mkdir(parents=True, exist_ok=True)

base, crest, height = 3.0, 1.0, 0.6
mesh = MeshQuad.init_tensor(np.linspace(0, 1, 13), np.linspace(0, 1, 5)).to_meshtri()
s, t = mesh.p
half = 0.5 * (base - (base - crest) * t)  # half-width at height t
x = np.column_stack([(2 * s - 1) * half, height * t])
h = height / 4  # particle spacing, for the remesher's alpha shape

# %%
# Material, wall and model, and the particles with masses `rho V_i` from the
# smoothing cells of the mapped mesh: a cohesive-frictional soil (cohesion keeps the
# 45 degree slopes standing) on a floor with a wall friction angle of 25 deg.
# `Model` defaults to dynamic steps (backward Euler) under gravity 9.81.
soil = npfem.MohrCoulomb(E=2e7, nu=0.3, rho=1900.0, c=4e3, phi=30.0, psi=0.0)
ground = npfem.floor(dim=2, friction_angle=25.0)
model = npfem.Model(dim=2, materials=[soil], walls=[ground])
mesher = npfem.AlphaShapeMesher(h=h, alpha=1.3, walls=[ground])
cells = npfem.nodal_integration(MeshTri(x.T, mesh.t))  # on the mapped mesh
particles = npfem.Particles.create(x, soil.rho * cells.volumes, n_walls=1)

# %%
# The time loop: `advance` remeshes the particles (`mesher`), solves the step's
# cone program and returns the new particles and the step's result.
dt, kinetic = 0.01, []
for _ in range(40):
    particles, step = npfem.advance(particles, model, dt, mesher)
    kinetic.append(0.5 * (particles.mass * (particles.v**2).sum(axis=1)).sum())
print(f"{len(kinetic)} steps, last status {step.record.status}")

# %%
# At rest the floor's normal forces (one column per wall in
# `particles.wall_force`) add up to the weight per metre of embankment.
weight = particles.mass.sum() * model.gravity
floor_force = float(particles.wall_force[:, 0].sum())
weight_error = abs(floor_force / weight - 1)
print(
    f"floor force {floor_force:.1f} N/m, weight {weight:.1f} N/m ({weight_error:.1e})"
)

fig, (ax, bx) = plt.subplots(2, 1, figsize=(6, 4.5), layout="constrained")
p = particles
sc = ax.tripcolor(*p.x.T, step.cells, -p.stress[:, 1] / 1e3, shading="gouraud")
outline = [(-base / 2, 0), (-crest / 2, height), (crest / 2, height), (base / 2, 0)]
ax.plot(*np.transpose(outline), "k--", lw=0.8, label="t = 0")
fig.colorbar(sc, ax=ax, label="−σ_yy (kPa)", orientation="horizontal", shrink=0.6)
ax.set(aspect="equal", xlabel="x (m)", ylabel="y (m)", title="embankment at rest")
bx.semilogy(dt * np.arange(1, len(kinetic) + 1), kinetic)
bx.set(xlabel="t (s)", ylabel="kinetic energy (J/m)")
fig.savefig(OUT / "embankment.png", dpi=100)
