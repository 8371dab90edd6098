"""Animations of a result: the frames of a renderer written as a GIF or an MP4."""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import NpfemError
from ..io import atomic_path
from .render import _GIF_MAX_SIDE, Renderer

__all__ = ["write_animation"]


def write_animation(
    renderer: Renderer, indices: Sequence[int], path: Path, kind: str
) -> None:
    """Write the frames of ``indices`` as a GIF or MP4."""
    fps = int(np.clip(round(len(indices) / 6), 4, 20))
    if kind == "mp4":
        try:
            import imageio.v2 as imageio

            if importlib.util.find_spec("imageio_ffmpeg") is None:
                # the mp4 writer needs it
                raise ImportError("No module named 'imageio_ffmpeg'")
        except ImportError as err:
            raise NpfemError(
                f"MP4 output needs imageio and imageio-ffmpeg ({err}); "
                "pip install 'skfem-npfem[viz]' or use animation='gif'"
            ) from None
        with atomic_path(path) as tmp:
            writer = imageio.get_writer(
                tmp, format="FFMPEG", fps=fps, macro_block_size=16, quality=7
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
    with atomic_path(path) as tmp:
        frames[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=frames[1:],
            duration=round(1000 / fps),
            loop=0,
            optimize=False,
        )
