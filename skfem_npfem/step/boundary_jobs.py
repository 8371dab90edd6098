"""The step asking its boundaries: each job once of the list, in its order.

A step holds the model's boundaries
(:attr:`~skfem_npfem.step.model.Model.boundaries`: the walls, then the rigid
bodies) and asks every one of them each job of
:class:`~skfem_npfem.boundary.protocol.Boundary` through these functions,
shared by N-PFEM (:mod:`.operators`, :mod:`.update`, :mod:`.stages`) and
FEM-remap:

1. :func:`with_columns` -- one lagged-force column of the particles per wall
   and body;
2. :func:`without_spanned` -- the elements of the step's mesh that span a
   boundary dropped (walls span none);
3. :func:`step_contacts` -- the contact rows of the step's nodes
   (:class:`~skfem_npfem.boundary.protocol.ContactNodes`; the particles':
   :func:`particle_nodes`), each boundary's after the previous one's, and the
   column of each row;
4. :func:`put_back` -- particles that crossed a boundary put back on it;
5. :func:`record` -- what each boundary writes into the step record.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..boundary import Boundary, ContactNodes, Contacts
from ..particles import Particles

__all__ = [
    "particle_nodes",
    "put_back",
    "record",
    "step_contacts",
    "with_columns",
    "without_spanned",
]


def particle_nodes(
    p: Particles, active: np.ndarray, local_t: np.ndarray
) -> ContactNodes:
    """The active particles of a step as the boundaries' contact nodes (N-PFEM).

    Their lagged forces are ``p.wall_force`` (with a column for every wall
    and body: :func:`with_columns`), whose largest magnitude over all
    particles sets each column's noise level.
    """
    return ContactNodes(
        x=p.x[active],
        v=p.v[active],
        fixed=p.fixed[active],
        v_prescribed=p.v_prescribed[active],
        lagged=p.wall_force[active],
        noise_ref=p.wall_force,
        local_t=local_t,
    )


def with_columns(boundaries: Sequence[Boundary], p: Particles) -> Particles:
    """Particles with a lagged-force column for every wall and body."""
    for b in boundaries:
        p = b.with_columns(p)
    return p


def without_spanned(
    boundaries: Sequence[Boundary],
    x: np.ndarray,
    active: np.ndarray,
    local_t: np.ndarray,
    time: float,
    sliver: float | None = None,
) -> tuple[np.ndarray, np.ndarray, int]:
    """The mesh source's mesh without the elements that span a boundary.

    Parameters
    ----------
    boundaries : sequence of Boundary
    x : ndarray (N, d)
        Positions of all particles.
    active, local_t : ndarray
        The mesh: its particles and its connectivity (d+1, ne) in numbers
        local to ``active``.
    time : float
        Time at the start of the step, s (where moving boundaries are).
    sliver : float or None
        How deep an element may cut a body's corner and stay (None: the
        bodies' default, :data:`~skfem_npfem.boundary.spanning.CLIP_DEPTH`).

    Returns
    -------
    active, local_t : ndarray
        The remaining mesh, renumbered.
    dropped : int
        Elements dropped.
    """
    dropped = 0
    for b in boundaries:
        active, local_t, n = b.without_spanned(x, active, local_t, time, sliver)
        dropped += n
    return active, local_t, dropped


def step_contacts(
    boundaries: Sequence[Boundary],
    nodes: ContactNodes,
    dt: float,
    h: float,
    time: float,
) -> tuple[Contacts, np.ndarray]:
    """The contact rows of all boundaries, in their order, and each row's column.

    Parameters
    ----------
    boundaries : sequence of Boundary
        At least one (a model's walls, possibly none of them, come first).
    nodes : ContactNodes
        The step's displacement nodes.
    dt, h, time : float
        Step (s), spacing (m), time at the start of the step (s).
    """
    rows, ids = boundaries[0].contacts(nodes, dt, h, time)
    for b in boundaries[1:]:
        more, more_ids = b.contacts(nodes, dt, h, time)
        rows = Contacts.concat([rows, more])
        ids = np.concatenate([ids, more_ids])
    return rows, ids


def put_back(
    boundaries: Sequence[Boundary],
    x: np.ndarray,
    v: np.ndarray,
    u: np.ndarray,
    friction: np.ndarray,
    t_end: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[Any]]:
    """Particles that crossed a boundary put back on it, boundary by boundary.

    ``friction`` flags the particles without contact rows (the ballistic
    ones), which a rough wall slows down.  Returns the new positions,
    velocities and displacements (each boundary adds its own shift to ``u``)
    and each boundary's mark (a body group: the deepest penetration).
    """
    marks = []
    for b in boundaries:
        x, v, u, mark = b.put_back(x, v, u, friction, t_end)
        marks.append(mark)
    return x, v, u, marks


def record(
    boundaries: Sequence[Boundary],
    extra: dict[str, Any],
    contacts: Contacts,
    ids: np.ndarray,
    lambdas: tuple[np.ndarray, np.ndarray],
    x: np.ndarray,
    t_end: float,
    marks: Sequence[Any],
    dropped: int,
) -> None:
    """Every boundary's keys in the step record's ``extra``.

    ``lambdas`` are the normal and tangential forces of the rows, ``x`` the
    positions of the nodes they index (start of the step), ``marks`` from
    :func:`put_back` and ``dropped`` from :func:`without_spanned`.
    """
    for b, mark in zip(boundaries, marks, strict=True):
        b.record(extra, contacts, ids, lambdas, x, t_end, mark, dropped)
