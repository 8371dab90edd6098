"""Water in the soil: pore pressure, effective stress and drainage.

A soil with water carries a pore pressure ``p`` (compression positive, Pa) at
every particle beside its stress.  The particles' ``stress`` is the
*effective* stress ``sigma'``, on which the yield cones act; the total stress
is ``sigma = sigma' - p I`` (tension positive), and equilibrium is written in
the total stress (docs/theory.md, "Water: effective stress").

* :mod:`.table` -- the water table (a level, or a polyline in a section) and
  the hydrostatic pressure below it;
* :mod:`.seepage` -- steady seepage: Darcy's problem on the step's mesh with
  heads fixed on water boundaries, its pore pressure and flow rates;
* :mod:`.model` -- :class:`Water`, what a :class:`~skfem_npfem.Model` is told
  about the water: the drainage mode, the table, the water's density;
* :mod:`.forces` -- what the water does in a step: the nodal force of a
  prescribed pore-pressure field (buoyancy and seepage forces, the pressure
  of free water on the surface), the volumetric coupling of the excess pore
  pressure, and its pressure-projection stabilisation.
"""

from __future__ import annotations

from .forces import (
    coupling_matrix,
    darcy_matrix,
    drained_nodes,
    projection_matrix,
    surface_force,
    water_force,
)
from .model import DRAINAGE, Water
from .seepage import HeadBoundary, Seepage, SeepageField, solve_heads
from .table import WaterTable

__all__ = [
    "DRAINAGE",
    "HeadBoundary",
    "Seepage",
    "SeepageField",
    "Water",
    "WaterTable",
    "coupling_matrix",
    "darcy_matrix",
    "drained_nodes",
    "projection_matrix",
    "solve_heads",
    "surface_force",
    "water_force",
]
