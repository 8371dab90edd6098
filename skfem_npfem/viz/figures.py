"""Pictures of 2D results with matplotlib: what a geotechnician expects to see.

:class:`Frames2D` draws one field of any stored step of a 2D result: the particles' mesh
coloured by the field (detached grains, outside the mesh, as black-edged diamonds in the
field's colours, counted in the legend), axes in metres with equal scales, the floor,
walls and footing of the scene, the initial outline of the body, the run-out (99 % mass
front) and the reference run-out of Lube et al. (2005) for the collapse, and for the
strip footing the load-settlement curve beside it with the current point marked.  The
frame is cropped to every particle (detached grains included, so the run-out line the
legend names is in the picture) and the scenery; the colour bar says when values beyond
its range were clipped.  :func:`load_settlement_figure` is the footing's main result on
its own, :func:`factor_curve_figure` the cone's.  They return matplotlib
figures (no pyplot, no display), so tests can look at what is drawn;
:meth:`Frames2D.image` renders one to pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io import atomic_path
from ..scenes.scenery import Scenery
from .render import Step, Style

__all__ = [
    "Frames2D",
    "View",
    "factor_curve_figure",
    "load_settlement_figure",
]

_DPI = 100
_BODY = "#303030"
_REF = "#1f77b4"
#: The hatched patches of a fixed base and of walls.
_SUPPORT = {"facecolor": "#d9d9d9", "edgecolor": "#404040", "lw": 0.8, "zorder": 1}
_FRONT = "#d62728"
_WATER = "#0072b2"


@dataclass
class View:
    """Crop and size of the pictures of one result.

    Attributes
    ----------
    xlim, ylim : (float, float)
        Axis ranges, m (the body over all steps, the outline, the reference).
    size : (int, int)
        Image width and height in pixels.
    """

    xlim: tuple[float, float]
    ylim: tuple[float, float]
    size: tuple[int, int]


def crop(steps: list[Step], sc: Scenery, window: tuple[int, int] | None) -> View:
    """The view of a result: every particle over the drawn steps plus the scenery.

    The detached grains (in no cell) are inside the frame too: they are drawn
    and named in the legend, and they can set the 99 % mass front whose line
    the legend labels.  A scenery with a ``window`` (the cone: a few D
    around the tip's path) shows that window instead.
    """
    boxes = []
    for s in steps:
        if len(s.points):
            p = s.points[:, :2]
            boxes.append(np.r_[p.min(axis=0), p.max(axis=0)])
    if sc.outline is not None:
        boxes.append(np.r_[np.nanmin(sc.outline, 0), np.nanmax(sc.outline, 0)])
    if not boxes:
        boxes.append(np.array([0.0, 0.0, 1.0, 1.0]))
    b = np.array(boxes)
    x0, y0 = b[:, 0].min(), b[:, 1].min()
    x1, y1 = b[:, 2].max(), b[:, 3].max()
    if sc.window is not None:
        x0, x1, y0, y1 = sc.window
    if sc.runout_reference is not None:
        x1 = max(x1, sc.runout_reference)
    if sc.water_level is not None:  # free water above the body is shown
        y0, y1 = min(y0, sc.water_level), max(y1, sc.water_level)
    span = max(x1 - x0, y1 - y0, 1e-12)
    pad = 0.05 * span
    xlim = (x0 - pad, x1 + pad)
    ylim = (y0 - 1.5 * pad if sc.floor is not None else y0 - pad, y1 + 2.5 * pad)
    if window is None:
        ratio = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
        curve = sc.load_curve is not None or sc.factor_curve is not None
        share = 0.55 if curve else 0.88  # of the width
        w = 1500.0 if curve else 1100.0
        h = share * w * ratio + 230.0  # title, axis labels and colour bar
        if h > 1100.0:  # a tall body: narrower
            h = 1100.0
            w = max(1100.0 if curve else 640.0, 870.0 / ratio / share)
        window = (16 * int(np.ceil(w / 16)), 16 * int(np.ceil(max(h, 420.0) / 16)))
    return View(xlim, ylim, (int(window[0]), int(window[1])))


def _new_figure(size: tuple[int, int]):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(
        figsize=(size[0] / _DPI, size[1] / _DPI), dpi=_DPI, layout="constrained"
    )
    FigureCanvasAgg(fig)
    return fig


def _scenery(ax, sc: Scenery, view: View) -> None:
    """The static scenery: base, walls, symmetry axis, outline, reference."""
    from matplotlib.patches import Rectangle

    (x0, x1), (y0, y1) = view.xlim, view.ylim
    floor = sc.floor if sc.floor is not None and sc.floor > y0 else None
    depth = 0.6 * (floor - y0) if floor is not None else 0.0
    if floor is not None:  # not when a window leaves it out (the cone)
        ax.add_patch(
            Rectangle(
                (x0, sc.floor - depth),
                x1 - x0,
                depth,
                hatch="////",
                label=sc.floor_label,
                **_SUPPORT,
            )
        )
        ax.axhline(sc.floor, color="black", lw=1.5, zorder=2)
    width = 0.02 * (x1 - x0)
    base = y0 if floor is None else floor
    for x, side, text in sc.walls:
        if not x0 <= x <= x1:
            continue
        ax.add_patch(
            Rectangle(
                (x - width if side > 0 else x, base),
                width,
                y1 - base,
                hatch="\\\\\\\\",
                label=text or None,
                **_SUPPORT,
            )
        )
    if sc.symmetry is not None:
        ax.axvline(sc.symmetry, color="black", lw=1.0, ls="-.", label=sc.symmetry_label)
    lines = (
        (sc.outline, "black", "--", "initial outline"),
        (sc.boundaries, "#7b3294", "-.", "layer boundaries (initial)"),
    )
    for xy, colour, ls, text in lines:
        if xy is not None and len(xy):
            ax.plot(*xy.T, color=colour, lw=1.2, ls=ls, zorder=6, label=text)
    _water(ax, sc)
    if sc.runout_reference is not None:
        ax.axvline(
            sc.runout_reference,
            color=_REF,
            lw=1.8,
            ls=":",
            zorder=6,
            label=f"{sc.runout_label} = {sc.runout_reference:.3g} m",
        )


def _water(ax, sc: Scenery) -> None:
    """The water table: a section's line, or a level across the picture."""
    style = {"color": _WATER, "lw": 1.6, "zorder": 6}
    if sc.water_line is not None and len(sc.water_line):
        ax.plot(*np.asarray(sc.water_line, float).T, **style, label="water table")
    elif sc.water_level is not None:
        level = sc.water_level
        ax.axhline(level, **style, label=f"water table ({level:.3g} m)")


def _colorbar(fig, ax, style: Style, label: str, extend: str) -> None:
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    sm = ScalarMappable(norm=Normalize(*style.clim), cmap=style.cmap)
    cb = fig.colorbar(
        sm, ax=ax, orientation="horizontal", shrink=0.7, aspect=40, extend=extend
    )
    cb.set_label(label)


def load_settlement_figure(
    sc: Scenery, size: tuple[int, int] = (800, 600), ax=None, mark: float | None = None
):
    """The footing's load-settlement curve (settlement down, pressure across).

    ``mark`` is a settlement (m) to mark on the curve.  With ``ax`` the curve
    is drawn there (and its figure returned); otherwise in a new figure.
    """
    fig = _new_figure(size) if ax is None else ax.figure
    ax = fig.add_subplot(1, 1, 1) if ax is None else ax
    curve = sc.load_curve if sc.load_curve is not None else np.zeros((0, 2))
    s = np.r_[0.0, curve[:, 0]] * 1e3
    q = np.r_[0.0, curve[:, 1]] / 1e3
    ax.plot(q, s, "-o", color="black", ms=3, lw=1.5, label="N-PFEM")
    if sc.q_reference is not None:
        ax.axvline(
            sc.q_reference / 1e3,
            color=_REF,
            ls="--",
            lw=1.5,
            label=f"Prandtl N_c c = {sc.q_reference / 1e3:.4g} kPa",
        )
    if curve.size:
        ax.annotate(
            f"q = {q[-1]:.4g} kPa",
            (q[-1], s[-1]),
            textcoords="offset points",
            xytext=(-10, -14),
            ha="right",
            fontsize=9,
        )
    if mark is not None and curve.size:
        qm = np.interp(mark * 1e3, s, q)
        ax.plot(
            [qm], [mark * 1e3], "o", color=_FRONT, ms=8, zorder=5, label="this picture"
        )
    ax.set_xlabel("footing pressure q [kPa]")
    ax.set_ylabel("settlement s [mm]")
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=max(float(s.max()) * 1.05, 1e-9), top=0.0)  # down
    ax.grid(True, lw=0.4, alpha=0.6)
    ax.set_title("load-settlement curve")
    ax.legend(loc="lower left", fontsize=9)
    return fig


