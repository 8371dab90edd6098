"""The sweep table: one row per run, gathered from the run summaries.

Columns, in this order:

* ``run`` (folder name under ``OUT/runs``), ``status`` (``ok`` or ``failed``),
  ``error`` (``"ErrorType: message"``, empty when ok), ``resumed`` (the run
  continued from a checkpoint in this invocation);
* every scene parameter, the varied ones first (their values as the run used
  them; failed runs: the values they were given);
* the scene's scalar summary metrics under their own names (list-valued
  metrics are left out: they stay in ``summary.json``);
* ``wall_time_total`` and the solver statistics as ``solver.NAME`` (nested
  ones as ``solver.wall_time.PHASE``; lists of names joined with ``+``).
"""

from __future__ import annotations

import importlib.util
import json
import math
import numbers
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ..errors import ParameterError
from ..io import atomic_path

__all__ = ["TABLE_CSV", "TABLE_PARQUET", "flatten", "read_table", "write_table"]

TABLE_CSV = "table.csv"
TABLE_PARQUET = "table.parquet"


def flatten(obj: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Scalars of a nested dict as ``{"a.b": value}``.

    Numbers, strings and booleans are kept, None (JSON's null, NaN in the
    summaries) becomes NaN; lists of strings are joined with ``+``; other lists
    are left out.

    Examples
    --------
    >>> flatten({"steps": 3, "wall_time": {"solve": 0.5}, "statuses": ["Solved"]})
    {'steps': 3, 'wall_time.solve': 0.5, 'statuses': 'Solved'}
    """
    out: dict[str, Any] = {}
    for key, val in obj.items():
        name = f"{prefix}{key}"
        if isinstance(val, Mapping):
            out.update(flatten(val, f"{name}."))
        elif isinstance(val, list | tuple):
            if all(isinstance(v, str) for v in val):
                out[name] = "+".join(val)
        elif val is None:
            out[name] = math.nan
        elif isinstance(val, str | bool | numbers.Number):
            out[name] = val.item() if hasattr(val, "item") else val
    return out


def summary_row(summary: Mapping[str, Any]) -> dict[str, Any]:
    """Parameters, scalar metrics, total wall time and solver statistics of a run."""
    row = dict(flatten(summary.get("parameters", {})))
    metrics = flatten(summary.get("metrics", {}))
    row.update({k if k not in row else f"metric.{k}": v for k, v in metrics.items()})
    row["wall_time_total"] = summary.get("wall_time_total", math.nan)
    row.update(flatten(summary.get("solver", {}), "solver."))
    return row


def build_rows(
    order: Sequence[str],
    varied: Sequence[str],
    records: Mapping[str, Mapping[str, Any]],
) -> list[dict[str, Any]]:
    """Table rows in ``order`` from per-run records.

    Each record holds ``status``, ``error``, ``resumed`` and either ``summary``
    (a finished run) or ``values`` (the parameters a failed run was given).
    """
    rows = []
    for name in order:
        rec = records[name]
        body = (
            summary_row(rec["summary"])
            if rec.get("summary") is not None
            else flatten(rec.get("values", {}))
        )
        head = {
            "run": name,
            "status": rec["status"],
            "error": rec.get("error", ""),
            "resumed": bool(rec.get("resumed", False)),
        }
        first = {k: body.pop(k) for k in varied if k in body}
        rows.append({**head, **first, **body})
    return rows


def write_table(rows: Iterable[Mapping[str, Any]], out: Path) -> Any:
    """Write ``table.csv`` (and ``table.parquet`` when pyarrow is installed).

    Returns
    -------
    pandas.DataFrame
        The table as written.
    """
    import pandas as pd

    frame = pd.DataFrame(list(rows))
    with atomic_path(out / TABLE_CSV) as tmp:
        frame.to_csv(tmp, index=False)
    parquet = out / TABLE_PARQUET
    if _has_pyarrow():
        with atomic_path(parquet) as tmp:
            frame.to_parquet(tmp, index=False)
    elif parquet.exists():  # never leave a stale Parquet table beside the CSV
        parquet.unlink()
    return frame


def _has_pyarrow() -> bool:
    try:
        return importlib.util.find_spec("pyarrow") is not None
    except (ImportError, ValueError):
        return False


def read_table(out: str | Path) -> Any:
    """The table of the sweep in folder ``out`` as a pandas DataFrame.

    Raises
    ------
    ParameterError
        ``out`` holds no sweep table.
    """
    import pandas as pd

    out = Path(out)
    if (out / TABLE_PARQUET).is_file() and _has_pyarrow():
        return pd.read_parquet(out / TABLE_PARQUET)
    if (out / TABLE_CSV).is_file():
        # The numbers as written, to the bit (pandas 3 does it by default).
        exact = {"float_precision": "round_trip"} if _major(pd) < 3 else {}
        return pd.read_csv(
            out / TABLE_CSV, keep_default_na=False, na_values=[""], **exact
        )
    raise ParameterError("DIR", str(out), f"a sweep folder (with {TABLE_CSV})")


def _major(module: Any) -> int:
    try:
        return int(str(module.__version__).split(".")[0])
    except ValueError:  # pragma: no cover - an unusual version string
        return 0


def read_spec(out: str | Path) -> dict[str, Any]:
    """``OUT/sweep.json`` (empty dict when missing or unreadable)."""
    try:
        return json.loads((Path(out) / "sweep.json").read_text())
    except (OSError, ValueError):
        return {}
