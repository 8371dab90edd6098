"""The runs of a sweep: grid parsing, validation and deterministic run names.

Everything here happens on the machine that starts the sweep, before any
cluster exists, so that bad input costs nothing and is reported as one
:class:`~skfem_npfem.errors.ParameterError`.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import ParameterError
from ..io import write_json

__all__ = [
    "Run",
    "check_spec",
    "parse_grid_args",
    "parse_set_args",
    "plan_runs",
    "run_name",
    "value_label",
    "write_json",
]

#: Longest run-folder name kept as is; longer names end in a hash instead.
MAX_NAME = 120

#: Scene parameters a sweep may choose itself and that never name a run folder.
SWEEP_CHOSEN = ("threads",)


@dataclass(frozen=True)
class Run:
    """One run of a sweep.

    Attributes
    ----------
    name : str
        Folder name under ``OUT/runs`` (from the varied values, deterministic).
    varied : dict
        The values that differ between runs (the grid point), validated.
    overrides : dict
        Everything passed to :func:`~skfem_npfem.run_scene`: fixed and varied.
    values : dict
        All scene parameters after defaults and overrides (what the run uses).
    """

    name: str
    varied: dict[str, Any]
    overrides: dict[str, Any]
    values: dict[str, Any] = field(default_factory=dict)


def parse_set_args(items: Sequence[str] | None) -> dict[str, str]:
    """``["name=value", ...]`` (``--set``) as a dict of strings."""
    out: dict[str, str] = {}
    for item in items or ():
        name, sep, val = item.partition("=")
        if not sep or not name.strip():
            raise ParameterError("--set", item, "name=value")
        if name.strip() in out:
            raise ParameterError("--set", item, f"{name.strip()} set once")
        out[name.strip()] = val
    return out


def parse_grid_args(items: Sequence[str] | None) -> dict[str, list[str]]:
    """``["name=v1,v2,...", ...]`` (``--grid``) as ``{name: [v1, v2, ...]}``.

    Raises
    ------
    ParameterError
        No grid, a grid without ``=``, an empty name or value, or a name given twice.
    """
    if not items:
        raise ParameterError.missing(
            "--grid",
            "a sweep needs at least one --grid name=v1,v2,... (a parameter to "
            "vary and its values, e.g. --grid spacing=0.02,0.01)",
        )
    grid: dict[str, list[str]] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise ParameterError("--grid", item, "name=v1,v2,... (comma-separated)")
        values = [v.strip() for v in text.split(",")]
        if not text.strip() or any(not v for v in values):
            raise ParameterError(
                "--grid", item, f"a non-empty comma-separated list of {name} values"
            )
        if name in grid:
            raise ParameterError("--grid", item, f"each parameter once ({name} twice)")
        grid[name] = values
    return grid


def value_label(value: Any) -> str:
    """Short, file-name-safe text of a parameter value that round-trips floats.

    Examples
    --------
    >>> value_label(1e7), value_label(1e3), value_label(0.25), value_label(2.0)
    ('1e+07', '1000', '0.25', '2')
    """
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float) and math.isfinite(value):
        plain = repr(value).removesuffix(".0")  # "1000", "0.25"
        for digits in range(1, 18):  # the shortest %g text that gives value back
            short = f"{value:.{digits}g}"  # "1e+07"
            if float(short) == value:
                return short if len(short) < len(plain) else plain
        return plain
    if value is None:
        return "default"
    return re.sub(r"[^A-Za-z0-9.+-]+", "-", str(value)).strip("-") or "x"


def run_name(varied: Mapping[str, Any]) -> str:
    """Folder name of a run: ``name=value`` pairs joined by ``_``, in grid order."""
    name = "_".join(f"{k}={value_label(v)}" for k, v in varied.items()) or "run"
    if len(name) > MAX_NAME:  # long grids: keep a readable head, make it unique
        digest = hashlib.sha1(name.encode()).hexdigest()[:10]
        name = f"{name[: MAX_NAME - 11]}~{digest}"
    return name


def _checked(scene: Any, name: str, value: Any, what: str) -> Any:
    by_name = {p.name: p for p in scene.params}
    if name not in by_name:
        raise ParameterError(
            what, name, f"scene '{scene.name}' has parameters: " + ", ".join(by_name)
        )
    return by_name[name].check(value)


def plan_runs(
    scene: Any,
    grid: Mapping[str, Sequence[Any]] | None = None,
    fixed: Mapping[str, Any] | None = None,
    cases: Sequence[Mapping[str, Any]] | None = None,
) -> list[Run]:
    """Validated runs of a sweep, in grid order (the first name varies slowest).

    Parameters
    ----------
    scene : Scene
        From :func:`~skfem_npfem.scenes.get_scene`.
    grid : dict, optional
        Parameter name -> list of values (numbers, or strings as on the command
        line); the runs are the Cartesian product.
    fixed : dict, optional
        Parameter name -> value shared by every run.
    cases : list of dict, optional
        Explicit runs instead of a grid (each a dict of overrides).

    Raises
    ------
    ParameterError
        Unknown parameters, empty or repeated values, a parameter both varied
        and fixed, both or neither of ``grid`` and ``cases``, or a value a
        parameter does not allow.
    """
    if (grid is None) == (cases is None):
        raise ParameterError("grid", grid, "give a grid or a list of cases (not both)")
    fixed_v = {k: _checked(scene, k, v, "fixed") for k, v in (fixed or {}).items()}
    points: list[dict[str, Any]] = []
    if grid is not None:
        axes = _grid_axes(scene, grid, fixed_v)
        points = [
            dict(zip(axes, combo, strict=True))
            for combo in itertools.product(*axes.values())
        ]
    else:
        if not cases:
            raise ParameterError("cases", cases, "a non-empty list of override dicts")
        for case in cases:
            both = sorted(set(case) & set(fixed_v))
            if both:
                raise ParameterError("cases", case, f"{both} are already fixed")
            points.append(
                {
                    k: _checked(scene, k, _as_list([v])[0], "cases")
                    for k, v in case.items()
                }
            )
    runs = []
    seen: dict[str, dict] = {}
    for varied in points:
        name = run_name(varied)
        if name in seen:
            raise ParameterError("cases", varied, f"distinct runs ({name} twice)")
        seen[name] = varied
        overrides = {**fixed_v, **varied}
        runs.append(Run(name, varied, overrides, dict(scene.resolve(overrides))))
    return runs


def _grid_axes(
    scene: Any, grid: Mapping[str, Sequence[Any]], fixed: Mapping[str, Any]
) -> dict[str, list[Any]]:
    if not grid:
        raise ParameterError("grid", dict(grid), "at least one name -> values entry")
    axes: dict[str, list[Any]] = {}
    for name, values in grid.items():
        values = _as_list(values)
        if name in fixed:
            raise ParameterError(
                "--grid", name, "a parameter either varied (--grid) or fixed (--set)"
            )
        if len(values) == 0:
            raise ParameterError("--grid", f"{name}=", f"at least one {name} value")
        checked = [_checked(scene, name, v, "--grid") for v in values]
        labels = [value_label(v) for v in checked]
        if len(set(labels)) != len(labels):
            raise ParameterError(
                "--grid", f"{name}={','.join(map(str, values))}", "distinct values"
            )
        axes[name] = checked
    return axes


def check_spec(out: Path, spec: dict[str, Any]) -> None:
    """Refuse to mix two different sweeps in one folder; record this one.

    ``OUT/sweep.json`` holds the scene and the fixed values.  A rerun with the
    same scene and fixed values may change the grid (new runs are added, the
    finished ones reused); anything else names the conflict.
    """
    path = out / "sweep.json"
    if path.is_file():
        try:
            old = json.loads(path.read_text())
        except (OSError, ValueError):
            old = {}
        for key in ("scene", "fixed"):
            was, now = old.get(key), json.loads(json.dumps(spec[key]))
            if key == "fixed" and isinstance(was, dict):
                was = {k: v for k, v in was.items() if k not in SWEEP_CHOSEN}
                now = {k: v for k, v in now.items() if k not in SWEEP_CHOSEN}
            if was is not None and was != now:
                raise ParameterError(
                    "--out",
                    str(out),
                    f"a new folder or the same {key} as the sweep already there "
                    f"({key} was {was}, now {now})",
                )
    write_json(path, spec)


def _as_list(values: Any) -> list[Any]:
    """Grid values as a list of plain Python scalars ("a,b" splits at commas)."""
    if isinstance(values, str):
        values = [v.strip() for v in values.split(",")]
    elif not hasattr(values, "__iter__"):
        values = [values]
    return [v.item() if hasattr(v, "item") else v for v in values]