def factor_curve_figure(
    sc: Scenery, size: tuple[int, int] = (800, 600), ax=None, mark: float | None = None
):
    """The cone's factor ``N_c`` against ``w/D`` (and the depth pushed, m).

    ``mark`` is a ``w/D`` to mark on the curve.  With ``ax`` the curve is
    drawn there (and its figure returned); otherwise in a new figure.
    """
    fig = _new_figure(size) if ax is None else ax.figure
    ax = fig.add_subplot(1, 1, 1) if ax is None else ax
    curve = sc.factor_curve if sc.factor_curve is not None else np.zeros((0, 2))
    ax.plot(curve[:, 0], curve[:, 1], "-o", color="black", ms=3, lw=1.5)
    ax.lines[-1].set_label("N-PFEM")
    if sc.factor_reference is not None:
        ax.axhline(
            sc.factor_reference,
            color=_REF,
            ls="--",
            lw=1.5,
            label=f"Teh & Houlsby N_c = {sc.factor_reference:.3g}",
        )
    if mark is not None and curve.size:
        ax.plot(
            [mark],
            [np.interp(mark, curve[:, 0], curve[:, 1])],
            "o",
            color=_FRONT,
            ms=8,
            zorder=5,
            label="this picture",
        )
    ax.set_xlabel("penetration w/D")
    ax.set_ylabel("cone factor N_c = (q_c - sigma_0) / s_u")
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    if sc.diameter:
        D = sc.diameter
        depth = ax.secondary_xaxis("top", functions=(lambda v: v * D, lambda v: v / D))
        depth.set_xlabel("depth pushed w [m]")
    ax.grid(True, lw=0.4, alpha=0.6)
    ax.set_title("cone factor against penetration", fontsize=10)
    ax.legend(loc="lower right", fontsize=9)
    return fig


