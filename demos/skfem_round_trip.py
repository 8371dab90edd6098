#!/usr/bin/env python
"""A scikit-fem round trip: mesh in, one step, mesh and P1 fields out
==================================================================

A soil column of width ``W`` and height ``H`` is meshed with scikit-fem,
its nodes become particles (:meth:`skfem_npfem.Particles.from_mesh`: mass
``rho V_i`` of each smoothing cell), one quasi-static step under gravity is
solved on the same mesh, and the step comes back as a scikit-fem mesh with
the particle fields as P1 degrees of freedom (:meth:`skfem_npfem.Step.to_skfem`).
scikit-fem then integrates the vertical stress over the base with a
``FacetBasis``: the base carries the whole weight, ``rho g H W``, exactly.
The nodal stresses of the base particles are averages over their smoothing
cells, so the integral misses the weight by ``6.9e-4`` at 32 elements over
the height (``2.3e-4`` at 64); the script checks it within ``TOLERANCE`` and
the nodal reactions of the cone solution within ``1e-9``.

Run it as ``python demos/skfem_round_trip.py``; it writes
``skfem_round_trip.png`` (the vertical stress on the scikit-fem mesh, and along
the centre line against ``-rho g (H - y)``) into ``out/gallery/skfem_round_trip/``
(or under ``$NPFEM_GALLERY_OUT``).
"""

# %%
# The column, meshed by scikit-fem
# --------------------------------
# Particles are the mesh's nodes; the base is fixed and the sides are smooth
# walls (rollers), so the exact stress is ``sigma_yy = -rho g (H - y)``.

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from skfem import Basis, ElementTriP1, FacetBasis, Functional, MeshTri

import skfem_npfem as npfem

#: Column width and height (m), density (kg/m^3) and gravity (m/s^2).
W, H, RHO, G = 1.0, 4.0, 2000.0, 9.81
#: Relative error allowed between the base integral of sigma_yy and the weight.
TOLERANCE = 1e-3
OUT = Path(os.environ.get("NPFEM_GALLERY_OUT", "out/gallery")) / "skfem_round_trip"

mesh = MeshTri.init_tensor(np.linspace(0, W, 9), np.linspace(0, H, 33))
soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=RHO)
x = mesh.p.T
fixed = np.zeros(x.shape, bool)
fixed[x[:, 1] == 0.0] = True  # fixed base
fixed[(x[:, 0] == 0.0) | (x[:, 0] == W), 0] = True  # smooth side walls
particles = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
print(f"{particles.n} particles, mass {particles.mass.sum():.1f} kg per m")

# %%
# One quasi-static step on the same mesh
# --------------------------------------
# The mesh is the step's mesh source (a ``FixedMesh``): no remeshing.

model = npfem.Model(dim=2, materials=[soil], gravity=G, mode="static")
particles, step = npfem.advance(particles, model, dt=1.0, mesh_source=mesh)
print(step.record.status, step.record.iterations, "iterations")

# %%
# Back to scikit-fem: the base reaction
# -------------------------------------
# ``to_skfem`` returns the mesh of the step's particles (node ``i`` is
# particle ``step.active[i]``) and the fields as P1 DOF arrays.  A
# ``FacetBasis`` on the base facets integrates ``sigma_yy`` over the base.

result_mesh, fields = step.to_skfem()
base = result_mesh.facets_satisfying(lambda p: np.isclose(p[1], 0.0))
facets = FacetBasis(result_mesh, ElementTriP1(), facets=base)
integral = Functional(lambda w: w["s"])
base_force = -float(
    integral.assemble(facets, s=facets.interpolate(fields["stress_yy"]))
)
weight = RHO * G * H * W
reaction = float(step.solution.reaction[:, 1].sum())
print(
    f"integral of -sigma_yy over the base {base_force:.2f} N/m, weight "
    f"{weight:.2f} N/m ({base_force / weight - 1:+.1e})"
)
print(f"sum of the nodal reactions {reaction:.6f} N/m ({reaction / weight - 1:+.1e})")
assert abs(base_force / weight - 1) < TOLERANCE
assert abs(reaction / weight - 1) < 1e-9

# %%
# The field inside: scikit-fem's L2 error of the P1 stress
# --------------------------------------------------------

basis = Basis(result_mesh, ElementTriP1())
exact = Functional(lambda w: (w["s"] + RHO * G * (H - w.x[1])) ** 2)
norm = Functional(lambda w: (RHO * G * (H - w.x[1])) ** 2)
s = basis.interpolate(fields["stress_yy"])
l2_error = float(np.sqrt(exact.assemble(basis, s=s) / norm.assemble(basis)))
print(f"relative L2 error of sigma_yy: {l2_error:.2%}")

# %%
# The figure
# ----------


def figure(out: Path) -> Path:
    """Draw sigma_yy on the mesh and along the centre line into ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from skfem.visuals.matplotlib import plot

    fig, (left, right) = plt.subplots(
        1, 2, figsize=(9, 5), width_ratios=(1, 2), layout="constrained"
    )
    plot(
        result_mesh,
        fields["stress_yy"] / 1e3,
        ax=left,
        shading="gouraud",
        colorbar=r"$\sigma_{yy}$ (kPa)",
    )
    left.set(aspect="equal", xlabel="x (m)", ylabel="y (m)")
    centre = np.isclose(result_mesh.p[0], W / 2)
    y = result_mesh.p[1, centre]
    right.plot(-RHO * G * (H - y) / 1e3, y, "k-", label=r"$-\rho g (H - y)$")
    right.plot(fields["stress_yy"][centre] / 1e3, y, "o", ms=4, label="particles")
    right.set(
        xlabel=r"$\sigma_{yy}$ (kPa)",
        ylabel="y (m)",
        title=f"base force / weight - 1 = {base_force / weight - 1:+.1e}",
    )
    right.legend()
    out.mkdir(parents=True, exist_ok=True)
    path = out / "skfem_round_trip.png"
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


print("wrote", figure(OUT))
