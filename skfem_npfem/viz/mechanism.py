"""The picture of a limit analysis's collapse mechanism.

A scene saves the mechanism's data as ``mechanism.npz``; :func:`plot_mechanism`
draws it with :func:`mechanism_figure` and the scene's supports, initial
outline and layer boundaries (``skfem-npfem plot`` calls it for a folder that
has one).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..io import atomic_path, check_writable_dir
from ..scenes.scenery import Scenery
from .figures import _REF, View, _new_figure, _scenery

__all__ = ["mechanism_figure", "plot_mechanism", "save_rgb"]


def plot_mechanism(
    path: str | os.PathLike, out_dir: str | os.PathLike, sc: Scenery | None = None
) -> Path:
    """Draw the ``mechanism.npz`` of a limit analysis as ``mechanism.png``.

    Parameters
    ----------
    path : str or os.PathLike
        The file a scene wrote (the slope's factor of safety stage).
    out_dir : str or os.PathLike
        Folder of the picture (created if needed).
    sc : Scenery or None, default None
        The scene's scenery: its initial outline, supports and layer
        boundaries are drawn over the mechanism.

    Returns
    -------
    Path
        The picture: dissipation density and velocity arrows of the mechanism.
    """
    data = np.load(path)
    out = Path(out_dir)
    check_writable_dir("out_dir", out)
    title = "collapse mechanism"
    if "factor_of_safety" in data:
        title += f" at F = {float(data['factor_of_safety']):.3f}"
    volumes = data["volumes"] if "volumes" in data else None
    fig = mechanism_figure(
        data["x"],
        data["triangles"],
        data["velocity"],
        data["dissipation"],
        volumes,
        title,
        sc=sc,
    )
    fig.canvas.draw()
    target = out / "mechanism.png"
    save_rgb(np.asarray(fig.canvas.buffer_rgba())[..., :3], target)
    return target


def save_rgb(img: np.ndarray, path: Path) -> None:
    """Write an RGB image array as a PNG, atomically."""
    from PIL import Image

    with atomic_path(path) as tmp:
        Image.fromarray(img).save(tmp, format="PNG")


def _frame(ax, x: np.ndarray, sc: Scenery) -> View:
    """Axis limits around the points ``x`` and the section's outline."""
    pts = x if sc.outline is None else np.r_[x, sc.outline[~np.isnan(sc.outline[:, 0])]]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.05 * float(max(hi - lo))
    view = View((lo[0] - pad, hi[0] + pad), (lo[1] - 1.5 * pad, hi[1] + pad), (0, 0))
    ax.set_xlim(*view.xlim)
    ax.set_ylim(*view.ylim)
    return view


def mechanism_figure(
    x: np.ndarray,
    triangles: np.ndarray,
    velocity: np.ndarray,
    dissipation: np.ndarray,
    volumes: np.ndarray | None = None,
    title: str = "collapse mechanism",
    size: tuple[int, int] = (900, 420),
    sc: Scenery | None = None,
):
    """A limit analysis's mechanism: dissipation density and velocity arrows.

    ``x`` (N, 2), ``triangles`` (3, m), ``velocity`` (N, 2) and
    ``dissipation`` (N,) as :class:`~skfem_npfem.LimitResult` gives them; the
    colour is the dissipation per cell volume (``volumes``, default 1), the
    fastest arrow is a tenth of the section's width long.  With the
    scene's scenery ``sc`` the section's initial outline, its supports and
    the boundaries between its layers are drawn too.
    """
    fig = _new_figure(size)
    ax = fig.add_subplot(1, 1, 1)
    dens = dissipation / (1.0 if volumes is None else volumes)
    pc = ax.tripcolor(
        x[:, 0], x[:, 1], triangles.T, dens, shading="gouraud", cmap="magma_r"
    )
    fig.colorbar(pc, ax=ax, label="dissipation density")
    speed = float(np.max(np.linalg.norm(velocity, axis=1), initial=0.0))
    if speed > 0:
        scale = speed / (0.1 * float(np.ptp(x[:, 0])))
        ax.quiver(
            x[:, 0], x[:, 1], velocity[:, 0], velocity[:, 1],
            color=_REF, width=0.002, angles="xy", scale_units="xy", scale=scale,
        )  # fmt: skip
    if sc is not None:
        _scenery(ax, sc, _frame(ax, x, sc))
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    return fig
