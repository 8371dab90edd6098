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
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..errors import CheckpointError, ParameterError, warn_user
from ..io import check_writable_dir, read_pvd
from .animation import write_animation
from .colours import (
    _extend,
    _style,
)
from .figures import Frames2D, crop, factor_curve_figure, load_settlement_figure
from .loading import (
    FIELDS,
    _load_reporting,
)
from .mechanism import plot_mechanism, save_rgb
from .render import (
    Renderer,
    check_rendering,
    import_pyvista,
)
from .scenery import scenery
from .snapshots import (
    _time_label,
    _time_unit,
)

__all__ = ["plot_results"]

_ANIMATIONS = ("gif", "mp4", "none")


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
        ``H0 = aspect * half_width`` and ``g = gravity`` (9.81 m/s² if absent) from
        ``scene.json``; if the folder has no such parameters the times are
        absolute seconds and a ``UserWarning`` says so. For the strip footing
        the times are settlements in m (its pseudo-time), for the cone the
        penetration w/D (``footing-penetration``: w/B), whatever
        ``normalised``. A time outside the
        stored steps draws the nearest step, with a ``UserWarning`` in the
        same unit, and is labelled with that step's time. None or empty: 5
        times evenly spaced from the first to the last step.
    normalised : bool, default True
        Whether ``times`` are normalised (see above) or in seconds.
    field : str or sequence of str, default "stress_yy"
        Field(s) to draw, see :data:`FIELDS`: ``stress_xx``, ``stress_yy``,
        ``stress_zz``, ``stress_xy`` (``stress_yz``, ``stress_zx`` in 3D), in Pa
        with tension positive (with pore water: the effective stress);
        ``pressure`` (minus the mean normal stress); ``pore_pressure`` and
        ``excess_pore_pressure`` (Pa, compression positive; results with pore
        water only); ``plastic_strain_eq``; ``velocity`` and ``displacement``
        (magnitudes).
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
        in the unit of ``times``, up to 4 significant digits: as requested, or
        the drawn step's time when the request is outside the stored steps;
        ``<field>_s<settlement>.png`` for the strip footing, settlement in m;
        ``<field>_wD<w/D>.png`` for the cone, ``<field>_wB<w/B>.png`` for
        ``footing-penetration``), then ``<field>.gif`` or
        ``<field>.mp4``; for the strip footing (2D) finally
        ``load_settlement.png``, for the cone ``cone_factor.png`` (N_c against
        w/D and the depth pushed), for a limit analysis ``mechanism.png``.

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
    equal scales, cells coloured by the field (thin mesh edges up to 4000 cells),
    particles in no cell (``active == 0``: detached grains) as black-edged diamonds
    in the same colours, counted in the legend, and the scenery of ``scene.json``
    (:mod:`skfem_npfem.viz.scenery`): the floor or fixed base, walls, the footing at
    its current settlement, the symmetry axis, the initial outline; for the collapse
    the run-out (99 % mass front) of the step and the final run-out of Lube et al.
    (2005); for the strip footing the load-settlement curve beside the field with
    the step marked (and ``load_settlement.png`` on its own), and the settlement
    instead of the pseudo-time in titles; for the cone a window a few D around
    the tip's path (said in the title) and its N_c-w/D curve beside the field;
    for the slope the section's supports and the boundaries between its layers;
    for a run with pore water its water table (the ``water_level`` of
    ``scene.json`` across the picture, or a section's water line; in 3D a
    translucent blue plane at the level).
    The frame holds every particle of the drawn steps (detached grains
    included) and everything the legend names (the cone: its window). 3D
    results are shown in an isometric view (pyvista, surface of the tetrahedra). The
    colour range is the same in every picture of a field, over all stored steps: for
    stresses the 1-99 % range, ``min..0`` (compression only), ``0..max`` (tension
    only) or symmetric, in Pa/kPa/MPa; for magnitudes ``0..max``; for plastic strain
    ``0`` to the 95th percentile of the plastic values (a thin band of very large
    strains, e.g. on the floor, does not swamp the body; at least 1e-6, so round-off
    is not coloured). Arrows on the colour bar show values beyond its range. A step
    file that cannot be read is skipped with a warning naming it.

    Examples
    --------
    >>> from skfem_npfem.viz.plot import plot_results
    >>> paths = plot_results("out", times=[0, 1, 2, 4])  # doctest: +SKIP
    """
    req = _check_args(animation, max_frames, window_size, clim, times)
    pvd = _find_pvd_or_mechanism(Path(result_dir))
    if pvd.name == "mechanism.npz":  # a limit analysis alone: its mechanism
        out = pvd.parent / "plots" if out_dir is None else out_dir
        return [plot_mechanism(pvd, out, scenery(pvd.parent))]
    folder = pvd.parent
    entries = read_pvd(pvd)
    if not entries:
        raise CheckpointError(f"{pvd}: the collection lists no steps")
    sc = scenery(folder)
    unit = _time_unit(sc, normalised)
    if normalised and sc.tau is None and sc.footing is None and sc.unit is None and req:
        warn_user(
            f"{folder}: scene.json has no 'aspect' and 'half_width' parameters, so "
            "times are taken as absolute seconds instead of t/sqrt(H0/g)",
        )
    loaded, entries, snaps, frames = _load_reporting(
        entries, field, req, unit, animation, max_frames
    )
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
                water=sc.water_level,
            )

        stem = f"{name}_{unit.prefix}"
        written += _render_field(make, snaps, ts, frames, out, stem, name, animation)
    return written + _extra_pictures(folder, sc, out, loaded.dim)


def _render_field(make, snaps, ts, frames, out, stem, name, animation) -> list[Path]:
    """One field's snapshots (``<stem><time>.png``) and its animation."""
    written = []
    renderer = make(False)
    try:
        for i in sorted(snaps, key=lambda k: ts[k]):
            path = out / f"{stem}{_time_label(snaps[i])}.png"
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
    return written


def _find_pvd_or_mechanism(result_dir: Path) -> Path:
    """The folder's ``result.pvd``, else its ``mechanism.npz`` (a limit analysis)."""
    try:
        return _find_pvd(result_dir)
    except CheckpointError:
        if not (result_dir / "mechanism.npz").is_file():
            raise
        return result_dir / "mechanism.npz"


def _extra_pictures(folder: Path, sc, out: Path, dim: int) -> list[Path]:
    """The footing's load-settlement curve, the cone's factor, the mechanism."""
    written = []
    curves = (
        (sc.factor_curve, "cone_factor.png", factor_curve_figure),
        (sc.load_curve, "load_settlement.png", load_settlement_figure),
    )
    for curve, name, figure in curves:
        if dim == 2 and curve is not None:
            fig = figure(sc)
            fig.canvas.draw()
            save_rgb(np.asarray(fig.canvas.buffer_rgba())[..., :3], out / name)
            written.append(out / name)
    if (folder / "mechanism.npz").is_file():
        written.append(plot_mechanism(folder / "mechanism.npz", out, sc))
    return written
