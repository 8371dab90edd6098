"""Read a result folder: the VTU/PVD series with meshio and pyvista, and the JSON
==============================================================================

``skfem-npfem run SCENE --out DIR`` (or ``npfem.run_scene(..., out=DIR)``)
writes one VTU file per output step, ``result.pvd`` listing them with their
times, and ``summary.json``.  Any VTK reader opens them; here meshio and
pyvista read the particles of a short column collapse, and the total mass in
the last file is checked against the column's rho L0 H0 (particles carry
fixed masses, so it is conserved exactly).
"""

# %%
# A short run (0.25 s of a coarse collapse) into a folder; a VTU every second
# step.
import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path

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
# pyvista reads the whole series through the PVD (one time per step) and
# renders off-screen.
reader = pv.get_reader(str(run / "result.pvd"))
reader.set_active_time_value(reader.time_values[-1])
grid = reader.read()[0]
grid["-stress_yy (kPa)"] = -grid["stress"][:, 1] / 1e3
plotter = pv.Plotter(off_screen=True, window_size=(640, 420))
plotter.add_mesh(grid, scalars="-stress_yy (kPa)", show_edges=True)
plotter.view_xy()
plotter.screenshot(OUT / "last_step.png")
print(
    f"pyvista: {grid.n_points} points, {grid.n_cells} cells, "
    f"times {np.round(reader.time_values, 2).tolist()}"
)
