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
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..boundary import RigidBody
from ..errors import ParameterError
from ..mesh.insertion import Insertion, edge_shares, insert_midpoints, long_edges
from ..mesh.merging import merge_pairs
from ..mesh.refine import mark_share
from ..mesh.sources import seal_with
from ..particles import Particles

__all__ = ["Refiner", "initial_rows", "refined_point_data"]


class Refiner:
    """Insert particles on stretched edges at the start of each step.

    Parameters
    ----------
    ratio : float or None, default 1.6
        An edge is split when longer than ``ratio`` times its ends' smaller
        target spacing (> sqrt(2): the diagonal of an undeformed square
        lattice is never split).  None: no particle is added (a graded
        lattice's spacing carried, merging only if ``merge``).
    merge : float, default 0.0
        Two particles closer than ``merge`` times the larger target spacing
        of the two are merged into one (:mod:`skfem_npfem.mesh.merging`);
        0: never.  Below ``ratio / 2``, so that a merged pair is not split
        again.
    max_spacing_ratio : float, default 4.0
        A particle whose nodal volume exceeds this many times its spacing^d is
        no donor (a lone particle at a free surface).
    target : callable, optional
        ``target(x, time) -> (n,)``: the spacing wanted at the particles'
        positions ``x`` (n, d) at ``time``, m (a user's grading: finer where a
        result is read, coarser far away).  The edge and merge tests read it
        instead of each particle's carried spacing; the carried spacing stays
        what the alpha test reads, so a coarse region is refined edge by edge
        (at most one edge per particle a pass) rather than dropped.  None:
        the carried spacing is the target.
    strain_share : float, optional
        Refine where the plastic strain rate concentrates: before each step
        the fewest particles whose cells carry this share (in (0, 1]) of the
        last step's plastic shear-strain rate times cell volume
        (:func:`~skfem_npfem.mesh.refine.mark_share`; for a soil of one
        strength, that share of the plastic power) have their target halved,
        so the edges round them are split until the spacing there is about
        half the carried one; where the flow has moved on, the target is the
        carried spacing again and the added particles stay (a ``merge`` below
        0.5 leaves a halved lattice alone; above it merges them whenever the
        marking moves away, and they are split again when it comes back).
        The particles carry the rate (:attr:`Particles.shear_rate`, zero
        before the first step).  None: no such marking.
    stretched : bool, default True
        Split an edge stretched beyond ``ratio`` times its ends' target
        anywhere.  False (with ``strain_share``): only the edges round the
        marked particles are split, the rest of the lattice stays as made.

    Attributes
    ----------
    inserted : int
        Particles added so far by this refiner.
    last : Insertion
        The last pass's insertions (``last_merge``: its merges).
    particles : Particles
        What the last call returned: the particles the step starts from.

    Raises
    ------
    ParameterError
        If ``ratio`` is not a number > sqrt(2), or ``merge`` not in
        ``[0, ratio / 2)``.
    """

    def __init__(
        self,
        ratio: float | None = 1.6,
        merge: float = 0.0,
        max_spacing_ratio: float = 4.0,
        target: Callable[[np.ndarray, float], np.ndarray] | None = None,
        strain_share: float | None = None,
        stretched: bool = True,
    ) -> None:
        if ratio is not None and (
            not (isinstance(ratio, int | float) and math.isfinite(ratio))
            or not ratio > math.sqrt(2.0)
        ):
            raise ParameterError(
                "ratio",
                ratio,
                "a number > sqrt(2) = 1.414 (edge over spacing), or None (no "
                "insertion)",
            )
        half = math.inf if ratio is None else 0.5 * ratio
        if not (isinstance(merge, int | float) and 0.0 <= merge < half):
            raise ParameterError(
                "merge",
                merge,
                f"a number in [0, ratio / 2 = {half:g}) (0: never merge; a merged "
                "pair must not be split again at once)",
            )
        self.ratio = math.inf if ratio is None else float(ratio)
        self.merge = float(merge)
        self.max_spacing_ratio = float(max_spacing_ratio)
        if target is not None and not callable(target):
            raise ParameterError(
                "target", type(target).__name__, "a function target(x, time)"
            )
        self.target = target
        if strain_share is not None and not (
            isinstance(strain_share, int | float) and 0.0 < strain_share <= 1.0
        ):
            raise ParameterError(
                "strain_share",
                strain_share,
                "a number in (0, 1] (the share of the plastic power whose "
                "particles are refined), or None",
            )
        self.strain_share = strain_share
        self.stretched = bool(stretched) or strain_share is None
        self.marked = 0  # particles whose target the last pass halved
        self.inserted = 0
        self.last = Insertion()
        self.last_merge = Insertion()
        self._loads0: np.ndarray | None = None  # the model's dead loads at start

    def __call__(
        self,
        p: Particles,
        mesh_source: Any,
        model: Any = None,
        time: float = 0.0,
    ) -> Particles:
        """The particles ``p`` refined; syncs the spacing and the model's loads.

        ``model`` (a :class:`~skfem_npfem.Model`, optional): its bodies get
        no particle inside them, and its dead loads (``loads``, one row per
        particle) follow the particles: an initial particle keeps its load,
        an added one has none, and a loaded particle is never merged.  A
        model with tied groups of particles (``tied``) is refused.
        """
        bodies = self._check_model(model)
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
        seal_with(mesh_source, p)
        tri = mesh_source.triangulate(p.x)
        edges, share, volume = edge_shares(p.x, tri.simplices)
        a, b = edges[:, 0], edges[:, 1]
        free = ~p.fixed.any(axis=1)
        same = p.material[a] == p.material[b]
        d = p.dim
        donor = free & (volume > 0) & (volume < self.max_spacing_ratio * spacing**d)
        goal = spacing if self.target is None else self._goal(p.x, time)
        if self.strain_share is not None:
            if p.shear_rate is None:  # the steps record it from now on
                p = p.replace(shear_rate=np.zeros(p.n))
            marked = self._mark(p.shear_rate * np.maximum(volume, 0.0))
            goal = np.where(marked, 0.5 * goal, goal)
            # Without the stretched edges' insertion only the marked split.
            split = goal if self.stretched else np.where(marked, goal, np.inf)
        else:
            split = goal
        chosen = long_edges(p.x, edges, split, self.ratio, donor[a] & donor[b] & same)
        chosen = chosen[_clear(bodies, 0.5 * (p.x[a[chosen]] + p.x[b[chosen]]), time)]
        pairs = edges[:0]
        if self.merge > 0.0:  # never a particle of a split edge
            busy = np.zeros(p.n, bool)
            busy[edges[chosen].ravel()] = True
            ok = free & ~busy & ~self._loaded(ids)
            short = long_edges(
                p.x, edges, goal, self.merge, ok[a] & ok[b] & same, shorter=True
            )
            m = p.mass[a[short], None], p.mass[b[short], None]
            centre = (m[0] * p.x[a[short]] + m[1] * p.x[b[short]]) / (m[0] + m[1])
            pairs = edges[short[_clear(bodies, centre, time)]]
        out, self.last = insert_midpoints(
            p, edges[chosen], share[chosen], volume, ids, spacing
        )
        # The merged rows are below p.n: the added particles (last) keep theirs.
        out, self.last_merge = merge_pairs(out, pairs, out.ids, out.spacing)
        self.inserted += self.last.count
        mesh_source.spacing = out.spacing
        if self._loads0 is not None:  # a function of the ids: retries repeat it
            loads = np.zeros((out.n, out.dim))
            rows, first = initial_rows(out, self._loads0.shape[0])
            loads[rows] = self._loads0[first]
            model.loads = loads
        self.particles = out
        return out

    def _loaded(self, ids: np.ndarray) -> np.ndarray:
        """Particles (by their ``ids``) that carry a dead load, bool.

        The loads follow the initial particles' ids, so a pair of unloaded
        particles merges into one that is unloaded whichever id it keeps: a
        loaded particle is never merged.
        """
        loaded = np.zeros(ids.size, bool)
        if self._loads0 is not None:
            rows = np.flatnonzero(ids < self._loads0.shape[0])
            loaded[rows] = np.any(self._loads0[ids[rows]] != 0.0, axis=1)
        return loaded

    def _mark(self, power: np.ndarray) -> np.ndarray:
        """The fewest particles that carry ``strain_share`` of ``power`` (n,) bool.

        None marked while nothing flows plastically.
        """
        if not np.any(power > 0.0):
            self.marked = 0
            return np.zeros(power.size, bool)
        marked = mark_share(power, self.strain_share)
        self.marked = int(marked.sum())
        return marked

    def _goal(self, x: np.ndarray, time: float) -> np.ndarray:
        """The user's target spacing at ``x``, checked: (n,) finite, > 0."""
        goal = np.asarray(self.target(x, time), dtype=float)
        if goal.ndim == 0:
            goal = np.full(x.shape[0], float(goal))
        if goal.shape != (x.shape[0],) or not np.all(np.isfinite(goal) & (goal > 0)):
            raise ParameterError(
                "target",
                f"values of shape {goal.shape}",
                f"({x.shape[0]},) finite spacings > 0 (m), one per particle",
            )
        return goal

    def _check_model(self, model: Any) -> Sequence[RigidBody]:
        """The model's bodies; keeps its initial dead loads; refuses ties."""
        if model is None:
            return ()
        if getattr(model, "tied", None):
            raise ParameterError(
                "tied",
                f"{len(model.tied)} tied group(s)",
                "None with particle refinement (a tied group names particles by row)",
            )
        if model.loads is not None and self._loads0 is None:
            self._loads0 = np.array(model.loads)
        return model.bodies

    def record(self) -> dict[str, float]:
        """The last pass for a step record's ``extra``."""
        return {
            "inserted": float(self.last.count),
            "insertion_mass_error": self.last.mass_error,
            "insertion_momentum_error": self.last.momentum_error,
            "merged": float(self.last_merge.count),
            "merging_momentum_error": self.last_merge.momentum_error,
        } | ({} if self.strain_share is None else {"refined": float(self.marked)})


def _clear(bodies: Sequence[RigidBody], x: np.ndarray, time: float) -> np.ndarray:
    """Points ``x`` outside every body at ``time`` (n,) bool."""
    inside = np.zeros(x.shape[0], bool)
    for body in bodies if x.shape[0] else ():
        inside |= body.contains(x, time)
    return ~inside


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


def initial_rows(p: Particles, n0: int) -> tuple[np.ndarray, np.ndarray]:
    """The rows of ``p`` that hold particles of the initial ``n0``, and their ids.

    Without refinement (``p.ids`` None) every row is its own initial
    particle.  A scene that marked initial particles (a boolean mask of
    ``n0``) reads ``values[rows]`` against ``mask[ids]``.

    Examples
    --------
    >>> q = Particles.create([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]], 1.0)
    >>> rows, ids = initial_rows(q.replace(ids=np.array([0, 2, 3])), 3)
    >>> rows.tolist(), ids.tolist()
    ([0, 1], [0, 2])
    """
    if p.ids is None:
        rows = np.arange(min(p.n, n0))
        return rows, rows
    rows = np.flatnonzero(p.ids < n0)
    return rows, p.ids[rows]
