"""Off-screen rendering with pyvista/VTK for :mod:`skfem_npfem.viz.plot`.

:class:`Renderer` holds one off-screen plotter showing one field and draws any
stored step on demand; :func:`~skfem_npfem.viz.animation.write_animation` turns a
sequence of steps into a GIF or MP4. On Linux without ``DISPLAY``, VTK is told to
use EGL (``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow``, unless already set), and
before the first picture :func:`check_rendering` runs a tiny test render in a child
process, because VTK crashes the whole interpreter instead of raising when it cannot
get an OpenGL context. Pictures are written through the atomic writer of
:mod:`skfem_npfem.io`.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ..errors import NpfemError
from ..io import atomic_path

__all__ = [
    "Renderer",
    "Step",
    "Style",
    "check_rendering",
    "import_pyvista",
]

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
class Step:
    """One stored step reduced to what the pictures need."""

    time: float
    points: np.ndarray  # (N, 3)
    cells: np.ndarray  # (ne, 3) triangles or (ne, 4) tetrahedra
    free: np.ndarray  # indices of particles drawn as points
    values: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    mass: np.ndarray | None = None  # particle masses (the run-out marker)


@dataclass
class Style:
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


def import_pyvista() -> Any:
    """Import pyvista for off-screen use or raise NpfemError."""
    _set_headless_backend()
    try:
        import pyvista as pv
    except ImportError as err:
        raise NpfemError(
            "plotting needs pyvista (pip install 'skfem-npfem[viz]'): " + str(err)
        ) from None
    return pv


def check_rendering() -> None:
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


def _grid(pv: Any, step: Step, dim: int, values: np.ndarray) -> Any:
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


def _view(
    dim: int,
    lo: np.ndarray,
    hi: np.ndarray,
    direction: tuple[float, float, float] | None = None,
) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:
    """View direction, screen-up vector and screen extent of the box lo..hi.

    2D looks down -z; 3D looks from ``direction`` (default the isometric
    ``(1, 1, 1)``) with z up.
    """
    if dim == 2:
        view_dir, up = np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0])
    else:
        view_dir = np.asarray(direction or (1.0, 1.0, 1.0), float)
        view_dir = view_dir / np.linalg.norm(view_dir)
        up = np.array([0.0, 0.0, 1.0]) - view_dir[2] * view_dir
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
    return view_dir, up, (np.ptp(corners @ right), np.ptp(corners @ up))


class Renderer:
    """One off-screen plotter showing one field; draws any step on demand.

    ``fast`` switches off multisample anti-aliasing (for animation frames).
    """

    def __init__(
        self,
        pv: Any,
        steps: dict[int, Step],
        dim: int,
        name: str,
        style: Style,
        title: str,
        tau: float | None,
        window_size: tuple[int, int] | None,
        fast: bool = False,
        view: tuple[float, float, float] | None = None,
        floor: float | None = None,
        water: float | None = None,
    ) -> None:
        self.pv, self.steps, self.dim, self.name = pv, steps, dim, name
        self.style, self.title, self.tau = style, title, tau
        pts = np.vstack([s.points for s in steps.values()])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        perspective = dim == 3 and view is not None
        if perspective and floor is not None:
            lo[2] = min(lo[2], floor)
        view_dir, up, extent = _view(dim, lo, hi, view if dim == 3 else None)
        if window_size is None:
            window_size = _window_size(*extent)
            if perspective:  # room for the axes' labels
                window_size = (max(window_size[0], 960), max(window_size[1], 880))
        self.size = (int(window_size[0]), int(window_size[1]))
        w, h = self.size
        band = h - _TOP - _BOTTOM
        scale = min(0.9 * w / max(extent[0], 1e-12), band / max(extent[1], 1e-12))
        spacing = self._spacing(steps)
        self.point_size = float(np.clip(0.6 * spacing * scale, 3, 20))
        self.pl = pv.Plotter(off_screen=True, window_size=self.size)
        if fast:  # no multisample anti-aliasing: 3x faster in software GL
            self.pl.ren_win.SetMultiSamples(0)
        self.pl.set_background("white")
        n_cells = max(len(s.cells) for s in steps.values())
        self._add_field(bool(n_cells <= 20000 and spacing * scale >= 14))
        self._add_texts()
        self.water_actor = None if water is None else self._water(lo, hi, water)
        self.free_actors: list[Any] = []
        # 2D: sphere impostors shift depth by their radius, so the coloured
        # free particles are lifted well above their dark rims
        size = hi - lo
        self.depth = 2 * spacing + 1e-3 * float(np.max(size)) if dim == 2 else 0.0
        # camera: parallel projection, the domain (union of all steps) centred
        # in the band between the colour bar and the two text lines
        diag = float(np.linalg.norm(size)) + 1e-12
        focal = (lo + hi) / 2 - (_BOTTOM + band / 2 - h / 2) / scale * up
        cam = self.pl.camera
        if perspective:
            # the same framing at the focal plane as the parallel view, seen
            # from a distance of ~3 body sizes (view angle 2 atan(1/6))
            half = h / (2 * scale)
            dist = max(4.0 * diag, half / math.tan(math.radians(15.0)))
            cam.view_angle = 2.0 * math.degrees(math.atan(1.3 * half / dist))
            self._scenery_3d(lo, hi, floor, spacing)
        else:
            self.pl.enable_parallel_projection()
            dist = 2.0 * diag + 1.0
            cam.parallel_scale = h / (2 * scale)
        cam.focal_point = tuple(focal)
        cam.position = tuple(focal + dist * view_dir)
        cam.up = tuple(up)
        cam.clipping_range = (max(dist - 2 * diag, 1e-6), dist + 2 * diag)

    def _scenery_3d(
        self, lo: np.ndarray, hi: np.ndarray, floor: float | None, spacing: float
    ) -> None:
        """The floor (a grey plane under the body) and axes in metres."""
        pl, pv = self.pl, self.pv
        if floor is not None:
            pad = 2.0 * spacing
            mid = (lo + hi) / 2
            plane = pv.Plane(
                center=(mid[0], mid[1], floor - 1e-4 * spacing),
                direction=(0.0, 0.0, 1.0),
                i_size=hi[0] - lo[0] + 2 * pad,
                j_size=hi[1] - lo[1] + 2 * pad,
            )
            pl.add_mesh(plane, color="#c8c8c8", lighting=False, render=False)
        pl.show_bounds(
            bounds=(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]),
            xtitle="x [m]",
            ytitle="y [m]",
            ztitle="z [m]",
            color="black",
            font_size=self._font_size() - 4,
            location="outer",
            grid=False,
            all_edges=False,
            ticks="outside",
            n_xlabels=3,
            n_ylabels=3,
            n_zlabels=3,
            fmt="%.2f",
            render=False,
        )

    def _water(self, lo: np.ndarray, hi: np.ndarray, level: float) -> Any:
        """A 3D result's water table: a translucent blue plane at its level."""
        mid = (lo + hi) / 2
        plane = self.pv.Plane(
            center=(mid[0], mid[1], level),
            direction=(0.0, 0.0, 1.0),
            i_size=hi[0] - lo[0],
            j_size=hi[1] - lo[1],
        )
        return self.pl.add_mesh(
            plane, color="#0072b2", opacity=0.3, lighting=False, render=False
        )

    def _font_size(self) -> int:
        return max(12, min(18, self.size[0] // 48))

    def _add_field(self, show_edges: bool) -> None:
        """The mesh coloured by the field, with a horizontal colour bar."""
        pl, style, (w, h) = self.pl, self.style, self.size
        fs = self._font_size()
        first = self.steps[min(self.steps)]
        bar_args = {
            "title": f"{self.name} [{style.unit}]",
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
            if self.dim == 3
            else {"lighting": False}
        )
        self.actor = pl.add_mesh(
            _grid(self.pv, first, self.dim, first.values[self.name] / style.scale),
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

    def _add_texts(self) -> None:
        """The header (title and time) and, in 3D, the axes."""
        pl, (w, h) = self.pl, self.size
        # header font: shrink so that the title (and the time line) fit
        chars = max(len(self.title), 48)
        header_fs = int(np.clip((w - 16) / (0.95 * chars), 8, self._font_size() - 2))
        self.text = pl.add_text(
            "", position=(8, h - 6), font_size=header_fs, color="black"
        )
        self.text.GetTextProperty().SetVerticalJustificationToTop()
        if self.dim == 3:
            pl.add_axes(
                color="black", viewport=(0.0, _BOTTOM / h, 0.15, 0.15 + _BOTTOM / h)
            )

    @staticmethod
    def _spacing(steps: dict[int, Step]) -> float:
        """Median nearest-neighbour distance of the particles (first step)."""
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

            with atomic_path(path) as tmp:
                Image.fromarray(img).save(tmp, format="PNG")
        return img

    def close(self) -> None:
        """Release the plotter."""
        self.pl.close()
