"""Particles added where the soil stretches, before each step of a run.

A :class:`Refiner` given to :class:`~skfem_npfem.Simulation` (``refiner=``)
triangulates the particles at the start of every step, as the step itself
will, and adds a particle at the middle of each edge that has grown beyond
``ratio`` times the smaller target spacing of its ends
(:mod:`skfem_npfem.mesh.insertion`: mass and momentum conserved, the other
particles untouched).  The particles start with ``ids`` (their row) and a
``spacing`` (the mesh source's per-particle spacing, or its ``h``); new ones
take the next ids and the smaller spacing of their ends, and the mesh
source's alpha test reads the spacing of every particle.

The refinement is a function of the particles a step starts from, which is
what a checkpoint holds: a run resumed across an insertion repeats the
uninterrupted one step for step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..boundary import RigidBody
from ..errors import ParameterError
from ..mesh.insertion import Insertion, edge_shares, insert_midpoints, long_edges
from ..particles import Particles

__all__ = ["Refiner", "refined_point_data"]


class Refiner:
    """Insert particles on stretched edges at the start of each step.

    Parameters
    ----------
    ratio : float, default 1.6
        An edge is split when longer than ``ratio`` times its ends' smaller
        target spacing (> sqrt(2): the diagonal of an undeformed square
        lattice is never split).
    max_spacing_ratio : float, default 4.0
        A particle whose nodal volume exceeds this many times its spacing^d is
        no donor (a lone particle at a free surface).

    Attributes
    ----------
    inserted : int
        Particles added so far by this refiner.
    last : Insertion
        The last pass.

    Raises
    ------
    ParameterError
        If ``ratio`` is not a number > sqrt(2).
    """

    def __init__(self, ratio: float = 1.6, max_spacing_ratio: float = 4.0) -> None:
        if not (isinstance(ratio, int | float) and math.isfinite(ratio)) or not (
            ratio > math.sqrt(2.0)
        ):
            raise ParameterError(
                "ratio", ratio, "a number > sqrt(2) = 1.414 (edge over spacing)"
            )
        self.ratio = float(ratio)
        self.max_spacing_ratio = float(max_spacing_ratio)
        self.inserted = 0
        self.last = Insertion()

    def __call__(
        self,
        p: Particles,
        mesh_source: Any,
        bodies: Sequence[RigidBody] = (),
        time: float = 0.0,
    ) -> Particles:
        """The particles ``p`` with the stretched edges split; syncs the spacing."""
        if not hasattr(mesh_source, "triangulate"):
            raise ParameterError(
                "mesh_source",
                type(mesh_source).__name__,
                "an AlphaShapeMesher (a refined run re-triangulates its particles)",
            )
        spacing = p.spacing
        if spacing is None:
            given = getattr(mesh_source, "spacing", None)
            spacing = np.full(p.n, mesh_source.h) if given is None else given.copy()
        ids = np.arange(p.n, dtype=np.int64) if p.ids is None else p.ids
        mesh_source.spacing = spacing
        tri = mesh_source.triangulate(p.x)
        edges, share, volume = edge_shares(p.x, tri.simplices)
        a, b = edges[:, 0], edges[:, 1]
        free = ~p.fixed.any(axis=1)
        d = p.dim
        donor = free & (volume > 0) & (volume < self.max_spacing_ratio * spacing**d)
        allowed = donor[a] & donor[b] & (p.material[a] == p.material[b])
        chosen = long_edges(p.x, edges, spacing, self.ratio, allowed)
        if chosen.size and bodies:
            mid = 0.5 * (p.x[a[chosen]] + p.x[b[chosen]])
            inside = np.zeros(chosen.size, bool)
            for body in bodies:
                inside |= body.contains(mid, time)
            chosen = chosen[~inside]
        out, self.last = insert_midpoints(
            p, edges[chosen], share[chosen], volume, ids, spacing
        )
        self.inserted += self.last.count
        mesh_source.spacing = out.spacing
        return out

    def record(self) -> dict[str, float]:
        """The last pass for a step record's ``extra``."""
        return {
            "inserted": float(self.last.count),
            "insertion_mass_error": self.last.mass_error,
            "insertion_momentum_error": self.last.momentum_error,
        }


def refined_point_data(p: Particles) -> dict[str, np.ndarray]:
    """``particle_id`` and ``target_spacing`` of refined particles (else nothing).

    ParaView follows a particle across steps whose particle counts differ by
    its ``particle_id`` (e.g. the Temporal Particles To Pathlines filter).
    """
    out = {}
    if p.ids is not None:
        out["particle_id"] = p.ids
    if p.spacing is not None:
        out["target_spacing"] = p.spacing
    return out
