"""Command-line interface: ``skfem-npfem`` (also ``python -m skfem_npfem``).

Commands
--------
``skfem-npfem scenes [SCENE]``
    List scenes (or one) with every parameter, unit and default, and the
    summary metrics; ``skfem-npfem run SCENE --help`` lists them too.
``skfem-npfem run SCENE [--set name=value ...] [--out DIR] [--summary FILE.json]``
    Run a scene; write a VTU per output step plus ``result.pvd`` to DIR and a JSON
    summary to FILE.json.  ``--resume`` continues from the latest checkpoint in
    DIR.  ``--quiet`` hides the progress line.
``skfem-npfem plot DIR``
    Render PNG snapshots (and an animation) of a result folder (``viz`` extra).
``skfem-npfem sweep SCENE --grid name=v1,v2 ... --out DIR``
    Run a parameter grid on Dask (``sweep`` extra); ``sweep-plot DIR METRIC
    PARAM`` draws one metric against one parameter (see docs/sweep.md).

Errors are printed as one line (``error: ...``) with exit code 2; ``--debug``
shows the traceback instead.  Warnings of a run (e.g. a limit load stopped by its
cap before the plateau) are printed as one ``warning: ...`` line each.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from collections.abc import Sequence

from ._version import __version__
from .errors import NpfemError, ParameterError, RunInterrupted
from .io import dumps
from .run.control import end_line
from .scenes import SCENES, run_scene
from .sweeps.cli import add_debug, add_sweep_commands

__all__ = ["main"]


def _parse_sets(items: Sequence[str]) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        if "=" not in item:
            raise ParameterError("--set", item, "name=value")
        key, val = item.split("=", 1)
        key = key.strip()
        if key in out:
            raise ParameterError(
                "--set",
                item,
                f"each parameter once ({key} is also set to {out[key]!r})",
            )
        out[key] = val
    return out


def format_value(value: object) -> str:
    """A metric for the terminal: floats to 4 significant digits, None/NaN as null.

    Examples
    --------
    >>> format_value(0.20018114348384494), format_value(None), format_value(True)
    ('0.2002', 'null', 'true')
    >>> format_value(2.4675063972e-05), format_value(1035)
    ('2.468e-05', '1035')
    >>> format_value({"setup": 0.0158615570035181, "solve": 0.5013162620016374})
    '{setup: 0.01586, solve: 0.5013}'
    """
    if value is None or (isinstance(value, float) and value != value):
        return "null"
    if isinstance(value, dict):  # e.g. the wall time of each stage
        inner = ", ".join(f"{k}: {format_value(v)}" for k, v in value.items())
        return "{" + inner + "}"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def _format_default(p) -> str:
    if p.default is None:
        return "(derived)"
    return str(p.default).lower() if isinstance(p.default, bool) else str(p.default)


def _chosen_scenes(name: str | None) -> dict:
    """All scenes, or the one named (refused if there is none of that name)."""
    if name is None:
        return dict(SCENES)
    if name not in SCENES:
        raise ParameterError("scene", name, "one of " + ", ".join(SCENES))
    return {name: SCENES[name]}


def scene_text(name: str) -> str:
    """One scene's parameters and summary metrics as plain text.

    Examples
    --------
    >>> print(scene_text("elastic-column").splitlines()[0])
    elastic-column: soil column under self-weight (oedometric).
    """
    s = SCENES[name]
    lines = [
        f"{name}: {s.description}",
        f"  {'parameter':<18} {'default':<12} {'unit':<8} description",
    ]
    lines += [
        f"  {p.name:<18} {_format_default(p):<12} {p.unit:<8} {p.help} [{p.allowed()}]"
        for p in s.params
    ]
    lines.append("  summary metrics:")
    lines += [f"    {k}: {v}" for k, v in s.metrics_doc.items()]
    return "\n".join(lines)


def cmd_scenes(args: argparse.Namespace) -> int:
    """Print the scene catalogue (or one scene's part of it)."""
    chosen = _chosen_scenes(args.name)
    if args.markdown:
        print(scenes_markdown(list(chosen)))
        return 0
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
            for name, s in chosen.items()
        }
        print(dumps(cat, indent=1))
        return 0
    for name in chosen:
        print(scene_text(name))
        print()
    return 0


