"""Parameter sweeps on Dask: many runs of one scene, one table of results.

``skfem_npfem.sweep(scene, grid, out=...)`` (:func:`sweep`) and the command
``skfem-npfem sweep SCENE --grid name=v1,v2 ... --out DIR`` run every point of
a parameter grid through :func:`~skfem_npfem.run_scene`, each in its own
folder, on a local Dask cluster or an existing scheduler, and gather the
summaries into ``DIR/table.csv``.  See docs/sweep.md.

Dask and pandas come with the ``sweep`` extra
(``pip install 'skfem-npfem[sweep]'``); nothing here imports them until a
sweep starts.
"""

from __future__ import annotations

from .api import sweep
from .cluster import dask_session, solver_threads
from .engine import Outcome, gather_tasks, run_tasks
from .plan import plan_runs, run_name, value_label
from .table import read_table

__all__ = [
    "Outcome",
    "dask_session",
    "gather_tasks",
    "plan_runs",
    "read_table",
    "run_name",
    "run_tasks",
    "solver_threads",
    "sweep",
    "value_label",
]
