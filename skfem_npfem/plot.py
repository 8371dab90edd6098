"""Off-screen pictures of a result folder: PNG snapshots and a GIF/MP4 animation.

:func:`plot_results` reads the ``result.pvd`` collection written by
:class:`skfem_npfem.io.ResultWriter` (and the ``scene.json`` the scene runner puts
next to it), and renders with pyvista/VTK without a display.

Needs the ``viz`` extra (``pip install 'skfem-npfem[viz]'``): pyvista, matplotlib
(colour maps), imageio (GIF; frames are encoded through Pillow, which imageio
depends on) and imageio-ffmpeg (MP4). On Linux without ``DISPLAY``, VTK is told
to use EGL (``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow``, unless already
set), which works on a headless machine with Mesa's ``libegl1``/``libegl-mesa0``.
Before the first picture a tiny test render runs in a child process, because
VTK crashes the whole interpreter (segmentation fault) instead of raising when
it cannot get an OpenGL context; a failed test render raises
:class:`~skfem_npfem.errors.NpfemError` that says what is missing.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import subprocess
import sys
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .errors import CheckpointError, NpfemError, ParameterError
from .io import read_pvd, read_step

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
_GRAVITY = 9.81
#: Values per step pooled for the colour range, and the share cut at each end.
_SAMPLE, _TAIL = 4000, 0.01
#: Smallest top of the colour range of the plastic strain (round-off below it).
_EPS_P_FLOOR = 1e-6
#: Longest side of GIF frames in pixels (snapshots and MP4 keep the full size).
_GIF_MAX_SIDE = 720
#: Pixels kept free for the text lines (top) and the colour bar (bottom) in 2D.
_TOP, _BOTTOM = 72, 136
_ANSI = re.compile(r"\x1b\[[0-9;]*m")
_VTK_LOG = re.compile(r"^.*?\b(?:WARN|ERR)\|\s*")

_PROBE_CODE = """
import vtkmodules.vtkRenderingOpenGL2
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkRenderingCore import (
    vtkActor, vtkPolyDataMapper, vtkRenderer, vtkRenderWindow, vtkWindowToImageFilter
)
win = vtkRenderWindow()
win.SetOffScreenRendering(1)
win.SetSize(32, 32)
ren = vtkRenderer()
win.AddRenderer(ren)
src = vtkSphereSource()
mapper = vtkPolyDataMapper()
mapper.SetInputConnection(src.GetOutputPort())
actor = vtkActor()
actor.SetMapper(mapper)
ren.AddActor(actor)
win.Render()
grab = vtkWindowToImageFilter()
grab.SetInput(win)
grab.Update()
img = vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars())
assert img.size and img.std() > 0, "blank test image"
"""
_probe_ok = False


@dataclass
class _Step:
    """One stored step reduced to what the pictures need."""

    time: float
    points: np.ndarray  # (N, 3)
    cells: np.ndarray  # (ne, 3) triangles or (ne, 4) tetrahedra
    free: np.ndarray  # indices of particles drawn as points
    values: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)


@dataclass
class _Style:
    """Colour range, colour map and unit of one field."""

    clim: tuple[float, float]
    cmap: str
    scale: float
    unit: str


def _set_headless_backend() -> None:
    """Point VTK at EGL on a Linux machine without a display (unless set)."""
    if sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    ):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


def _import_pyvista() -> Any:
    """Import pyvista for off-screen use or raise NpfemError."""
    _set_headless_backend()
    try:
        import pyvista as pv
    except ImportError as err:
        raise NpfemError(
            "plotting needs pyvista (pip install 'skfem-npfem[viz]'): " + str(err)
        ) from None
    return pv


def _check_rendering() -> None:
    """Run a tiny off-screen render in a child process once per process.

    Raises
    ------
    NpfemError
        If the test render fails or crashes (no OpenGL context available).
    """
    global _probe_ok
    if _probe_ok:
        return
    try:
        proc = subprocess.run(
            [sys.executable, "-c", _PROBE_CODE],
            capture_output=True,
            text=True,
            timeout=180,
            env=os.environ.copy(),
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired) as err:
        raise NpfemError(f"off-screen rendering test could not run: {err}") from None
    if proc.returncode != 0:
        lines = [
            _VTK_LOG.sub("", _ANSI.sub("", ln)).strip()
            for ln in proc.stderr.splitlines()
            if ln.strip() and ("WARN" in ln or "ERR" in ln or "Error" in ln)
        ]
        said = "; ".join(dict.fromkeys(lines[-4:])) or "no message"
        how = (
            f"crashed with signal {-proc.returncode}"
            if proc.returncode < 0
            else f"failed with exit code {proc.returncode}"
        )
        backend = os.environ.get("VTK_DEFAULT_OPENGL_WINDOW", "VTK's default")
        raise NpfemError(
            f"off-screen rendering is not possible here: a VTK test render "
            f"({backend}) {how}. VTK needs an OpenGL context without a display: "
            "install EGL (Debian/Ubuntu: apt-get install libegl1 libegl-mesa0) "
            "or OSMesa (libosmesa6) and set VTK_DEFAULT_OPENGL_WINDOW to "
            "vtkEGLRenderWindow or vtkOSMesaRenderWindow, or run with a display. "
            f"VTK said: {said}"
        )
    _probe_ok = True


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


def _scene_info(folder: Path) -> tuple[str, float | None]:
    """Return ``(scene name, sqrt(H0/g) or None)`` from ``folder/scene.json``."""
    try:
        info = json.loads((folder / "scene.json").read_text())
        params = info.get("parameters", {})
        name = str(info.get("scene", ""))
    except (OSError, ValueError, AttributeError):
        return "", None
    try:
        h0 = float(params["aspect"]) * float(params["length"])
        g = float(params.get("gravity", _GRAVITY))
    except (KeyError, TypeError, ValueError):
        return name, None
    if not (math.isfinite(h0) and h0 > 0 and math.isfinite(g) and g > 0):
        return name, None
    return name, math.sqrt(h0 / g)


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


def _read(path: Path, time: float, fields: Sequence[str]) -> tuple[_Step, int]:
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
    step = _Step(time, points, cells, np.flatnonzero(~in_cell))
    for name in fields:
        if dim == 2 and name in ("stress_yz", "stress_zx"):
            raise ParameterError("field", name, "a field of 2D results (3D only)")
        step.values[name] = _field_values(name, mesh.point_data)
    return step, dim


def _robust_range(values: np.ndarray) -> tuple[float, float]:
    """Range of pooled values without the outermost 1 % on either side."""
    if not values.size:
        return 0.0, 0.0
    lo, hi = np.quantile(values, [_TAIL, 1 - _TAIL])
    return float(lo), float(hi)


def _style(name: str, lo: float, hi: float, fixed: bool = False) -> _Style:
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
            return _Style((lo / scale, hi / scale), cmap, scale, unit)
        if big == 0:
            return _Style((-1.0, 1.0), "coolwarm", scale, unit)
        if hi <= 0.05 * big:  # (nearly) compression only: min..0
            return _Style((lo / scale, 0.0), "viridis", scale, unit)
        if lo >= -0.05 * big:  # (nearly) tension only: 0..max
            return _Style((0.0, hi / scale), "viridis", scale, unit)
        return _Style((-big / scale, big / scale), "coolwarm", scale, unit)
    cmap = "plasma" if name == "plastic_strain_eq" else "viridis"
    if fixed and hi > lo:
        return _Style((lo, hi), cmap, 1.0, _UNITS[name])
    top = max(hi, _EPS_P_FLOOR) if name == "plastic_strain_eq" else hi
    if not top > 0:
        top = 1.0
    return _Style((0.0, top), cmap, 1.0, _UNITS[name])


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


def _round16(x: float) -> int:
    return int(16 * math.ceil(x / 16))


def _window_size(width: float, height: float) -> tuple[int, int]:
    """Window size (multiples of 16) that fits a width x height picture."""
    width, height = max(width, 1e-3 * height, 1e-12), max(height, 1e-3 * width, 1e-12)
    w = 1024
    h = _TOP + _BOTTOM + 0.9 * w * height / width
    if h > 1024:
        h = 1024
        w = max(640, min(1024, (1024 - _TOP - _BOTTOM) * width / height / 0.9))
    return _round16(w), _round16(max(h, 480))


def _grid(pv: Any, step: _Step, dim: int, values: np.ndarray) -> Any:
    """A pyvista UnstructuredGrid of the step's cells with point data 'value'."""
    ctype = pv.CellType.TETRA if dim == 3 else pv.CellType.TRIANGLE
    if len(step.cells):
        grid = pv.UnstructuredGrid({ctype: step.cells}, step.points)
    else:
        grid = pv.UnstructuredGrid()
        grid.points = step.points
    grid.point_data["value"] = values
    grid.set_active_scalars("value")
    return grid