class Frames2D:
    """One figure showing one field of a 2D result; draws any step on demand.

    Parameters
    ----------
    steps : dict of int to Step
        The steps that may be drawn.
    name : str
        Field name (a key of each step's ``values``).
    style : Style
        Colour range (in ``style.unit``), map and unit scale.
    title : str
        First title line (scene and field).
    label : str
        Colour bar label.
    sc : Scenery
        What to draw around the particles.
    view : View
        Crop and image size.
    extend : str
        Colour bar ends beyond the range ("neither", "min", "max", "both").
    """

    def __init__(
        self,
        steps: dict[int, Step],
        name: str,
        style: Style,
        title: str,
        label: str,
        sc: Scenery,
        view: View,
        extend: str = "neither",
    ) -> None:
        self.steps, self.name, self.style = steps, name, style
        self.title, self.sc, self.view = title, sc, view
        self.size = view.size
        self.fig = _new_figure(view.size)
        if sc.load_curve is not None or sc.factor_curve is not None:
            grid = self.fig.add_gridspec(1, 2, width_ratios=[1.6, 1.0], wspace=0.25)
            self.ax = self.fig.add_subplot(grid[0])
            self.curve_ax = self.fig.add_subplot(grid[1])
        else:
            self.ax, self.curve_ax = self.fig.add_subplot(1, 1, 1), None
        ax = self.ax
        ax.set_aspect("equal")
        ax.set_xlim(*view.xlim)
        ax.set_ylim(*view.ylim)
        ax.set_xlabel(f"{sc.axes[0]} [m]")
        ax.set_ylabel(f"{sc.axes[1]} [m]")
        ax.grid(True, lw=0.3, alpha=0.5)
        _scenery(ax, sc, view)
        _colorbar(self.fig, ax, style, label, extend)
        self.dynamic: list = []

    def _remove_dynamic(self) -> None:
        for artist in self.dynamic:
            artist.remove()
        self.dynamic = []
        if self.curve_ax is not None:
            self.curve_ax.clear()

    def _body(self, step: Step, values: np.ndarray) -> None:
        from matplotlib.colors import Normalize
        from matplotlib.tri import Triangulation

        ax, style = self.ax, self.style
        norm = Normalize(*style.clim)
        x, y = step.points[:, 0], step.points[:, 1]
        if len(step.cells):
            tri = Triangulation(x, y, step.cells)
            self.dynamic.append(
                ax.tripcolor(
                    tri,
                    values,
                    shading="gouraud",
                    cmap=style.cmap,
                    norm=norm,
                    zorder=3,
                )
            )
            if len(step.cells) <= 4000:
                self.dynamic += ax.triplot(
                    tri, color="black", lw=0.25, alpha=0.35, zorder=4
                )
        if len(step.free):
            f = step.free
            n = len(f)
            self.dynamic.append(
                ax.scatter(
                    x[f],
                    y[f],
                    c=values[f],
                    cmap=style.cmap,
                    norm=norm,
                    s=30,
                    marker="D",
                    edgecolors="black",
                    linewidths=1.0,
                    zorder=8,
                    label=f"detached grain{'s' if n > 1 else ''} (in no cell): {n}",
                )
            )

    def _markers(self, step: Step) -> None:
        from matplotlib.patches import Polygon, Rectangle

        ax, sc = self.ax, self.sc
        if sc.front is not None and step.mass is not None:
            front = sc.front(step.points, step.mass)
            self.dynamic.append(
                ax.axvline(
                    front,
                    color=_FRONT,
                    lw=2.0,
                    zorder=7,
                    label=f"run-out (99 % mass) {front:.3g} m",
                )
            )
        if sc.footing is not None:
            x0, x1, surface = sc.footing
            thick = 0.04 * (self.view.ylim[1] - self.view.ylim[0])
            bar = Rectangle(
                (x0, surface - step.time),
                x1 - x0,
                thick,
                facecolor="#606060",
                edgecolor="black",
                lw=1.0,
                zorder=7,
                label="footing (half width b)",
            )
            ax.add_patch(bar)
            self.dynamic.append(bar)
        for outline, velocity, label in sc.bodies:
            poly = Polygon(
                np.asarray(outline) + np.asarray(velocity) * step.time,
                closed=True,
                facecolor="#606060",
                edgecolor="black",
                lw=1.0,
                zorder=7,
                label=label,
            )
            ax.add_patch(poly)
            self.dynamic.append(poly)
        if self.curve_ax is not None and sc.factor_curve is not None:
            mark = step.time / sc.unit[2] if sc.unit else None
            factor_curve_figure(sc, ax=self.curve_ax, mark=mark)
        elif self.curve_ax is not None:
            load_settlement_figure(sc, ax=self.curve_ax, mark=step.time)

    def draw(self, index: int) -> None:
        """Show step ``index``."""
        step = self.steps[index]
        self._remove_dynamic()
        values = step.values[self.name] / self.style.scale
        self._body(step, values)
        self._markers(step)
        if self.ax.get_legend_handles_labels()[0]:
            leg = self.ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
            leg.set_zorder(10)
            self.dynamic.append(leg)
        note = f"   [{self.sc.window_note}]" if self.sc.window_note else ""
        self.fig.suptitle(
            f"{self.title}\n{self.sc.label(step.time)}{note}", fontsize=12
        )

    def image(self, path: Path | None = None) -> np.ndarray:
        """Render and return the RGB image (and save it as PNG if path given)."""
        canvas = self.fig.canvas
        canvas.draw()
        img = np.asarray(canvas.buffer_rgba())[..., :3].copy()
        if path is not None:
            from PIL import Image

            with atomic_path(path) as tmp:
                Image.fromarray(img).save(tmp, format="PNG")
        return img

    def close(self) -> None:
        """Release the figure."""
        self.fig.clear()
