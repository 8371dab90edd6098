"""Reading a result folder's steps for the pictures.

The fields a picture can show, the requested snapshots, the animation's frames
and the colour ranges over all stored steps.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import CheckpointError, ParameterError, warn_user
from ..io import read_step
from .colours import (
    _SAMPLE,
    _STRESS_INDEX,
    _robust_range,
)
from .render import (
    Step,
)
from .snapshots import (
    _frame_indices,
    _pick_snapshots,
)

#: The ``field`` argument that draws the vertical stress and the plastic strain.
_DEFAULT_FIELD = "stress_yy"

__all__ = [
    "FIELDS",
    "PORE_FIELDS",
]


#: The fields of a result with pore water (its VTU point data of these names).
PORE_FIELDS = ("pore_pressure", "excess_pore_pressure")

#: Fields :func:`plot_results` can draw, with a short description.
FIELDS: dict[str, str] = {
    "stress_xx": "normal stress xx (tension +)",
    "stress_yy": "normal stress yy (tension +)",
    "stress_zz": "normal stress zz (tension +)",
    "stress_xy": "shear stress xy",
    "stress_yz": "shear stress yz (3D only)",
    "stress_zx": "shear stress zx (3D only)",
    "pressure": "pressure, -mean normal stress (compression +)",
    "pore_pressure": "pore pressure (compression +)",
    "excess_pore_pressure": "excess pore pressure (compression +)",
    "plastic_strain_eq": "equivalent plastic strain",
    "velocity": "velocity magnitude",
    "displacement": "displacement magnitude",
}


def _field_values(name: str, pdata: Mapping[str, np.ndarray]) -> np.ndarray:
    """Return the (N,) values of field ``name`` from VTU point data."""
    if name in _STRESS_INDEX or name == "pressure":
        key = "stress"
    elif name in ("velocity", "displacement", "plastic_strain_eq", *PORE_FIELDS):
        key = name
    else:  # pragma: no cover - names are checked before
        raise ParameterError("field", name, "one of " + ", ".join(FIELDS))
    if key not in pdata and name in PORE_FIELDS:
        raise ParameterError("field", name, "a field of a result with pore water")
    if key not in pdata:
        raise CheckpointError(
            f"result has no point data {key!r} (has: {', '.join(pdata)})"
        )
    a = np.asarray(pdata[key], dtype=float)
    if name == "pressure":
        return -a[:, :3].mean(axis=1)
    if name in _STRESS_INDEX:
        return a[:, _STRESS_INDEX[name]].copy()
    if a.ndim == 2:
        return np.linalg.norm(a, axis=1)
    return a.copy()


def _read(path: Path, time: float, fields: Sequence[str]) -> tuple[Step, int]:
    """Read one VTU step; return it and its spatial dimension."""
    mesh = read_step(path)
    points = np.asarray(mesh.points, dtype=float)
    n = len(points)
    blocks = {b.type: np.asarray(b.data, dtype=np.int64) for b in mesh.cells}
    stress = mesh.point_data.get("stress")
    if "tetra" in blocks or (stress is not None and np.shape(stress)[-1] == 6):
        dim = 3
    elif "triangle" in blocks or (stress is not None and np.shape(stress)[-1] == 4):
        dim = 2
    else:
        dim = 3 if n and np.ptp(points[:, 2]) > 0 else 2
    cells = blocks.get("tetra" if dim == 3 else "triangle")
    cells = np.zeros((0, dim + 1), np.int64) if cells is None else cells
    in_cell = np.zeros(n, dtype=bool)
    in_cell[cells.ravel()] = True
    if "active" in mesh.point_data:
        in_cell &= np.asarray(mesh.point_data["active"]).ravel() != 0
    step = Step(time, points, cells, np.flatnonzero(~in_cell))
    if "mass" in mesh.point_data:
        step.mass = np.asarray(mesh.point_data["mass"], dtype=float).ravel()
    for name in fields:
        if dim == 2 and name in ("stress_yz", "stress_zx"):
            raise ParameterError("field", name, "a field of 2D results (3D only)")
        step.values[name] = _field_values(name, mesh.point_data)
    return step, dim


def _resolve_fields(field_arg: str | Sequence[str], dim: int) -> list[str]:
    """List of field names to draw (the default gives two fields)."""
    if isinstance(field_arg, str):
        if field_arg == _DEFAULT_FIELD:
            vertical = "stress_yy" if dim == 2 else "stress_zz"
            return [vertical, "plastic_strain_eq"]
        names = [s.strip() for s in field_arg.split(",") if s.strip()]
    else:
        names = [str(s) for s in field_arg]
    if not names:
        raise ParameterError("field", field_arg, "at least one field name")
    for name in names:
        if name not in FIELDS:
            raise ParameterError("field", name, "one of " + ", ".join(FIELDS))
    return list(dict.fromkeys(names))


@dataclass
class _Loaded:
    """The steps of a result read once (see :func:`_load`)."""

    dim: int
    names: list[str]
    kept: dict[int, Step]
    ranges: dict[str, tuple[float, float]]
    extremes: dict[str, tuple[float, float]]
    bad: list[int]


def _load(
    entries: list[tuple[float, Path]],
    field_arg: str | Sequence[str],
    needed: set[int],
) -> _Loaded:
    """Read every step once; keep those in ``needed``.

    A step that cannot be read is skipped with a warning and listed in
    ``bad``.  ``ranges`` is the robust colour range of each field over all
    steps, ``extremes`` its true minimum and maximum.
    """
    dim, names = 0, []
    kept: dict[int, Step] = {}
    pooled: dict[str, list[np.ndarray]] = {}
    extremes: dict[str, tuple[float, float]] = {}
    bad: list[int] = []
    for i, (t, path) in enumerate(entries):
        try:
            if not names:
                _, dim = _read(path, t, [])
                names = _resolve_fields(field_arg, dim)
                pooled = {name: [] for name in names}
            step, _ = _read(path, t, names)
        except CheckpointError as err:
            warn_user(f"skipped an unreadable step: {err}")
            bad.append(i)
            continue
        for name in names:
            v = step.values[name]
            pooled[name].append(v[:: max(1, v.size // _SAMPLE)])
            lo, hi = extremes.get(name, (np.inf, -np.inf))
            if v.size:
                extremes[name] = (min(lo, float(v.min())), max(hi, float(v.max())))
        if i in needed:
            kept[i] = step
    if not names:
        raise CheckpointError(f"{entries[0][1].parent}: no readable step")
    ranges = {name: _robust_range(np.concatenate(pooled[name]), name) for name in names}
    return _Loaded(dim, names, kept, ranges, extremes, bad)


def _load_reporting(entries, field, req, unit, animation, max_frames):
    """:func:`_load_picked`, its warnings reported as the caller's."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        picked = _load_picked(entries, field, req, unit, animation, max_frames)
    for w in caught:
        warn_user(str(w.message), w.category)
    return picked


def _load_picked(entries, field, req, unit, animation, max_frames):
    """Read the steps; pick the snapshots and frames among the readable ones."""
    ts = np.array([t for t, _ in entries])
    snaps = _pick_snapshots(ts, req, unit)
    n_frames = 0 if animation == "none" else max_frames
    frames = list(_frame_indices(len(ts), n_frames)) if n_frames else []
    loaded = _load(entries, field, set(snaps) | set(frames))
    if loaded.bad:  # pick again among the readable steps (rare)
        entries = [e for k, e in enumerate(entries) if k not in set(loaded.bad)]
        ts = np.array([t for t, _ in entries])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # said on the first pass
            snaps = _pick_snapshots(ts, req, unit)
            frames = list(_frame_indices(len(ts), n_frames)) if n_frames else []
            loaded = _load(entries, field, set(snaps) | set(frames))
        loaded.bad = []
    return loaded, entries, snaps, frames
