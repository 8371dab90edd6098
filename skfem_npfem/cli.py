"""Command-line interface: ``skfem-npfem`` (also ``python -m skfem_npfem``).

Commands
--------
``skfem-npfem scenes``
    List scenes with every parameter, unit and default, and the summary metrics.
``skfem-npfem run SCENE [--set name=value ...] [--out DIR] [--summary FILE.json]``
    Run a scene; write a VTU per output step plus ``result.pvd`` to DIR and a JSON
    summary to FILE.json.  ``--resume`` continues from the latest checkpoint in
    DIR.  ``--quiet`` hides the progress line.
``skfem-npfem plot DIR``
    Render PNG snapshots (and an animation) of a result folder (``viz`` extra).

Errors are printed as one line (``error: ...``) with exit code 2; ``--debug``
shows the traceback instead.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from . import __version__
from .errors import NpfemError, ParameterError

__all__ = ["main"]


def _parse_sets(items: Sequence[str]) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        if "=" not in item:
            raise ParameterError("--set", item, "name=value")
        key, val = item.split("=", 1)
        out[key.strip()] = val
    return out


def _format_default(p) -> str:
    if p.default is None:
        return "(derived)"
    return str(p.default).lower() if isinstance(p.default, bool) else str(p.default)


def cmd_scenes(args: argparse.Namespace) -> int:
    """Print the scene catalogue."""
    from .scenes import SCENES

    if args.json:
        cat = {
            name: {
                "description": s.description,
                "parameters": {
                    p.name: {
                        "default": p.default,
                        "unit": p.unit,
                        "help": p.help,
                        "allowed": p.allowed(),
                    }
                    for p in s.params
                },
                "metrics": s.metrics_doc,
            }
            for name, s in SCENES.items()
        }
        print(json.dumps(cat, indent=1))
        return 0
    for name, s in SCENES.items():
        print(f"{name}: {s.description}")
        print(f"  {'parameter':<18} {'default':<12} {'unit':<8} description")
        for p in s.params:
            print(
                f"  {p.name:<18} {_format_default(p):<12} {p.unit:<8} {p.help} "
                f"[{p.allowed()}]"
            )
        print("  summary metrics:")
        for k, v in s.metrics_doc.items():
            print(f"    {k}: {v}")
        print()
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    """Run one scene."""
    from .scenes import run_scene

    overrides = _parse_sets(args.set or [])
    progress = False if args.quiet else None
    if args.resume and not args.out:
        raise ParameterError("--resume", True, "needs --out DIR with a checkpoint")
    result = run_scene(
        args.scene,
        overrides,
        out=args.out,
        summary=args.summary,
        progress=progress,
        resume=args.resume,
    )
    if not args.quiet:
        metrics = {
            k: v for k, v in result["metrics"].items() if not isinstance(v, list)
        }
        solver = result["solver"]
        print(
            f"scene {result['scene']}: {solver['steps']} steps, "
            f"{solver['ipm_iterations_total']} IPM iterations, "
            f"{result['wall_time_total']:.2f} s"
        )
        for k, v in metrics.items():
            print(f"  {k} = {v}")
        if args.out:
            print(f"  results: {args.out}/result.pvd")
        if args.summary:
            print(f"  summary: {args.summary}")
    return 0


def cmd_plot(args: argparse.Namespace) -> int:
    """Render snapshots of a result folder."""
    try:
        from .plot import plot_results
    except ImportError as err:  # pragma: no cover - depends on the extra
        raise NpfemError(
            f"plotting needs the viz extra (pip install 'skfem-npfem[viz]'): {err}"
        ) from None
    written = plot_results(
        args.dir,
        times=args.times,
        normalised=not args.absolute,
        field=args.field,
        animation=args.animation,
    )
    for path in written:
        print(path)
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argparse parser of ``skfem-npfem``."""
    parser = argparse.ArgumentParser(
        prog="skfem-npfem",
        description="Nodal-integration particle FEM (N-PFEM) for scikit-fem.",
    )
    parser.add_argument("--version", action="version", version=__version__)
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", required=True)
    p_sc = sub.add_parser("scenes", help="list scenes and their parameters")
    p_sc.add_argument("--json", action="store_true", help="machine-readable output")
    p_sc.set_defaults(func=cmd_scenes)
    p_run = sub.add_parser("run", help="run a scene")
    p_run.add_argument("scene", help="scene name (see 'skfem-npfem scenes')")
    p_run.add_argument(
        "--set",
        action="append",
        metavar="NAME=VALUE",
        help="override a scene parameter (repeatable)",
    )
    p_run.add_argument("--out", metavar="DIR", help="folder for VTU/PVD output")
    p_run.add_argument("--summary", metavar="FILE", help="write a JSON summary")
    p_run.add_argument(
        "--resume",
        action="store_true",
        help="continue from the latest checkpoint in --out",
    )
    p_run.add_argument("--quiet", action="store_true", help="no progress output")
    p_run.add_argument("--debug", action="store_true", help="show tracebacks")
    p_run.set_defaults(func=cmd_run)
    p_plot = sub.add_parser("plot", help="render PNG snapshots of a result folder")
    p_plot.add_argument("dir", help="result folder (with result.pvd)")
    p_plot.add_argument(
        "--times",
        type=float,
        nargs="*",
        default=None,
        help="times to render (normalised by sqrt(H0/g) unless --absolute)",
    )
    p_plot.add_argument(
        "--absolute", action="store_true", help="--times are in seconds"
    )
    p_plot.add_argument(
        "--field",
        default="stress_yy",
        help="stress_yy, plastic_strain_eq, velocity, ...",
    )
    p_plot.add_argument("--animation", default="gif", choices=("gif", "mp4", "none"))
    p_plot.add_argument("--debug", action="store_true", help="show tracebacks")
    p_plot.set_defaults(func=cmd_plot)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except (NpfemError, OSError) as err:
        if args.debug:
            raise
        print(f"error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted; finished steps are on disk", file=sys.stderr)
        return 130
