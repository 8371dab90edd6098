"""The picture of a limit analysis's collapse mechanism.

A scene saves the mechanism's data as ``mechanism.npz``; :func:`plot_mechanism`
draws it (``skfem-npfem plot`` calls it for a folder that has one).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..io import atomic_path, check_writable_dir
from .figures import mechanism_figure

__all__ = ["plot_mechanism", "save_rgb"]


def plot_mechanism(path: str | os.PathLike, out_dir: str | os.PathLike) -> Path:
    """Draw the ``mechanism.npz`` of a limit analysis as ``mechanism.png``.

    Parameters
    ----------
    path : str or os.PathLike
        The file a scene wrote (the slope's factor of safety stage).
    out_dir : str or os.PathLike
        Folder of the picture (created if needed).

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