def scenes_markdown(names: Sequence[str] | None = None) -> str:
    """The scene catalogue as Markdown (this is docs/scenes.md).

    ``names`` restricts it to those scenes (default: all).
    """
    lines = [
        "# Scenes",
        "",
        "Generated by `skfem-npfem scenes --markdown`; a test keeps it in sync with "
        "the code. Set parameters with `--set name=value`; the metrics are the keys "
        "of `metrics` in the JSON written by `--summary`.",
        "",
    ]
    for name in SCENES if names is None else names:
        s = SCENES[name]
        lines += [
            f"## `{name}`",
            "",
            s.description,
            "",
            "| parameter | default | unit | description | allowed |",
            "|---|---|---|---|---|",
        ]
        for p in s.params:
            lines.append(
                f"| `{p.name}` | {_format_default(p)} | {p.unit} | "
                f"{p.help} | {p.allowed()} |"
            )
        lines += ["", "| metric | meaning |", "|---|---|"]
        lines += [f"| `{k}` | {v} |" for k, v in s.metrics_doc.items()]
        lines.append("")
    return "\n".join(lines)


def cmd_run(args: argparse.Namespace) -> int:
    """Run one scene."""
    overrides = _parse_sets(args.set or [])
    progress = False if args.quiet else None
    if args.resume and not args.out:
        raise ParameterError("--resume", True, "needs --out DIR with a checkpoint")
    # A scene's warnings (e.g. a limit load stopped by its cap before the
    # plateau) are printed as one clean line each, not as Python's
    # "file:line: UserWarning" block; the warning filters stay as they are.
    with warnings.catch_warnings(record=True) as caught:
        try:
            result = run_scene(
                args.scene,
                overrides,
                out=args.out,
                summary=args.summary,
                progress=progress,
                resume=args.resume,
            )
        finally:
            end_line()
            for msg in dict.fromkeys(str(w.message) for w in caught):
                print(f"warning: {msg}", file=sys.stderr)
    if not args.quiet:
        metrics = {
            k: v for k, v in result["metrics"].items() if not isinstance(v, list)
        }
        print(f"scene {result['scene']}: {work_done(result)}")
        for k, v in metrics.items():
            print(f"  {k} = {format_value(v)}")
        if args.out:
            print(f"  results: {args.out}/result.pvd")
        if args.summary:
            print(f"  summary: {args.summary} (full precision)")
    return 0


def work_done(result: dict) -> str:
    """What a run solved, for its headline: steps, or a limit analysis's programs.

    Examples
    --------
    >>> work_done({"solver": {"steps": 3, "ipm_iterations_total": 40},
    ...            "metrics": {}, "wall_time_total": 1.5})
    '3 steps, 40 IPM iterations, 1.50 s'
    >>> work_done({"solver": {"steps": 0, "ipm_iterations_total": 0},
    ...            "metrics": {"cone_programs": 5, "limit_iterations": 92},
    ...            "wall_time_total": 7.25})
    'limit analysis, 5 cone programs, 92 IPM iterations, 7.25 s'
    """
    m, solver = result["metrics"], result["solver"]
    if m.get("cone_programs") is not None:  # analysis=limit: no steps
        n = m["cone_programs"]
        return (
            f"limit analysis, {n} cone program{'s' if n != 1 else ''}, "
            f"{m.get('limit_iterations', 0)} IPM iterations, "
            f"{result['wall_time_total']:.2f} s"
        )
    return (
        f"{solver['steps']} steps, {solver['ipm_iterations_total']} IPM "
        f"iterations, {result['wall_time_total']:.2f} s"
    )


def interrupted_message(err: KeyboardInterrupt, command: str = "run") -> str:
    """The one line printed when ``command`` is stopped by a signal."""
    if command == "sweep":
        return (
            "interrupted; finished runs are kept, and running the same sweep "
            "command again skips them and continues the interrupted runs from "
            "their latest checkpoints"
        )
    if not isinstance(err, RunInterrupted):
        if command != "run":
            return "interrupted; every file written so far is complete"
        return (
            "interrupted; every file written so far is complete, and --resume "
            "continues from the latest checkpoint in --out, if there is one"
        )
    how = "abandoned the step in progress; " if err.abandoned else ""
    msg = (
        f"interrupted by {err.signal_name} after step {err.step} "
        f"(t = {err.time:.6g} s): {how}"
    )
    saved = []
    if err.checkpoint is not None:
        saved.append(f"checkpoint {err.checkpoint}")
    if err.summary_path is not None:
        saved.append(f'partial summary {err.summary_path} ("interrupted": true)')
    why = "no step finished: --out is as it was" if err.step == 0 else "no --out"
    msg += ", ".join(saved) if saved else f"nothing written ({why})"
    if err.checkpoint is not None:
        msg += "; continue with --resume"
    return msg


