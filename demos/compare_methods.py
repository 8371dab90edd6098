"""N-PFEM beside FEM with remapping: P1 elements lock under an undrained footing
=============================================================================

A Tresca soil deforms plastically at constant volume.  Linear triangles with
Gauss-point stresses (FEM P1) cannot represent such a flow on a general mesh:
they lock, and the footing's load keeps rising to about three times
Prandtl's 2 + pi.  N-PFEM uses the same P1 mesh but smooths strains over nodal cells and
does not lock.  (Quadratic triangles, ``element="p2"``, do not lock either,
at several times the cost.)  The method of a scene is one parameter,
``method``.
"""

# %%
# The same scene twice: N-PFEM, then `method="fem-remap"` with P1 elements.
# The P1 run never reaches a plateau: it stops at its settlement cap with a
# warning, its load still rising.
import math
import os
import time
import warnings
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import skfem_npfem as npfem

OUT = Path(os.environ.get("NPFEM_GALLERY_OUT", "out/gallery")) / "compare_methods"
OUT.mkdir(parents=True, exist_ok=True)

methods = {
    "N-PFEM": {"method": "npfem"},
    "FEM P1": {"method": "fem-remap", "element": "p1"},
}
results = {}
for label, params in methods.items():
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # P1: "no load plateau"
        summary = npfem.run_scene("strip-footing", {"material": "tresca", **params})
    results[label] = summary
    m = summary["metrics"]
    print(
        f"{label:7s} q/c = {m['bearing_factor']:6.3f} "
        f"({m['bearing_factor'] / (2 + math.pi) - 1:+7.1%} vs 2 + pi), "
        f"stopped by {m['stopped_by']}, {time.perf_counter() - start:.1f} s"
    )

npfem_error = abs(results["N-PFEM"]["metrics"]["bearing_factor"] / (2 + math.pi) - 1)
p1_overshoot = results["FEM P1"]["metrics"]["bearing_factor"] / (2 + math.pi)

# %%
# The load-settlement curves: N-PFEM levels off at 2 + pi, P1 keeps climbing.
fig, ax = plt.subplots(figsize=(5, 3.5))
for label, summary in results.items():
    curve = np.vstack([[0.0, 0.0], summary["metrics"]["load_curve"]])
    b, c = summary["parameters"]["width"] / 2, summary["parameters"]["c"]
    ax.plot(curve[:, 0] / b, curve[:, 1] / c, ".-", label=label)
ax.axhline(2 + math.pi, c="k", ls="--", label="Prandtl 2 + π")
ax.set(xlabel="settlement / b", ylabel="q / c")
ax.set_xscale("symlog", linthresh=1e-2)
ax.set_xlim(0, 1.2)
ax.legend()
fig.tight_layout()
fig.savefig(OUT / "load_curves.png", dpi=100)
