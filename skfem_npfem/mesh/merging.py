"""Particle removal where particles crowd: two close particles merged into one.

Where the soil is squeezed (at a body's corner, in a deposit compacting) two
particles can come far closer than the spacing they were made with; their
cells become slivers that carry no information the pair's mean does not.
:func:`~skfem_npfem.mesh.insertion.long_edges` with ``shorter=True`` picks
edges shorter than ``ratio`` times the larger target spacing of their ends,
at most one per particle in a pass, and
:func:`merge_pairs` replaces each pair by one particle:

* **mass** is the sum, and the position the pair's centre of mass;
* **momentum**: the velocity (and acceleration) is the mass-weighted mean, so
  the total momentum is unchanged to round-off;
* **intensive state** (stress, plastic strain, pore pressure, strength and
  stiffness factors, displacement since the start): the mass-weighted mean,
  admissible when the two stresses are (the yield set is convex);
* the wall forces add up; the larger of the two ids and spacings is kept (so
  the largest id never disappears and an added particle never reuses one).

The merged particle takes the row of the lower of the two; the other row is
removed, so the rows after it move up: scenes that follow particles use
their ``ids``.
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np

from ..particles import Particles
from .insertion import Insertion, conservation_errors

__all__ = ["merge_pairs"]


def merge_pairs(
    p: Particles, pairs: np.ndarray, ids: np.ndarray, spacing: np.ndarray
) -> tuple[Particles, Insertion]:
    """Merge each pair of particles (disjoint pairs) into one.

    Parameters
    ----------
    p : Particles
    pairs : ndarray (k, 2)
        Disjoint pairs of rows (``long_edges(..., shorter=True)``).
    ids, spacing : ndarray (N,)
        Stable ids and target spacings.

    Returns
    -------
    Particles
        ``N - k`` particles with ``ids`` and ``spacing`` set.
    Insertion
        The pairs merged (``count``) and the conservation errors.
    """
    k = pairs.shape[0]
    if k == 0:
        return p.replace(ids=ids, spacing=spacing), Insertion()
    a, b = pairs.min(axis=1), pairs.max(axis=1)
    ma, mb = p.mass[a], p.mass[b]
    m = ma + mb
    wa, wb = ma / m, mb / m
    keep = np.ones(p.n, bool)
    keep[b] = False
    changes: dict[str, np.ndarray] = {}
    for f in fields(p):
        arr = getattr(p, f.name)
        if arr is None or f.name in ("mass", "ids", "spacing"):
            continue
        arr = arr.copy()
        if f.name == "wall_force":  # extensive
            arr[a] = arr[a] + arr[b]
        elif arr.dtype.kind == "f" and f.name != "v_prescribed":
            wa_, wb_ = (wa, wb) if arr.ndim == 1 else (wa[:, None], wb[:, None])
            arr[a] = wa_ * arr[a] + wb_ * arr[b]
        changes[f.name] = arr[keep]
    mass = p.mass.copy()
    mass[a] = m
    changes["mass"] = mass[keep]
    new_ids, new_spacing = ids.copy(), spacing.copy()
    new_ids[a] = np.maximum(ids[a], ids[b])
    new_spacing[a] = np.maximum(spacing[a], spacing[b])
    changes["ids"], changes["spacing"] = new_ids[keep], new_spacing[keep]
    out = p.replace(**changes)
    return out, Insertion(k, *conservation_errors(p, out))
