"""The ``sweep`` and ``sweep-plot`` commands of ``skfem-npfem``."""

from __future__ import annotations

import argparse
import sys
import warnings
from typing import Any

from ..scenes import get_scene
from .api import sweep
from .cluster import CONNECT_TIMEOUT
from .engine import RETRIES
from .plan import parse_grid_args, parse_set_args
from .plot import plot_sweep

__all__ = ["add_debug", "add_sweep_commands", "cmd_sweep", "cmd_sweep_plot"]


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run a sweep; exit code 1 when some runs failed (they are in the table)."""
    get_scene(args.scene)  # an unknown scene is the first thing to report
    grid = parse_grid_args(args.grid)
    fixed = parse_set_args(args.set)
    table = sweep(
        args.scene,
        grid,
        out=args.out,
        fixed=fixed,
        workers=args.workers,
        scheduler=args.scheduler,
        retries=args.retries,
        connect_timeout=args.connect_timeout,
        progress=not args.quiet,
    )
    failed = int((table["status"] != "ok").sum())
    if failed:
        print(
            f"{failed} of {len(table)} runs failed (error column of the table); "
            "rerun the same command to retry them",
            file=sys.stderr,
        )
    return 1 if failed else 0


def cmd_sweep_plot(args: argparse.Namespace) -> int:
    """Draw one metric of a sweep against one parameter."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        path = plot_sweep(args.dir, args.metric, args.param, out=args.png, log=args.log)
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    print(path)
    return 0


def add_sweep_commands(sub: Any) -> None:
    """Add ``sweep`` and ``sweep-plot`` to the ``skfem-npfem`` sub-parsers."""
    p = sub.add_parser(
        "sweep",
        help="run a scene over a parameter grid on Dask (sweep extra)",
        description="Run SCENE for every combination of the --grid values on a "
        "local Dask cluster (default) or an existing scheduler; one folder per "
        "run under OUT/runs and one table OUT/table.csv.  Rerunning the same "
        "command skips finished runs and resumes interrupted ones.",
    )
    p.add_argument("scene", help="scene name (see 'skfem-npfem scenes')")
    p.add_argument(
        "--grid",
        action="append",
        metavar="NAME=V1,V2,...",
        help="varied parameter and its values (repeatable: Cartesian product)",
    )
    p.add_argument(
        "--set",
        action="append",
        metavar="NAME=VALUE",
        help="parameter fixed for every run (repeatable)",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="sweep folder")
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="local worker processes (default: one per core)",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="existing Dask scheduler, e.g. tcp://HOST:8786 (no local cluster)",
    )
    p.add_argument(
        "--connect-timeout",
        type=float,
        default=CONNECT_TIMEOUT,
        metavar="S",
        help=f"seconds to wait for --scheduler (default {CONNECT_TIMEOUT:g})",
    )
    p.add_argument(
        "--retries",
        type=int,
        default=RETRIES,
        help=f"retries of a run whose worker died or that crashed (default {RETRIES})",
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    add_debug(p)
    p.set_defaults(func=cmd_sweep)
    q = sub.add_parser(
        "sweep-plot",
        help="plot one metric of a sweep against one parameter",
        description="Draw METRIC against PARAM from DIR/table.csv (one line per "
        "combination of the other varied parameters); prints the PNG path.",
    )
    q.add_argument("dir", help="sweep folder (with table.csv)")
    q.add_argument("metric", help="table column, e.g. sigma_v_rel_l2")
    q.add_argument("param", help="table column, e.g. spacing")
    q.add_argument("--png", metavar="FILE", help="output (default DIR/M_vs_P.png)")
    q.add_argument("--log", default="", choices=("", "x", "y", "xy"), help="log axes")
    add_debug(q)
    q.set_defaults(func=cmd_sweep_plot)


def add_debug(p: argparse.ArgumentParser) -> None:
    """Add ``--debug`` (tracebacks) to a sub-command, after the command name too."""
    p.add_argument(
        "--debug",
        action="store_true",
        default=argparse.SUPPRESS,
        help="show tracebacks",
    )
