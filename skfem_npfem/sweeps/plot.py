"""``skfem-npfem sweep-plot``: one metric of a sweep against one parameter."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from ..errors import NpfemError, ParameterError, warn_user
from ..io import atomic_path
from .plan import value_label
from .table import read_spec, read_table

__all__ = ["NOT_AT_REST", "not_at_rest", "plot_sweep"]

#: Legend entry of the runs that ended before the material came to rest.
NOT_AT_REST = "not at rest at t_end (not final)"


def plot_sweep(
    folder: str | Path,
    metric: str,
    param: str,
    *,
    out: str | Path | None = None,
    log: str = "",
) -> Path:
    """Draw ``metric`` against ``param`` for the finished runs of a sweep.

    One line per combination of the other varied parameters (from
    ``sweep.json``); failed runs are left out.  Runs whose summary says they
    ended before the material came to rest (``at_rest`` false: a collapse
    stopped by ``t_end``) are drawn with open markers, named in the legend,
    and reported in one :class:`UserWarning` (their metrics are not final).

    Parameters
    ----------
    folder : path
        Sweep folder (with ``table.csv``).
    metric, param : str
        Table columns (``skfem-npfem sweep`` prints the table's path; any
        numeric column works, e.g. ``solver.ipm_iterations_total``).
    out : path, optional
        PNG to write (default ``FOLDER/METRIC_vs_PARAM.png``).
    log : str
        Logarithmic axes: "", "x", "y" or "xy".

    Returns
    -------
    Path
        The PNG written.
    """
    if log not in ("", "x", "y", "xy"):
        raise ParameterError("--log", log, "one of x, y, xy")
    table = read_table(folder)
    for what, name in (("METRIC", metric), ("PARAM", param)):
        if name not in table.columns:
            raise ParameterError(what, name, "a column of the table: " + _cols(table))
    ok = table[table["status"] == "ok"]
    if ok.empty:
        raise ParameterError("DIR", str(folder), "a sweep with finished runs")
    y = ok[metric]
    if not _numeric(y):
        raise ParameterError("METRIC", metric, "a numeric column: " + _cols(table))
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as err:  # pragma: no cover - depends on the extra
        raise NpfemError(
            f"sweep-plot needs matplotlib (pip install 'skfem-npfem[viz]'): {err}"
        ) from None
    others = [
        k for k in read_spec(folder).get("grid", {}) if k != param and k in ok.columns
    ]
    moving = not_at_rest(ok)
    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    groups = ok.groupby(others, sort=True, dropna=False) if others else [((), ok)]
    for key, sub in groups:
        sub = sub.sort_values(param)
        keys = key if isinstance(key, tuple) else (key,)
        label = ", ".join(
            f"{k}={value_label(v)}" for k, v in zip(others, keys, strict=True)
        )
        (line,) = ax.plot(sub[param], sub[metric], "o-", label=label or None)
        still = moving.loc[sub.index]
        if still.any():
            ax.plot(
                sub[param][still],
                sub[metric][still],
                "o",
                mfc="white",
                mec=line.get_color(),
                zorder=line.get_zorder() + 0.1,
            )
    if moving.any():
        ax.plot([], [], "o", mfc="white", mec="0.3", label=NOT_AT_REST)
        warn_user(
            f"{int(moving.sum())} of {len(ok)} runs ended at t_end before the "
            f"material came to rest (at_rest = false): their {metric} is not "
            f"final; open markers in the plot",
        )
    ax.set_xlabel(param)
    ax.set_ylabel(metric)
    if "x" in log:
        ax.set_xscale("log")
    if "y" in log:
        ax.set_yscale("log")
    failed = len(table) - len(ok)
    title = f"{read_spec(folder).get('scene', 'sweep')}: {metric} against {param}"
    ax.set_title(title + (f" ({failed} failed runs not shown)" if failed else ""))
    if others or moving.any():
        ax.legend(fontsize="small")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    path = Path(out) if out is not None else Path(folder) / _png_name(metric, param)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120, format="png")
    plt.close(fig)
    return path


def not_at_rest(rows: Any) -> Any:
    """Boolean Series: the run's ``at_rest`` is false (False without the column)."""
    import pandas as pd

    if "at_rest" not in rows.columns:
        return pd.Series(False, index=rows.index)
    return rows["at_rest"].map(lambda v: str(v).strip().lower() in ("false", "0"))


def _numeric(col: Any) -> bool:
    import pandas as pd

    return bool(pd.api.types.is_numeric_dtype(col)) and not bool(
        pd.api.types.is_bool_dtype(col)
    )


def _cols(table: Any) -> str:
    return ", ".join(c for c in table.columns if _numeric(table[c]))


def _png_name(metric: str, param: str) -> str:
    safe = re.sub(r"[^A-Za-z0-9._-]+", "-", f"{metric}_vs_{param}")
    return f"{safe}.png"
