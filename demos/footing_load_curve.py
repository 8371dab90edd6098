"""The strip footing's load-settlement curve against Prandtl's 2 + pi
==================================================================

A rigid, smooth strip footing of half-width b is pushed into a weightless
Tresca soil of cohesion c.  Each step is a cone program; the footing pressure
rises elastically, bends as the plastic zone spreads, and levels off at the
collapse load.  For this problem Prandtl (1920) gives the exact collapse
pressure q = (2 + pi) c.
"""

# %%
# The `strip-footing` scene pushes the footing down in prescribed settlement
# steps (here 20 equal ones up to 0.01 m) and stops when the load changes by
# less than 0.1 % while the settlement doubles (a plateau).  The summary's
# `load_curve` holds one (settlement, pressure) pair per step.
import math
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import skfem_npfem as npfem

OUT = Path(os.environ.get("NPFEM_GALLERY_OUT", "out/gallery")) / "footing_load_curve"
OUT.mkdir(parents=True, exist_ok=True)

summary = npfem.run_scene(
    "strip-footing",
    {"material": "tresca", "interface": "smooth", "c": 10e3, "steps": 20},
)
m = summary["metrics"]
bearing_factor = m["bearing_factor"]
print(f"{m['n_particles']} particles, stopped by {m['stopped_by']}")
print(
    f"q/c = {bearing_factor:.4f}; Prandtl 2 + pi = {2 + math.pi:.4f} "
    f"({bearing_factor / (2 + math.pi) - 1:+.2%})"
)

# %%
# The curve, in the dimensionless form q/c against settlement / b, from the
# unloaded start.
c = summary["parameters"]["c"]
b = summary["parameters"]["width"] / 2
curve = np.vstack([[0.0, 0.0], m["load_curve"]])
fig, ax = plt.subplots(figsize=(5, 3.5))
ax.plot(curve[:, 0] / b, curve[:, 1] / c, "o-", ms=4, label="N-PFEM")
ax.axhline(2 + math.pi, c="k", ls="--", label="Prandtl 2 + π")
ax.set(xlabel="settlement / b", ylabel="q / c", ylim=(0, 6))
ax.legend(loc="lower right")
fig.tight_layout()
fig.savefig(OUT / "load_curve.png", dpi=100)
