"""What a picture of a footing result shows.

The fixed base, the rollers, the symmetry axis, the footing and the load curve.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ...constants import GRAVITY
from ...errors import CheckpointError
from ...io import latest_checkpoint, load_checkpoint
from ...laws import prandtl_nc
from ..scenery import Scenery, box, number
from .mesh import (
    resolve_defaults,
)

__all__ = ["footing_scenery", "saved_factor_curve", "saved_load_curve"]


def footing_scenery(p: dict, folder: Path | None = None) -> Scenery:
    """The footing's scenery: base, rollers, symmetry axis, footing, load curve.

    The load curve comes from ``folder``'s ``summary.json``, else from the
    latest checkpoint there; steps are labelled by their settlement.
    """
    s = Scenery(scene="strip-footing")
    p = resolve_defaults(dict(p))
    B, domain = number(p, "width"), number(p, "domain_width")
    if B is None or domain is None:
        return s
    b = B / 2
    L = domain * b
    s.half_width = b
    s.floor, s.floor_label = 0.0, "fixed base"
    s.walls.append((L, -1, "rollers"))
    s.symmetry = 0.0
    s.outline = box(0.0, L, 0.0, L)
    s.footing = (0.0, b, L)
    s.label = s.settlement_label
    c, phi = number(p, "c", 0.0), number(p, "phi", 0.0)
    # unit weight rho g
    gamma = number(p, "rho", 0.0) * (number(p, "gravity", GRAVITY) or GRAVITY)
    if p.get("material") == "tresca":
        phi = 0.0
    if gamma == 0 and c and c > 0:
        s.q_reference = prandtl_nc(phi or 0.0) * c
    if folder is not None:
        s.load_curve = saved_load_curve(Path(folder))
    return s


def saved_load_curve(folder: Path) -> np.ndarray | None:
    """``[settlement, pressure]`` rows of a result folder (summary, else checkpoint)."""
    records = _saved(folder, "load_curve")
    if not isinstance(records, list):
        return records
    rows = []
    for r in records:
        extra = r.get("extra", r) if isinstance(r, dict) else {}
        if "settlement" in extra and "pressure" in extra:
            rows.append([extra["settlement"], extra["pressure"]])
    return np.array(rows, dtype=float).reshape(-1, 2) if rows else None


def saved_factor_curve(
    folder: Path, D: float, su: float, s0: float
) -> np.ndarray | None:
    """The cone's ``[w/D, N_c]`` rows of a result folder (summary, else checkpoint).

    From a checkpoint's step records as the scene's ``curve`` metric is:
    ``w/D = -cone_y / D``, ``N_c = (F / (pi D^2 / 4) - sigma_0) / s_u``.
    """
    records = _saved(folder, "curve")
    if not isinstance(records, list):
        return records
    area = math.pi * D**2 / 4
    rows = []
    for r in records:
        extra = r.get("extra", r) if isinstance(r, dict) else {}
        if "cone_force_y" in extra and "cone_y" in extra:
            rows.append(
                [-extra["cone_y"] / D, (extra["cone_force_y"] / area - s0) / su]
            )
    return np.array(rows, dtype=float).reshape(-1, 2) if rows else None


def _saved(folder: Path, key: str) -> np.ndarray | list | None:
    """The summary's ``metrics[key]`` rows, else the latest checkpoint's records."""
    try:
        data = json.loads((folder / "summary.json").read_text())
        return np.array(data["metrics"][key], dtype=float).reshape(-1, 2)
    except (OSError, ValueError, KeyError, TypeError):
        pass
    path = latest_checkpoint(folder)
    if path is None:
        return None
    try:
        _, meta = load_checkpoint(path)
        return list(meta.get("records", []))
    except CheckpointError:
        return None
