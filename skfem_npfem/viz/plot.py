"""Off-screen pictures of a result folder: PNG snapshots and a GIF/MP4 animation.

:func:`plot_results` reads the ``result.pvd`` collection written by
:class:`skfem_npfem.io.ResultWriter` (and the ``scene.json`` the scene runner puts
next to it).  2D results are drawn with matplotlib (:mod:`skfem_npfem.viz.figures`:
axes in metres, the scene's floor, walls and footing, the initial outline, the
collapse's run-out against Lube et al. 2005, the footing's load-settlement
curve); 3D results are rendered with pyvista/VTK without a display.  A step
file that cannot be read is skipped with a warning.

Needs the ``viz`` extra (``pip install 'skfem-npfem[viz]'``): pyvista, matplotlib
(colour maps), imageio (GIF; frames are encoded through Pillow, which imageio
depends on) and imageio-ffmpeg (MP4).  The drawing itself is done by
:mod:`skfem_npfem.viz.render`: on Linux without ``DISPLAY`` VTK is told to use EGL,
which works on a headless machine with Mesa's ``libegl1``/``libegl-mesa0``, and
a failed test render raises :class:`~skfem_npfem.errors.NpfemError` that says
what is missing.
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..constants import GRAVITY
from ..errors import CheckpointError, ParameterError
from ..io import atomic_path, check_writable_dir, read_pvd, read_step
from .figures import Frames2D, crop, load_settlement_figure
from .render import (
    Renderer,
    Step,
    Style,
    check_rendering,
    import_pyvista,
    write_animation,
)
from .scenery import scenery

__all__ = ["FIELDS", "plot_results"]

#: Fields :func:`plot_results` can draw, with a short description.
FIELDS: dict[str, str] = {
    "stress_xx": "normal stress xx (tension +)",
    "stress_yy": "normal stress yy (tension +)",
    "stress_zz": "normal stress zz (tension +)",
    "stress_xy": "shear stress xy",
    "stress_yz": "shear stress yz (3D only)",
    "stress_zx": "shear stress zx (3D only)",
    "pressure": "pressure, -mean normal stress (compression +)",
    "plastic_strain_eq": "equivalent plastic strain",
    "velocity": "velocity magnitude",
    "displacement": "displacement magnitude",
}

_STRESS_INDEX = {
    "stress_xx": 0,
    "stress_yy": 1,
    "stress_zz": 2,
    "stress_xy": 3,
    "stress_yz": 4,
    "stress_zx": 5,
}
_UNITS = {"plastic_strain_eq": "-", "velocity": "m/s", "displacement": "m"}
_ANIMATIONS = ("gif", "mp4", "none")
_DEFAULT_FIELD = "stress_yy"
_GRAVITY = GRAVITY
#: Values per step pooled for the colour range, and the share cut at each end.
_SAMPLE, _TAIL = 4000, 0.01
#: Top of the plastic-strain colour range: this quantile of the plastic values.
_PLASTIC_QUANTILE = 0.95
#: Smallest top of the colour range of the plastic strain (round-off below it).
_EPS_P_FLOOR = 1e-6


def _find_pvd(result_dir: Path) -> Path:
    """Return the ``.pvd`` collection of a result folder."""
    if result_dir.is_file() and result_dir.suffix == ".pvd":
        return result_dir
    if not result_dir.is_dir():
        raise CheckpointError(f"{result_dir}: result folder does not exist")
    pvd = result_dir / "result.pvd"
    if pvd.is_file():
        return pvd
    found = sorted(result_dir.glob("*.pvd"))
    if len(found) == 1:
        return found[0]
    what = "no result.pvd" if not found else "several .pvd files and no result.pvd"
    raise CheckpointError(
        f"{result_dir}: {what}; not a result folder written by "
        "'skfem-npfem run SCENE --out DIR'"
    )


def _field_values(name: str, pdata: Mapping[str, np.ndarray]) -> np.ndarray:
    """Return the (N,) values of field ``name`` from VTU point data."""
    if name in _STRESS_INDEX or name == "pressure":
        key = "stress"
    elif name in ("velocity", "displacement", "plastic_strain_eq"):
        key = name
    else:  # pragma: no cover - names are checked before
        raise ParameterError("field", name, "one of " + ", ".join(FIELDS))
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


def _robust_range(values: np.ndarray, name: str = "") -> tuple[float, float]:
    """Range of pooled values without the outermost 1 % on either side.

    Plastic strain: 0 up to the 95th percentile of the plastic values (those
    above 1e-6 of the largest), so that a thin band of very large strains (the
    grains sliding on the floor) does not leave the body in one colour.
    """
    if not values.size:
        return 0.0, 0.0
    if name == "plastic_strain_eq":
        plastic = values[values > 1e-6 * values.max()]
        if plastic.size:
            return 0.0, float(np.quantile(plastic, _PLASTIC_QUANTILE))
        return 0.0, float(values.max())
    lo, hi = np.quantile(values, [_TAIL, 1 - _TAIL])
    return float(lo), float(hi)


def _extend(style: Style, lo: float, hi: float) -> str:
    """Colour bar arrows for values beyond the range (SI values lo..hi)."""
    a, b = (v * style.scale for v in style.clim)
    tol = 1e-9 * max(abs(a), abs(b), 1e-300)
    low, high = lo < a - tol, hi > b + tol
    return {(0, 0): "neither", (1, 0): "min", (0, 1): "max"}.get(
        (int(low), int(high)), "both"
    )


def _style(name: str, lo: float, hi: float, fixed: bool = False) -> Style:
    """Colour range, colour map and unit scale of a field.

    With ``fixed`` the range ``lo..hi`` (SI units) is used as given.
    """
    if name in _STRESS_INDEX or name == "pressure":
        big = max(abs(lo), abs(hi))
        scale, unit = next(
            ((s, u) for s, u in ((1e6, "MPa"), (1e3, "kPa")) if big >= s),
            (1.0, "Pa"),
        )
        if fixed and hi > lo:
            cmap = "coolwarm" if lo < 0 < hi else "viridis"
            return Style((lo / scale, hi / scale), cmap, scale, unit)
        if big == 0:
            return Style((-1.0, 1.0), "coolwarm", scale, unit)
        if hi <= 0.05 * big:  # (nearly) compression only: min..0
            return Style((lo / scale, 0.0), "viridis", scale, unit)
        if lo >= -0.05 * big:  # (nearly) tension only: 0..max
            return Style((0.0, hi / scale), "viridis", scale, unit)
        return Style((-big / scale, big / scale), "coolwarm", scale, unit)
    cmap = "plasma" if name == "plastic_strain_eq" else "viridis"
    if fixed and hi > lo:
        return Style((lo, hi), cmap, 1.0, _UNITS[name])
    top = max(hi, _EPS_P_FLOOR) if name == "plastic_strain_eq" else hi
    if not top > 0:
        top = 1.0
    return Style((0.0, top), cmap, 1.0, _UNITS[name])


def _time_label(value: float) -> str:
    """Short decimal text of a time for file names (4 significant digits)."""
    return np.format_float_positional(
        value, precision=4, unique=True, fractional=False, trim="-"
    )


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


def _frame_indices(n: int, max_frames: int) -> np.ndarray:
    """Evenly spread step indices (first and last included), at most max_frames."""
    if n <= max_frames:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, max_frames)).astype(int))


def _check_args(
    animation: str,
    max_frames: int,
    window_size: tuple[int, int] | None,
    clim: Mapping[str, tuple[float, float]] | None,
    times: Sequence[float] | None,
) -> list[float] | None:
    """Validate the plain arguments of plot_results; return the times as floats."""
    if animation not in _ANIMATIONS:
        raise ParameterError("animation", animation, "one of gif, mp4, none")
    if (
        isinstance(max_frames, bool)
        or not isinstance(max_frames, int | np.integer)
        or max_frames < 1
    ):
        raise ParameterError("max_frames", max_frames, "an integer >= 1")
    if window_size is not None:
        try:
            ok = len(window_size) == 2 and all(
                int(v) == v and v >= 200 for v in window_size
            )
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise ParameterError(
                "window_size", window_size, "(width, height), integers >= 200"
            )
    for name, pair in (clim or {}).items():
        try:
            lo, hi = (float(v) for v in pair)
            ok = name in FIELDS and math.isfinite(lo) and math.isfinite(hi) and lo < hi
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise ParameterError(
                f"clim[{name!r}]", pair, "a field name -> finite (lo, hi), lo < hi"
            )
    if times is None:
        return None
    try:
        req = [float(t) for t in np.ravel(np.asarray(times, dtype=float))]
    except (TypeError, ValueError):
        req = [math.nan]
    if not all(math.isfinite(t) for t in req):
        raise ParameterError("times", times, "finite numbers")
    return req


def _pick_snapshots(
    ts: np.ndarray, req: list[float] | None, tau: float | None
) -> dict[int, float]:
    """Map step index -> time label (in the unit of the request) of each snapshot.

    ``tau`` is ``sqrt(H0/g)`` when the requested times are normalised.
    """
    unit = 1.0 if tau is None else tau
    if not req:  # 5 evenly spaced times, labelled with the step times
        picks = (np.argmin(np.abs(ts - t)) for t in np.linspace(ts[0], ts[-1], 5))
        return {int(i): float(ts[i] / unit) for i in dict.fromkeys(picks)}
    dt = float(np.median(np.diff(ts))) if len(ts) > 1 else 0.0
    snaps: dict[int, float] = {}
    for label in req:
        t_s = label * unit
        i = int(np.argmin(np.abs(ts - t_s)))
        if abs(ts[i] - t_s) > 0.5 * dt + 1e-9 * max(1.0, abs(t_s)):
            warnings.warn(
                f"time {label:g} is outside the stored steps "
                f"({ts[0]:.4g}..{ts[-1]:.4g} s); drawing the step at t = {ts[i]:.4g} s",
                UserWarning,
                stacklevel=3,
            )
        snaps.setdefault(i, label)
    return snaps


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
            warnings.warn(f"skipped an unreadable step: {err}", UserWarning, 3)
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


def plot_results(
    result_dir: str | os.PathLike,
    times: Sequence[float] | None = None,
    normalised: bool = True,
    field: str | Sequence[str] = "stress_yy",
    animation: str = "gif",
    out_dir: str | os.PathLike | None = None,
    *,
    window_size: tuple[int, int] | None = None,
    max_frames: int = 150,
    clim: Mapping[str, tuple[float, float]] | None = None,
) -> list[Path]:
    """Render PNG snapshots and an animation of a result folder, off-screen.

    Parameters
    ----------
    result_dir : str or os.PathLike
        Folder written by ``skfem-npfem run SCENE --out DIR`` (holding
        ``result.pvd``, the VTU steps and usually ``scene.json``), or the
        ``.pvd`` file itself.
    times : sequence of float or None, default None
        Snapshot times; each picks the nearest stored step (steps picked twice
        are drawn once). With ``normalised``, times are ``t / sqrt(H0 / g)`` with
        ``H0 = aspect * length`` and ``g = gravity`` (9.81 m/s² if absent) from
        ``scene.json``; if the folder has no such parameters the times are
        absolute seconds and a ``UserWarning`` says so. None or empty: 5 times
        evenly spaced from the first to the last step.
    normalised : bool, default True
        Whether ``times`` are normalised (see above) or in seconds.
    field : str or sequence of str, default "stress_yy"
        Field(s) to draw, see :data:`FIELDS`: ``stress_xx``, ``stress_yy``,
        ``stress_zz``, ``stress_xy`` (``stress_yz``, ``stress_zx`` in 3D), in Pa
        with tension positive; ``pressure`` (minus the mean normal stress);
        ``plastic_strain_eq``; ``velocity`` and ``displacement`` (magnitudes).
        The default string ``"stress_yy"`` draws the vertical stress
        (``stress_yy`` in 2D, ``stress_zz`` in 3D) *and* ``plastic_strain_eq``;
        pass a list (``["stress_yy"]``) or a comma-separated string
        (``"stress_yy,velocity"``) to choose exactly.
    animation : {"gif", "mp4", "none"}, default "gif"
        Animation over all steps (evenly thinned to ``max_frames``) of every
        field drawn. GIF frames are shrunk to at most 720 px; MP4 needs
        imageio-ffmpeg.
    out_dir : str or os.PathLike or None, default None
        Output folder, ``result_dir / "plots"`` if None; created if needed.
    window_size : (int, int) or None, default None
        Image size ``(width, height)`` in pixels, at least 200 each. None: a
        size that fits the view of the domain (union of all steps) plus text
        and colour bar (2D: 1100 px wide, 1500 with the footing's curve, at
        most 1104 high; 3D: at most 1024 x 1024), multiples of 16.
    max_frames : int, default 150
        Most frames per animation.
    clim : mapping of str to (float, float) or None, default None
        Colour range per field name in SI units (Pa, m, m/s, -), instead of the
        automatic range, e.g. ``{"stress_yy": (-20e3, 0)}`` to compare runs.

    Returns
    -------
    list of pathlib.Path
        Files written, per field: ``<field>_t<time>.png`` per snapshot (time
        as requested, in the unit of ``times``, up to 4 significant digits),
        then ``<field>.gif`` or ``<field>.mp4``; for the strip footing (2D)
        finally ``load_settlement.png``.

    Raises
    ------
    CheckpointError
        If the folder has no ``result.pvd``, no steps, or lacks a field's data.
    ParameterError
        If an argument is invalid.
    NpfemError
        If pyvista is not installed or off-screen rendering is impossible.

    Notes
    -----
    2D results (matplotlib, :mod:`skfem_npfem.viz.figures`): axes in metres with
    equal scales, cells coloured by the field (thin mesh edges up to 4000
    cells), particles in no cell (``active == 0``) as dots in the same colours,
    and the scenery of ``scene.json`` (:mod:`skfem_npfem.viz.scenery`): the floor
    or fixed base, walls, the footing at its current settlement, the symmetry
    axis, the initial outline; for the collapse the run-out (99 % mass front)
    of the step and the final run-out of Lube et al. (2005); for the strip
    footing the load-settlement curve beside the field with the step marked
    (and ``load_settlement.png`` on its own), and the settlement instead of
    the pseudo-time in titles.  The frame is cropped to the meshed body over
    all steps (grains that flew off may lie outside).  3D results are shown
    in an isometric view (pyvista, surface of the tetrahedra).  The colour
    range is the same in every picture of a field, over all stored steps: for
    stresses the 1-99 % range, ``min..0`` (compression only), ``0..max``
    (tension only) or symmetric, in Pa/kPa/MPa; for magnitudes ``0..max``; for
    plastic strain ``0`` to the 95th percentile of the plastic values (a thin
    band of very large strains, e.g. on the floor, does not swamp the body; at
    least 1e-6, so round-off is not coloured).  Arrows on the colour bar show
    values beyond its range.  A step file that cannot be read is skipped with
    a warning naming it.

    Examples
    --------
    >>> from skfem_npfem.viz.plot import plot_results
    >>> paths = plot_results("out", times=[0, 1, 2, 4])  # doctest: +SKIP
    """
    req = _check_args(animation, max_frames, window_size, clim, times)
    pvd = _find_pvd(Path(result_dir))
    folder = pvd.parent
    entries = read_pvd(pvd)
    if not entries:
        raise CheckpointError(f"{pvd}: the collection lists no steps")
    sc = scenery(folder)
    if normalised and sc.tau is None and req:
        warnings.warn(
            f"{folder}: scene.json has no 'aspect' and 'length' parameters, so "
            "times are taken as absolute seconds instead of t/sqrt(H0/g)",
            UserWarning,
            stacklevel=2,
        )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        loaded, entries, snaps, frames = _load_picked(
            entries, field, req, sc.tau if normalised else None, animation, max_frames
        )
    for w in caught:
        warnings.warn(str(w.message), w.category, stacklevel=2)
    out = folder / "plots" if out_dir is None else Path(out_dir)
    ts = np.array([t for t, _ in entries])
    if loaded.dim == 3:
        pv = import_pyvista()
        check_rendering()
    else:
        view = crop(list(loaded.kept.values()), sc, window_size)
    check_writable_dir("out_dir", out)

    written: list[Path] = []
    for name in loaded.names:
        fixed = clim is not None and name in clim
        lo, hi = (float(v) for v in clim[name]) if fixed else loaded.ranges[name]
        style = _style(name, lo, hi, fixed=fixed)
        what = sc.field_names.get(name, FIELDS[name])
        title = f"{sc.scene + ': ' if sc.scene else ''}{what}"

        def make(fast: bool, name=name, style=style, title=title, what=what):
            if loaded.dim == 2:
                label = f"{what} [{style.unit}]"
                ext = _extend(style, *loaded.extremes.get(name, (0.0, 0.0)))
                return Frames2D(loaded.kept, name, style, title, label, sc, view, ext)
            return Renderer(
                pv,
                loaded.kept,
                3,
                name,
                style,
                title,
                sc.tau,
                window_size,
                fast=fast,
                view=sc.view,
                floor=sc.floor,
            )

        renderer = make(False)
        try:
            for i in sorted(snaps, key=lambda k: ts[k]):
                path = out / f"{name}_t{_time_label(snaps[i])}.png"
                renderer.draw(i)
                renderer.image(path)
                written.append(path)
        finally:
            renderer.close()
        if animation != "none":
            renderer = make(True)
            try:
                path = out / f"{name}.{animation}"
                write_animation(renderer, frames, path, animation)
                written.append(path)
            finally:
                renderer.close()
    if loaded.dim == 2 and sc.load_curve is not None:
        path = out / "load_settlement.png"
        fig = load_settlement_figure(sc)
        fig.canvas.draw()
        _save_rgb(np.asarray(fig.canvas.buffer_rgba())[..., :3], path)
        written.append(path)
    return written


def _load_picked(entries, field, req, tau, animation, max_frames):
    """Read the steps; pick the snapshots and frames among the readable ones."""
    ts = np.array([t for t, _ in entries])
    snaps = _pick_snapshots(ts, req, tau)
    n_frames = 0 if animation == "none" else max_frames
    frames = list(_frame_indices(len(ts), n_frames)) if n_frames else []
    loaded = _load(entries, field, set(snaps) | set(frames))
    if loaded.bad:  # pick again among the readable steps (rare)
        entries = [e for k, e in enumerate(entries) if k not in set(loaded.bad)]
        ts = np.array([t for t, _ in entries])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # said on the first pass
            snaps = _pick_snapshots(ts, req, tau)
            frames = list(_frame_indices(len(ts), n_frames)) if n_frames else []
            loaded = _load(entries, field, set(snaps) | set(frames))
        loaded.bad = []
    return loaded, entries, snaps, frames


def _save_rgb(img: np.ndarray, path: Path) -> None:
    from PIL import Image

    with atomic_path(path) as tmp:
        Image.fromarray(img).save(tmp, format="PNG")