class _Renderer:
    """One off-screen plotter showing one field; draws any step on demand.

    ``fast`` switches off multisample anti-aliasing (for animation frames).
    """

    def __init__(
        self,
        pv: Any,
        steps: dict[int, _Step],
        dim: int,
        name: str,
        style: _Style,
        title: str,
        tau: float | None,
        window_size: tuple[int, int] | None,
        fast: bool = False,
    ) -> None:
        self.pv, self.steps, self.dim, self.name = pv, steps, dim, name
        self.style, self.title, self.tau = style, title, tau
        pts = np.vstack([s.points for s in steps.values()])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        size = hi - lo
        # screen axes: 2D looks down -z; 3D is an isometric view with z up
        if dim == 2:
            view_dir, up = np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0])
        else:
            view_dir = np.ones(3) / math.sqrt(3.0)
            up = np.array([0.0, 0.0, 1.0]) - view_dir / math.sqrt(3.0)
            up /= np.linalg.norm(up)
        right = np.cross(up, view_dir)
        corners = np.array(
            [
                [x, y, z]
                for x in (lo[0], hi[0])
                for y in (lo[1], hi[1])
                for z in (lo[2], hi[2])
            ]
        )
        extent = np.ptp(corners @ right), np.ptp(corners @ up)
        if window_size is None:
            window_size = _window_size(*extent)
        self.size = (int(window_size[0]), int(window_size[1]))
        w, h = self.size
        band = h - _TOP - _BOTTOM
        scale = min(0.9 * w / max(extent[0], 1e-12), band / max(extent[1], 1e-12))
        first = steps[min(steps)]
        spacing = self._spacing(steps)
        n_cells = max(len(s.cells) for s in steps.values())
        show_edges = bool(n_cells <= 20000 and spacing * scale >= 14)
        self.point_size = float(np.clip(0.6 * spacing * scale, 3, 20))

        pl = pv.Plotter(off_screen=True, window_size=self.size)
        if fast:  # no multisample anti-aliasing: 3x faster in software GL
            pl.ren_win.SetMultiSamples(0)
        self.pl = pl
        pl.set_background("white")
        fs = max(12, min(18, w // 48))
        bar_args = {
            "title": f"{name} [{style.unit}]",
            "vertical": False,
            "n_labels": 5,
            "fmt": "%.3g",
            "color": "black",
            "label_font_size": fs + 4,
            "unconstrained_font_size": True,
            "position_x": 0.2,
            "position_y": 10 / h,
            "width": 0.6,
            "height": 80 / h,
        }
        shading = (
            {"lighting": True, "ambient": 0.35, "diffuse": 0.65, "specular": 0.0}
            if dim == 3
            else {"lighting": False}
        )
        self.actor = pl.add_mesh(
            _grid(pv, first, dim, first.values[name] / style.scale),
            scalars="value",
            clim=style.clim,
            cmap=style.cmap,
            show_edges=show_edges,
            edge_color="#404040",
            line_width=0.5,
            scalar_bar_args=bar_args,
            render=False,
            **shading,
        )
        # labels under the bar, its title as a centred text above it
        bar = pl.scalar_bars[bar_args["title"]]
        bar.SetTextPositionToPrecedeScalarBar()
        bar.SetTitle("")
        bar.SetBarRatio(0.45)
        bar_title = pl.add_text(
            bar_args["title"], position=(w // 2, 98), font_size=fs - 2, color="black"
        )
        bar_title.GetTextProperty().SetJustificationToCentered()
        # header font: shrink so that the title (and the time line) fit
        chars = max(len(title), 48)
        header_fs = int(np.clip((w - 16) / (0.95 * chars), 8, fs - 2))
        self.text = pl.add_text(
            "", position=(8, h - 6), font_size=header_fs, color="black"
        )
        self.text.GetTextProperty().SetVerticalJustificationToTop()
        if dim == 3:
            pl.add_axes(
                color="black", viewport=(0.0, _BOTTOM / h, 0.15, 0.15 + _BOTTOM / h)
            )
        self.free_actors: list[Any] = []
        # 2D: sphere impostors shift depth by their radius, so the coloured
        # free particles are lifted well above their dark rims
        self.depth = 2 * spacing + 1e-3 * float(np.max(size)) if dim == 2 else 0.0

        # camera: parallel projection, the domain (union of all steps) centred
        # in the band between the colour bar and the two text lines
        pl.enable_parallel_projection()
        diag = float(np.linalg.norm(size)) + 1e-12
        focal = (lo + hi) / 2 - (_BOTTOM + band / 2 - h / 2) / scale * up
        dist = 2.0 * diag + 1.0
        cam = pl.camera
        cam.focal_point = tuple(focal)
        cam.position = tuple(focal + dist * view_dir)
        cam.up = tuple(up)
        cam.parallel_scale = h / (2 * scale)
        cam.clipping_range = (max(dist - 2 * diag, 1e-6), dist + 2 * diag)

    @staticmethod
    def _spacing(steps: dict[int, _Step]) -> float:
        """Median nearest-neighbour distance of the particles (first step)."""
        from scipy.spatial import cKDTree

        p = steps[min(steps)].points
        if len(p) < 2:
            return 0.0
        d, _ = cKDTree(p).query(p[:: max(1, len(p) // 5000)], k=2)
        return float(np.median(d[:, 1]))

    def draw(self, index: int) -> None:
        """Show step ``index`` (mesh, free particles and time text)."""
        pv, step, style = self.pv, self.steps[index], self.style
        values = step.values[self.name] / style.scale
        self.actor.mapper.dataset = _grid(pv, step, self.dim, values)
        for actor in self.free_actors:
            self.pl.remove_actor(actor, render=False)
        self.free_actors = []
        if len(step.free):
            pts = step.points[step.free]
            lift = [0.0, 0.0, self.depth if self.dim == 2 else 0.0]
            self.free_actors.append(
                self.pl.add_points(
                    pts + lift,
                    scalars=values[step.free],
                    clim=style.clim,
                    cmap=style.cmap,
                    render_points_as_spheres=True,
                    point_size=self.point_size,
                    show_scalar_bar=False,
                    lighting=False,
                    render=False,
                )
            )
            if self.dim == 2:  # dark rim, drawn behind (camera at +z)
                self.free_actors.append(
                    self.pl.add_points(
                        pts,
                        color="#303030",
                        render_points_as_spheres=True,
                        point_size=self.point_size + 3,
                        lighting=False,
                        render=False,
                    )
                )
        t = step.time
        when = f"t = {t:.4g} s"
        if self.tau is not None:
            when += f"     t/\u221a(H0/g) = {t / self.tau:.3f}"
        self.text.SetInput(f"{self.title}\n{when}")

    def image(self, path: Path | None = None) -> np.ndarray:
        """Render and return the RGB image (and save it as PNG if path given)."""
        self.pl.render()
        img = self.pl.screenshot(filename=None, return_img=True)
        if path is not None:
            from PIL import Image

            Image.fromarray(img).save(path)
        return img

    def close(self) -> None:
        self.pl.close()


def _write_animation(
    renderer: _Renderer, indices: Sequence[int], path: Path, kind: str
) -> None:
    """Write the frames of ``indices`` as a GIF or MP4."""
    fps = int(np.clip(round(len(indices) / 6), 4, 20))
    if kind == "mp4":
        try:
            import imageio.v2 as imageio
            import imageio_ffmpeg  # noqa: F401
        except ImportError as err:
            raise NpfemError(
                f"MP4 output needs imageio and imageio-ffmpeg ({err}); "
                "pip install 'skfem-npfem[viz]' or use animation='gif'"
            ) from None
        writer = imageio.get_writer(
            path, format="FFMPEG", fps=fps, macro_block_size=16, quality=7
        )
        try:
            for i in indices:
                renderer.draw(i)
                writer.append_data(renderer.image())
        finally:
            writer.close()
        return
    try:
        from PIL import Image  # installed with imageio
    except ImportError as err:
        raise NpfemError(
            f"GIF output needs Pillow ({err}); pip install 'skfem-npfem[viz]'"
        ) from None
    w, h = renderer.size
    shrink = min(1.0, _GIF_MAX_SIDE / max(w, h))
    frames = []
    for i in indices:
        renderer.draw(i)
        im = Image.fromarray(renderer.image())
        if shrink < 1:
            im = im.resize(
                (round(w * shrink), round(h * shrink)), Image.Resampling.BILINEAR
            )
        frames.append(im.quantize(256, method=Image.Quantize.FASTOCTREE))
    tmp = path.with_name(f".tmp_{path.name}")
    try:
        frames[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=frames[1:],
            duration=round(1000 / fps),
            loop=0,
            optimize=False,
        )
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


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


def _load(
    entries: list[tuple[float, Path]],
    field_arg: str | Sequence[str],
    needed: set[int],
) -> tuple[int, list[str], dict[int, _Step], dict[str, tuple[float, float]]]:
    """Read every step once.

    Returns
    -------
    dim : int
        Spatial dimension.
    names : list of str
        Fields to draw.
    kept : dict of int to _Step
        The steps in ``needed``.
    ranges : dict of str to (float, float)
        Colour range per field (robust range over all steps).
    """
    _, dim = _read(entries[0][1], entries[0][0], [])
    names = _resolve_fields(field_arg, dim)
    kept: dict[int, _Step] = {}
    pooled: dict[str, list[np.ndarray]] = {name: [] for name in names}
    for i, (t, path) in enumerate(entries):
        step, _ = _read(path, t, names)
        for name in names:
            v = step.values[name]
            pooled[name].append(v[:: max(1, v.size // _SAMPLE)])
        if i in needed:
            kept[i] = step
    ranges = {name: _robust_range(np.concatenate(pooled[name])) for name in names}
    return dim, names, kept, ranges


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
        and colour bar, at most 1024 x 1024, multiples of 16.
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
        then ``<field>.gif`` or ``<field>.mp4``.

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
    2D results are viewed from +z with equal axes, cells coloured by the field
    (mesh edges when cells are at least 8 px wide) and particles in no cell
    (``active == 0``) drawn as dots in the same colours. 3D results are shown
    in an isometric view (surface of the tetrahedra). The colour range is the
    same in every picture of a field: the range over all stored steps; for
    stresses ``min..0`` (compression only), ``0..max`` (tension only) or
    symmetric, in Pa/kPa/MPa; for magnitudes and plastic strain ``0..max``
    (plastic strain at least up to 1e-6, so round-off is not coloured). Each
    picture shows the scene, field, ``t`` and ``t/sqrt(H0/g)``.

    Examples
    --------
    >>> from skfem_npfem.plot import plot_results
    >>> paths = plot_results("out", times=[0, 1, 2, 4])  # doctest: +SKIP
    """
    req = _check_args(animation, max_frames, window_size, clim, times)
    pvd = _find_pvd(Path(result_dir))
    folder = pvd.parent
    entries = read_pvd(pvd)
    if not entries:
        raise CheckpointError(f"{pvd}: the collection lists no steps")
    ts = np.array([t for t, _ in entries])
    scene, tau = _scene_info(folder)
    if normalised and tau is None and req:
        warnings.warn(
            f"{folder}: scene.json has no 'aspect' and 'length' parameters, so "
            "times are taken as absolute seconds instead of t/sqrt(H0/g)",
            UserWarning,
            stacklevel=2,
        )
    snaps = _pick_snapshots(ts, req, tau if normalised else None)
    frames = [] if animation == "none" else list(_frame_indices(len(ts), max_frames))
    pv = _import_pyvista()
    _check_rendering()
    dim, names, kept, ranges = _load(entries, field, set(snaps) | set(frames))
    out = folder / "plots" if out_dir is None else Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        msg = f"a writable folder ({err})"
        raise ParameterError("out_dir", str(out), msg) from None

    written: list[Path] = []
    for name in names:
        fixed = clim is not None and name in clim
        lo, hi = (float(v) for v in clim[name]) if fixed else ranges[name]
        style = _style(name, lo, hi, fixed=fixed)
        title = f"{scene + ': ' if scene else ''}{FIELDS[name]}"
        args = (pv, kept, dim, name, style, title, tau, window_size)
        renderer = _Renderer(*args)
        try:
            for i in sorted(snaps, key=lambda k: ts[k]):
                path = out / f"{name}_t{_time_label(snaps[i])}.png"
                renderer.draw(i)
                renderer.image(path)
                written.append(path)
        finally:
            renderer.close()
        if animation != "none":
            renderer = _Renderer(*args, fast=True)
            try:
                path = out / f"{name}.{animation}"
                _write_animation(renderer, frames, path, animation)
                written.append(path)
            finally:
                renderer.close()
    return written
