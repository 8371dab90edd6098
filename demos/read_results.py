"""Read a result folder: the VTU/PVD series with meshio and pyvista, and the JSON
==============================================================================

``skfem-npfem run SCENE --out DIR`` (or ``npfem.run_scene(..., out=DIR)``)
writes one VTU file per output step, ``result.pvd`` listing them with their
times, and ``summary.json``.  Any VTK reader opens them; here meshio and
pyvista read the particles of a short column collapse (matplotlib draws the
last step), and the total mass in the last file is checked against the
column's rho L0 H0 (particles carry fixed masses, so it is conserved exactly).
"""

# %%
# A short run (0.25 s of a coarse collapse) into a folder; a VTU every second
# step.
import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib.pyplot as plt
import meshio
import numpy as np
import pyvista as pv

import skfem_npfem as npfem

OUT = Path(os.environ.get("NPFEM_GALLERY_OUT", "out/gallery")) / "read_results"
run = OUT / "run"
npfem.run_scene(
    "column-collapse",
    {"spacing": 0.02, "dt": 0.01, "t_end": 0.25, "output_every": 2},
    out=run,
    summary=run / "summary.json",
)
suffixes = [p.suffix for p in run.iterdir()]
print({s: suffixes.count(s) for s in sorted(set(suffixes))})

# %%
# `result.pvd` is a short XML file: one `DataSet` per output step, with its
# time and VTU file. meshio reads a VTU as a mesh of triangles with point data
# (displacement, velocity, stress in Voigt order xx, yy, zz, xy, plastic
# strain, mass, active).
steps = [
    (float(d.get("timestep")), run / d.get("file"))
    for d in ET.parse(run / "result.pvd").getroot().iter("DataSet")
]
time, last = steps[-1]
mesh = meshio.read(last)
print(f"{len(steps)} steps, last at t = {time:.2f} s: {last.name}")
print({name: a.shape for name, a in mesh.point_data.items()})

# %%
# Mass is carried by the particles: the last file's total is the column's.
summary = json.loads((run / "summary.json").read_text())
par = summary["parameters"]
column_mass = par["rho"] * par["half_width"] * par["half_width"] * par["aspect"]
total_mass = float(mesh.point_data["mass"].sum())
mass_error = abs(total_mass / column_mass - 1)
print(f"mass {total_mass:.4f} kg/m, rho L0 H0 = {column_mass:.4f} ({mass_error:.1e})")
print(
    f"summary: {summary['solver']['steps']} steps, run-out history ends at "
    f"{summary['history'][-1]['runout']:.3f} m"
)

# %%
# pyvista reads the whole series through the PVD (one time per step); its grid
# holds the triangles and the point data. matplotlib draws the last step (no
# display or X server needed, with axes in metres and a colour bar that starts
# at zero: the free surface carries no stress).
reader = pv.get_reader(str(run / "result.pvd"))
reader.set_active_time_value(reader.time_values[-1])
grid = reader.read()[0]
triangles = grid.cells_dict[pv.CellType.TRIANGLE]
sigma_v = -grid["stress"][:, 1] / 1e3  # -stress_yy, kPa
fig, ax = plt.subplots(figsize=(6.4, 3.4))
art = ax.tripcolor(
    grid.points[:, 0],
    grid.points[:, 1],
    triangles,
    sigma_v,
    vmin=0.0,
    shading="gouraud",
)
ax.triplot(grid.points[:, 0], grid.points[:, 1], triangles, lw=0.3, c="k")
ax.set_aspect("equal")
ax.set(xlabel="x (m)", ylabel="y (m)", title=f"last step, t = {time:.2f} s")
fig.colorbar(art, ax=ax, label="vertical stress -$\\sigma_{yy}$ (kPa)", shrink=0.8)
fig.tight_layout()
fig.savefig(OUT / "last_step.png", dpi=100)
print(
    f"pyvista: {grid.n_points} points, {grid.n_cells} cells, "
    f"times {np.round(reader.time_values, 2).tolist()}"
)
