"""A granular column collapse in ten seconds
=========================================

A half column of dry sand (Mohr-Coulomb, phi = 30 deg, no cohesion) of aspect
ratio a = H0/L0 = 2 is released against a smooth symmetry wall on a rough
floor, and spreads into a deposit.  Every step remeshes the particles
(Delaunay + alpha shape) and solves one cone program with inertia.  The run is
coarse (10 particles across L0) so it finishes in seconds; the run-out is
checked against the experimental band (L_inf - L0)/L0 = 1.2 a to 1.8 a
(Lube et al. 2005; Lajeunesse et al. 2005).
"""

# %%
# `run_scene` runs a ready scene with the parameters of `skfem-npfem run
# column-collapse --set name=value` and returns the JSON summary as a dict.
# With `out=` it also writes the VTU series, `result.pvd` and the summary.
import os
from pathlib import Path

import matplotlib.pyplot as plt

import skfem_npfem as npfem
from skfem_npfem.viz.plot import plot_results

OUT = Path(os.environ.get("NPFEM_GALLERY_OUT", "out/gallery")) / "column_collapse"

summary = npfem.run_scene(
    "column-collapse",
    {"aspect": 2.0, "spacing": 0.02, "dt": 0.01},
    out=OUT / "run",
    progress=False,
)
m = summary["metrics"]
a = summary["parameters"]["aspect"]
normalised_runout = m["normalised_runout"]
print(f"{m['n_particles']} particles, {summary['solver']['steps']} steps")
print(f"(L_inf - L0)/L0 = {normalised_runout:.2f}; experiments {1.2 * a}..{1.8 * a}")
print(f"H_inf/L0 = {m['final_height']:.2f}, at rest: {m['at_rest']}")

# %%
# Every step's record is in `summary["history"]`: the front spreads and stops.
t = [r["time"] for r in summary["history"]]
front = [r["runout"] for r in summary["history"]]
fig, ax = plt.subplots(figsize=(5, 3.2))
ax.plot(t, front)
ax.axhline(summary["parameters"]["half_width"] * (1 + 1.2 * a), ls=":", c="k")
ax.axhline(summary["parameters"]["half_width"] * (1 + 1.8 * a), ls=":", c="k")
ax.set(xlabel="t (s)", ylabel="run-out (m)", title="front against the band")
fig.tight_layout()
fig.savefig(OUT / "runout.png", dpi=100)

# %%
# The pictures of `skfem-npfem plot OUT/run`: the particles' mesh coloured by a
# field at chosen times (in units of sqrt(H0/g)), with the floor, the wall, the
# initial outline and Lube's run-out.
pictures = plot_results(
    OUT / "run",
    times=[0, 1.5, 4],
    field="plastic_strain_eq",
    animation="none",
    out_dir=OUT,
)
print([p.name for p in pictures])
