"""A parameter sweep on Dask: the footing's collapse load against the spacing
==========================================================================

``npfem.sweep`` runs one scene over a grid of parameters on a local Dask
cluster (or an existing scheduler), each run in its own folder, and returns
the table of results as a pandas DataFrame (also ``table.csv``).  Here three
particle spacings of the strip footing show its bearing factor q/c converging
to Prandtl's 2 + pi.  Needs the ``sweep`` extra (``pip install
'skfem-npfem[sweep]'``).
"""

# %%
# Dask starts worker processes that import this script afresh: the sweep must
# sit under `if __name__ == "__main__":` (so must anything that should run only
# once). A rerun skips the runs whose summaries are already in `OUT/runs`.
import math
import os
from pathlib import Path

import matplotlib.pyplot as plt

import skfem_npfem as npfem

OUT = Path(os.environ.get("NPFEM_GALLERY_OUT", "out/gallery")) / "parameter_sweep"

if __name__ == "__main__":
    table = npfem.sweep(
        "strip-footing",
        {"spacing": [0.5, 0.25, 0.125]},
        fixed={"material": "tresca", "interface": "smooth"},
        out=OUT,
        workers=2,
        progress=False,
    )
    print(table[["run", "status", "n_particles", "bearing_factor", "wall_time_total"]])
    finest_error = abs(table["bearing_factor"].iloc[-1] / (2 + math.pi) - 1)
    print(f"finest spacing: q/c off 2 + pi by {finest_error:.2%}")

# %%
# The table has one row per run: the parameters, the scene's metrics and the
# solver's statistics. The error against 2 + pi falls about as h^2 with the
# spacing h.
if __name__ == "__main__":
    error = table["bearing_factor"] / (2 + math.pi) - 1
    fig, ax = plt.subplots(figsize=(4.5, 3.5))
    ax.loglog(table["spacing"], error, "o-", label="N-PFEM")
    h = table["spacing"]
    ax.loglog(h, error.iloc[-1] * (h / h.iloc[-1]) ** 2, "k:", label="slope 2")
    ax.set(xlabel="spacing h (m)", ylabel="q / c / (2 + π) − 1")
    ax.legend()
    fig.tight_layout()
    fig.savefig(OUT / "convergence.png", dpi=100)