def cmd_plot(args: argparse.Namespace) -> int:
    """Render snapshots of a result folder."""
    try:
        from .viz.plot import plot_results
    except ImportError as err:  # pragma: no cover - depends on the extra
        raise NpfemError(
            f"plotting needs the viz extra (pip install 'skfem-npfem[viz]'): {err}"
        ) from None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        written = plot_results(
            args.dir,
            times=args.times,
            normalised=not args.absolute,
            field="stress_yy" if args.field is None else list(args.field),
            animation=args.animation,
        )
    for w in caught:
        print(f"note: {w.message}", file=sys.stderr)
    for path in written:
        print(path)
    return 0


def _help_scene(argv: Sequence[str]) -> str | None:
    """The scene of ``run SCENE ... --help`` (None for any other command line)."""
    argv = list(argv)
    if "run" not in argv or not {"-h", "--help"} & set(argv):
        return None
    after = argv[argv.index("run") + 1 :]
    valued = {"--set", "--out", "--summary"}  # options followed by a value
    words = [a for i, a in enumerate(after) if i == 0 or after[i - 1] not in valued]
    name = next((a for a in words if not a.startswith("-")), None)
    return name if name in SCENES else None


def build_parser(scene: str | None = None) -> argparse.ArgumentParser:
    """The argparse parser of ``skfem-npfem``.

    ``scene``: the help of ``run`` lists that scene's parameters and metrics.
    """
    parser = argparse.ArgumentParser(
        prog="skfem-npfem",
        description="Nodal-integration particle FEM (N-PFEM) for scikit-fem.",
    )
    parser.add_argument("--version", action="version", version=__version__)
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", required=True)
    p_sc = sub.add_parser("scenes", help="list scenes and their parameters")
    p_sc.add_argument(
        "name", nargs="?", default=None, help="list only this scene (default: all)"
    )
    p_sc.add_argument("--json", action="store_true", help="machine-readable output")
    p_sc.add_argument("--markdown", action="store_true", help="Markdown tables")
    p_sc.set_defaults(func=cmd_scenes)
    p_run = sub.add_parser(
        "run",
        help="run a scene",
        description="Run a scene. 'skfem-npfem run SCENE --help' lists the "
        "scene's parameters (set them with --set name=value) and metrics.",
        epilog=None if scene is None else scene_text(scene),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
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
    add_debug(p_run)
    p_run.set_defaults(func=cmd_run)
    p_plot = sub.add_parser("plot", help="render PNG snapshots of a result folder")
    p_plot.add_argument("dir", help="result folder (with result.pvd)")
    p_plot.add_argument(
        "--times",
        type=float,
        nargs="*",
        default=None,
        help="times to render (normalised by sqrt(H0/g) unless --absolute; "
        "strip-footing: settlements in m; cone-penetration: w/D; "
        "footing-penetration: w/B)",
    )
    p_plot.add_argument(
        "--absolute", action="store_true", help="--times are in seconds"
    )
    p_plot.add_argument(
        "--field",
        nargs="+",
        default=None,
        help="fields to draw (default: the vertical stress and plastic_strain_eq); "
        "stress_xx, stress_yy, stress_zz, stress_xy, pressure, plastic_strain_eq, "
        "velocity, displacement; with pore water pore_pressure, "
        "excess_pore_pressure",
    )
    p_plot.add_argument("--animation", default="gif", choices=("gif", "mp4", "none"))
    add_debug(p_plot)
    p_plot.set_defaults(func=cmd_plot)
    add_sweep_commands(sub)
    return parser


def _silence_stdout() -> None:
    """Point stdout at the null device (after the reader closed the pipe)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # not a real file (tests)
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit code."""
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(_help_scene(argv))
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except BrokenPipeError:
        # The reader of stdout went away (`skfem-npfem scenes | head -1`): stop
        # quietly, as other command-line tools do, and keep Python's final
        # flush of stdout from failing again on the closed pipe.
        _silence_stdout()
        return 128 + 13  # the shell's code of a process ended by SIGPIPE
    except (NpfemError, OSError) as err:
        if args.debug:
            raise
        print(f"error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as err:
        end_line()
        print(interrupted_message(err, args.command), file=sys.stderr)
        return err.exit_code if isinstance(err, RunInterrupted) else 130
