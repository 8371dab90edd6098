"""The rigid bodies of a model as one boundary of a step.

N-PFEM (:func:`~skfem_npfem.step.stages.advance`) and FEM-remap
(:class:`~skfem_npfem.baseline.FemRemap`) ask :class:`RigidBodies` the same
jobs (:mod:`.protocol`): elements spanning a body are dropped, the body rows
follow the wall rows with the bodies' lagged normal forces, particles that end
a step inside a body are put back on it, and the record gets each body's
position, load and penetration.  2D bodies are
:class:`~skfem_npfem.RigidBody` polygons; 3D ones
:class:`~skfem_npfem.RigidPlane` and :class:`~skfem_npfem.BodyOfRevolution`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..particles import Particles
from .body import body_loads, project_out_of_bodies
from .contact import body_contacts, oriented_boundary
from .contact3d import boundary_faces, spanning_tetrahedra
from .contacts import Contacts
from .protocol import ContactNodes
from .spanning import CLIP_DEPTH, spanning_elements

__all__ = ["RigidBodies"]


@dataclass(frozen=True)
class RigidBodies:
    """A model's moving rigid bodies as one boundary of a step.

    The :class:`~skfem_npfem.boundary.protocol.Boundary` of the bodies; their
    lagged normal forces are the columns ``first .. first + len(bodies) - 1``
    of :attr:`Particles.wall_force` (after the walls': ``first`` is the
    number of walls), and body ``k``'s contact rows carry the id
    ``first + k``.

    Parameters
    ----------
    bodies : sequence of RigidBody, RigidPlane or BodyOfRevolution
    first : int
        Lagged-force column (and contact id) of the first body.
    dim : int
        2 (polygons, plane strain or axisymmetric) or 3.
    axisymmetric : bool
        The 2D mesh is an ``(r, z)`` half-section.
    gravity : float
        Gravitational acceleration, m/s^2 (the contact reach of a step).
    """

    bodies: Sequence[Any]
    first: int
    dim: int
    axisymmetric: bool
    gravity: float

    @property
    def columns(self) -> slice:
        """The bodies' lagged-force columns."""
        return slice(self.first, self.first + len(self.bodies))

    def with_columns(self, p: Particles) -> Particles:
        """Particles with one lagged-force column per wall and body."""
        need = self.first + len(self.bodies)
        have = p.wall_force.shape[1]
        if have >= need:
            return p
        pad = np.zeros((p.n, need - have))
        return p.replace(wall_force=np.concatenate([p.wall_force, pad], axis=1))

    def without_spanned(
        self,
        x: np.ndarray,
        active: np.ndarray,
        local_t: np.ndarray,
        time: float,
        sliver: float | None = None,
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """Drop the elements that span a rigid body; renumber the remaining nodes.

        An element whose vertices lie on both sides of a body (or that covers
        one) is not soil.

        Parameters
        ----------
        x : ndarray (N, d)
            Positions of all particles.
        active, local_t : ndarray
            The mesh source's mesh: its particles and its connectivity (d+1, ne)
            in numbers local to ``active``.
        time : float
            Time at the start of the step, s (where the bodies are).
        sliver : float or None
            How deep (a fraction of an element's mean edge) an element may cut
            a corner of a plane-strain or axisymmetric body and stay
            (:func:`~skfem_npfem.boundary.spanning.spanning_elements`; None:
            :data:`~skfem_npfem.boundary.spanning.CLIP_DEPTH`); 0 drops every
            element that cuts into a body.

        Returns
        -------
        active, local_t : ndarray
            The mesh without the spanning elements (particles in no element
            left out, the connectivity renumbered).
        dropped : int
            Number of elements dropped.
        """
        sliver = CLIP_DEPTH if sliver is None else sliver
        if self.dim == 3:
            drop = spanning_tetrahedra(self.bodies, x[active], local_t, time)
        else:
            drop = spanning_elements(self.bodies, x[active], local_t, time, sliver)
        if not np.any(drop):
            return active, local_t, 0
        local_t = local_t[:, ~drop]
        used = np.unique(local_t)
        if used.size == 0:
            raise ParameterError(
                "bodies",
                [b.name for b in self.bodies],
                "bodies that leave some soil: every element of the mesh spans a body",
            )
        return active[used], np.searchsorted(used, local_t), int(drop.sum())

    def contacts(
        self, nodes: ContactNodes, dt: float, h: float, time: float
    ) -> tuple[Contacts, np.ndarray]:
        """The rigid-body rows of one step on any set of displacement nodes.

        The particles of N-PFEM, the P1 or P2 nodes of FEM-remap:
        :func:`~skfem_npfem.boundary.contact.body_contacts` (with the bodies'
        corners in 2D), the lagged normal forces of the body columns, adhesion
        and friction as the bodies define them.

        Returns
        -------
        Contacts, ndarray (nc,) int
            The candidates and their columns; body ``k`` is ``first + k``.
        """
        cols = self.columns
        bc, body_ids = body_contacts(
            self.bodies,
            nodes.x,
            nodes.v,
            nodes.fixed,
            nodes.v_prescribed,
            nodes.lagged[:, cols],
            self._facets(nodes),
            dt,
            h,
            self.gravity,
            time,
            noise_ref=nodes.noise_ref[:, cols],
            axisymmetric=self.axisymmetric,
            corners=self.dim == 2,
        )
        return bc, self.first + body_ids

    def put_back(
        self,
        x: np.ndarray,
        v: np.ndarray,
        u: np.ndarray,
        friction: np.ndarray,
        t_end: float,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Particles that ended a step inside a body put back on its outline.

        Returns the positions, velocities and displacements (the same arrays
        when no particle was inside) and the deepest particle inside each body
        before the projection, m (n_bodies,).
        """
        xb, vb, depth = project_out_of_bodies(self.bodies, x, v, t_end)
        if xb is not x:
            return xb, vb, u + (xb - x), depth
        return x, v, u, depth

    def record(
        self,
        extra: dict[str, Any],
        contacts: Contacts,
        ids: np.ndarray,
        lambdas: tuple[np.ndarray, np.ndarray],
        x: np.ndarray,
        t_end: float,
        mark: np.ndarray | None,
        dropped: int,
    ) -> None:
        """Position, load and penetration of each body in the step's record.

        The keys are those of :func:`~skfem_npfem.step.stages.advance`
        (``<name>_x``, ``<name>_y``, ``<name>_force_x``, ``<name>_force_y``,
        ``<name>_moment``, ``<name>_penetration``, ``dropped_elements``; a 3D
        body has ``_z`` keys and a moment vector ``<name>_moment_x/_y/_z``).

        Parameters
        ----------
        extra : dict
            The record's ``extra``.
        contacts, ids : Contacts, ndarray (nc,) int
            The step's candidates and their columns (bodies after the walls).
        lambdas : (ndarray (nc,), ndarray (nc, d-1))
            Normal and tangential forces of the candidates.
        x : ndarray (n, d)
            Positions of the nodes the candidates index (start of the step).
        t_end : float
            Time at the end of the step, s.
        mark : ndarray (n_bodies,) or None
            The penetration depths from :meth:`put_back` (None: the particles
            were not moved).
        dropped : int
            Elements dropped by :meth:`without_spanned`.
        """
        sel = ids >= self.first
        sub = contacts.subset(sel)
        body_ids = ids[sel] - self.first
        lambda_n, lambda_t = lambdas[0][sel], lambdas[1][sel]
        extra["dropped_elements"] = dropped
        loads = body_loads(self.bodies, sub, body_ids, lambda_n, lambda_t, x, t_end)
        for k, (body, (force, moment)) in enumerate(
            zip(self.bodies, loads, strict=True)
        ):
            disp = body.displacement(t_end)
            if self.dim == 3:
                for i, axis in enumerate("xyz"):
                    extra[f"{body.name}_{axis}"] = float(disp[i])
                    extra[f"{body.name}_force_{axis}"] = float(force[i])
                    extra[f"{body.name}_moment_{axis}"] = float(moment[i])
            else:
                extra[f"{body.name}_x"] = float(disp[0])
                extra[f"{body.name}_y"] = float(disp[1])
                # A body of revolution takes no net radial force.
                extra[f"{body.name}_force_x"] = (
                    0.0 if self.axisymmetric else float(force[0])
                )
                extra[f"{body.name}_force_y"] = float(force[1])
                extra[f"{body.name}_moment"] = 0.0 if self.axisymmetric else moment
            extra[f"{body.name}_penetration"] = 0.0 if mark is None else float(mark[k])

    def _facets(self, nodes: ContactNodes) -> np.ndarray:
        """The boundary the body rows need: oriented edges (2D), faces (3D)."""
        if nodes.facets is not None:
            return nodes.facets()
        if self.dim == 2:
            return oriented_boundary(nodes.x, nodes.local_t)
        if any(b.adhesion > 0 for b in self.bodies):
            return boundary_faces(nodes.local_t)
        return np.zeros((3, 0), int)
