"""What a step needs of a boundary: :class:`Boundary` and :class:`ContactNodes`.

A step (N-PFEM's :func:`~skfem_npfem.step.stages.advance`, FEM-remap's
:meth:`~skfem_npfem.baseline.FemRemap.advance`) holds a list of
:class:`Boundary` objects -- the walls as one
(:class:`~skfem_npfem.boundary.walls.Walls`), the rigid bodies as another
(:class:`~skfem_npfem.boundary.rigid_bodies.RigidBodies`;
:attr:`~skfem_npfem.step.model.Model.boundaries`) -- and asks each job of
every one of them, in the list's order
(:mod:`skfem_npfem.step.boundary_jobs`): the lagged-force columns, the
elements of the mesh they span, their contact rows on the step's nodes
(:class:`ContactNodes`), the particles put back, the record keys.

The order of the list is the order of the contact rows and of the
lagged-force columns: the walls first, then the bodies (body ``k`` is column
``len(walls) + k``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..particles import Particles
from .contacts import Contacts

__all__ = ["Boundary", "ContactNodes"]


@dataclass(frozen=True)
class ContactNodes:
    """The displacement nodes of one step as the boundaries' contact rows see them.

    Attributes
    ----------
    x, v : ndarray (n, d)
        Positions and velocities at the start of the step.
    fixed : ndarray (n, d) bool
        Prescribed dofs; ``v_prescribed`` (n, d) their velocities.
    v_prescribed : ndarray (n, d)
    lagged : ndarray (n, n_columns)
        Normal force of each wall and body on the node in the previous step, N.
    noise_ref : ndarray (m, n_columns)
        Forces whose largest magnitude per column sets the noise level of
        ``lagged`` (N-PFEM: all particles' columns).
    local_t : ndarray (d+1, ne) int
        Connectivity of the step's mesh in node numbers (its vertices).
    facets : callable or None
        ``() -> ndarray``: the boundary edges (2, nb) the bodies' rows need,
        when they are not those of ``local_t`` (FEM-remap's P2 half edges);
        None: the bodies take them from ``x`` and ``local_t``.
    """

    x: np.ndarray
    v: np.ndarray
    fixed: np.ndarray
    v_prescribed: np.ndarray
    lagged: np.ndarray
    noise_ref: np.ndarray
    local_t: np.ndarray
    facets: Callable[[], np.ndarray] | None = None


@runtime_checkable
class Boundary(Protocol):
    """What a step needs of a boundary (a group of walls, a group of bodies).

    Each method is one job of the step; a boundary with nothing to do for a
    job hands its input back unchanged.
    """

    def with_columns(self, p: Particles) -> Particles:
        """``p`` with the lagged-force columns this boundary writes."""
        ...

    def without_spanned(
        self,
        x: np.ndarray,
        active: np.ndarray,
        local_t: np.ndarray,
        time: float,
        sliver: float | None,
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """The mesh without the elements that span this boundary, and how many."""
        ...

    def contacts(
        self, nodes: ContactNodes, dt: float, h: float, time: float
    ) -> tuple[Contacts, np.ndarray]:
        """The boundary's contact rows and the lagged-force column of each."""
        ...

    def put_back(
        self,
        x: np.ndarray,
        v: np.ndarray,
        u: np.ndarray,
        friction: np.ndarray,
        t_end: float,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, Any]:
        """Positions, velocities, displacements after crossings, and a mark."""
        ...

    def record(
        self,
        extra: dict[str, Any],
        contacts: Contacts,
        ids: np.ndarray,
        lambdas: tuple[np.ndarray, np.ndarray],
        x: np.ndarray,
        t_end: float,
        mark: Any,
        dropped: int,
    ) -> None:
        """Write this boundary's keys into a step record's ``extra``."""
        ...
