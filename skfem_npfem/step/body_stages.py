"""The rigid bodies' part of a step, shared by every method on a particle mesh.

N-PFEM (:func:`~skfem_npfem.step.stages.advance`) and FEM-remap
(:class:`~skfem_npfem.baseline.FemRemap`) call the same functions: elements
spanning a body are dropped, the body rows join the wall rows with the
bodies' lagged normal forces, particles that end a step inside a body are put
back on it, and the record gets each body's position, load and penetration.
2D bodies are :class:`~skfem_npfem.RigidBody` polygons; 3D ones
:class:`~skfem_npfem.RigidPlane` and :class:`~skfem_npfem.BodyOfRevolution`.
"""

from __future__ import annotations

import numpy as np

from ..bodies import (
    CLIP_DEPTH,
    body_contacts,
    body_loads,
    boundary_faces,
    oriented_boundary,
    project_out_of_bodies,
    solid_contacts,
    solid_loads,
    spanning_elements,
    spanning_tetrahedra,
)
from ..boundary import Contacts
from ..errors import ParameterError
from ..particles import Particles
from .conic import ConeSolution
from .model import Model
from .records import StepRecord

__all__ = [
    "add_body_contacts",
    "keep_out_of_bodies",
    "record_bodies",
    "with_body_columns",
    "with_body_contacts",
    "without_body_elements",
]


def without_body_elements(
    model: Model,
    x: np.ndarray,
    active: np.ndarray,
    local_t: np.ndarray,
    time: float,
    sliver: float = CLIP_DEPTH,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Drop the elements that span a rigid body; renumber the remaining nodes.

    Shared by every method that steps on a mesh of the particles (N-PFEM,
    FEM-remap): an element whose vertices lie on both sides of a body (or
    that covers one) is not soil.

    Parameters
    ----------
    model : Model
        Its :attr:`~skfem_npfem.step.model.Model.bodies`.
    x : ndarray (N, d)
        Positions of all particles.
    active, local_t : ndarray
        The mesh source's mesh: its particles and its connectivity (d+1, ne)
        in numbers local to ``active``.
    time : float
        Time at the start of the step, s (where the bodies are).
    sliver : float
        How deep (a fraction of an element's mean edge) an element may cut a
        corner of a plane-strain or axisymmetric body and stay
        (:func:`~skfem_npfem.bodies.spanning_elements`); 0 drops every element
        that cuts into a body.

    Returns
    -------
    active, local_t : ndarray
        The mesh without the spanning elements (particles in no element left
        out, the connectivity renumbered).
    dropped : int
        Number of elements dropped.
    """
    if model.dim == 3:
        drop = spanning_tetrahedra(model.bodies, x[active], local_t, time)
    else:
        drop = spanning_elements(model.bodies, x[active], local_t, time, sliver)
    if not np.any(drop):
        return active, local_t, 0
    local_t = local_t[:, ~drop]
    used = np.unique(local_t)
    if used.size == 0:
        raise ParameterError(
            "bodies",
            [b.name for b in model.bodies],
            "bodies that leave some soil: every element of the mesh spans a body",
        )
    return active[used], np.searchsorted(used, local_t), int(drop.sum())


def with_body_contacts(
    model: Model,
    p: Particles,
    active: np.ndarray,
    local_t: np.ndarray,
    dt: float,
    h: float,
    time: float,
    contacts: Contacts,
    wall_ids: np.ndarray,
) -> tuple[Contacts, np.ndarray]:
    """The wall candidates followed by the rigid-body ones (ids after the walls)."""
    x = p.x[active]
    return add_body_contacts(
        model,
        contacts,
        wall_ids,
        x,
        p.v[active],
        p.fixed[active],
        p.v_prescribed[active],
        p.wall_force[active],
        _facets(model, x, local_t),
        dt,
        h,
        time,
        noise_ref=p.wall_force,
    )


def add_body_contacts(
    model: Model,
    contacts: Contacts,
    wall_ids: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    fixed: np.ndarray,
    v_prescribed: np.ndarray,
    lagged: np.ndarray,
    facets: np.ndarray,
    dt: float,
    h: float,
    time: float,
    noise_ref: np.ndarray,
) -> tuple[Contacts, np.ndarray]:
    """The wall candidates followed by the rigid-body ones (ids after the walls).

    The body rows of one step on any set of displacement nodes (the
    particles of N-PFEM, the P1 or P2 nodes of FEM-remap):
    :func:`~skfem_npfem.bodies.body_contacts` with the bodies' corners, the
    lagged normal forces of the body columns, adhesion and friction as the
    bodies define them.

    Parameters
    ----------
    model : Model
        Its walls (how many) and bodies.
    contacts, wall_ids : Contacts, ndarray (nc,) int
        The wall candidates of the step and the wall of each.
    x, v, fixed, v_prescribed : ndarray (n, d)
        Positions, velocities, prescribed dofs and their velocities of the
        nodes at the start of the step.
    lagged : ndarray (n, n_columns)
        Lagged normal forces of the nodes, one column per wall then per body
        (:func:`with_body_columns`), N.
    facets : ndarray (2, nb) or (3, nf)
        Boundary edges of the nodes' mesh with the mesh on their left
        (:func:`~skfem_npfem.bodies.oriented_boundary`); in 3D the boundary
        triangles (:func:`~skfem_npfem.bodies.boundary_faces`, read for
        Tresca adhesion only).
    dt, h, time : float
        Step (s), spacing (m), time at the start of the step (s).
    noise_ref : ndarray (m, n_columns)
        Forces that set the noise level of ``lagged`` (all particles' columns).

    Returns
    -------
    Contacts, ndarray (nc',) int
        All candidates and their walls; body ``k`` is ``len(model.walls) + k``.
    """
    nw = len(model.walls)
    cols = slice(nw, nw + len(model.bodies))
    if model.dim == 3:
        bc, body_ids = solid_contacts(
            model.bodies,
            x,
            v,
            fixed,
            v_prescribed,
            lagged[:, cols],
            facets,
            dt,
            h,
            model.gravity,
            time,
            noise_ref=noise_ref[:, cols],
        )
        return Contacts.concat([contacts, bc]), np.concatenate(
            [wall_ids, nw + body_ids]
        )
    bc, body_ids = body_contacts(
        model.bodies,
        x,
        v,
        fixed,
        v_prescribed,
        lagged[:, cols],
        facets,
        dt,
        h,
        model.gravity,
        time,
        noise_ref=noise_ref[:, cols],
        axisymmetric=model.axisymmetric,
        corners=True,
    )
    return Contacts.concat([contacts, bc]), np.concatenate([wall_ids, nw + body_ids])


def with_body_columns(p: Particles, model: Model) -> Particles:
    """Particles with one lagged-force column per wall and body."""
    need = len(model.walls) + len(model.bodies)
    have = p.wall_force.shape[1]
    if have >= need:
        return p
    pad = np.zeros((p.n, need - have))
    return p.replace(wall_force=np.concatenate([p.wall_force, pad], axis=1))


def keep_out_of_bodies(
    model: Model, new: Particles, t_end: float
) -> tuple[Particles, np.ndarray | None]:
    """Particles that ended a step inside a body put back on its outline.

    Returns
    -------
    Particles
        ``new``, or a copy with the projected positions, velocities and
        displacements.
    ndarray (n_bodies,) or None
        Deepest particle inside each body before the projection, m (None
        without bodies or with ``update_geometry`` off).
    """
    if not (model.bodies and model.update_geometry):
        return new, None
    x, v, depth = project_out_of_bodies(model.bodies, new.x, new.v, t_end)
    if x is not new.x:
        new = new.replace(x=x, v=v, u=new.u + (x - new.x))
    return new, depth


def record_bodies(
    rec: StepRecord,
    model: Model,
    contacts: Contacts,
    wall_ids: np.ndarray,
    sol: ConeSolution,
    x: np.ndarray,
    t_end: float,
    depth: np.ndarray | None,
    dropped: int,
) -> None:
    """Position, load and penetration of each body in the step's record.

    The keys are those of :func:`~skfem_npfem.step.stages.advance`
    (``<name>_x``, ``<name>_y``, ``<name>_force_x``, ``<name>_force_y``,
    ``<name>_moment``, ``<name>_penetration``, ``dropped_elements``; a 3D
    body has ``_z`` keys and a moment vector ``<name>_moment_x/_y/_z``).

    Parameters
    ----------
    rec : StepRecord
        The record to fill (its ``extra``).
    model : Model
    contacts, wall_ids : Contacts, ndarray (nc,) int
        The step's candidates and their walls (bodies after the walls).
    sol : ConeSolution
        Its ``lambda_n`` and ``lambda_t`` per candidate.
    x : ndarray (n, d)
        Positions of the nodes the candidates index (start of the step).
    t_end : float
        Time at the end of the step, s.
    depth : ndarray (n_bodies,) or None
        From :func:`keep_out_of_bodies`.
    dropped : int
        Elements dropped by :func:`without_body_elements`.
    """
    nw = len(model.walls)
    sel = wall_ids >= nw
    sub = contacts.subset(sel)
    rec.extra["dropped_elements"] = dropped
    if model.dim == 3:
        _record_solids(rec, model, sub, wall_ids[sel] - nw, sol, sel, x, t_end, depth)
        return
    loads = body_loads(
        model.bodies,
        sub,
        wall_ids[sel] - nw,
        sol.lambda_n[sel],
        sol.lambda_t[sel],
        x,
        t_end,
    )
    for k, (body, (force, moment)) in enumerate(zip(model.bodies, loads, strict=True)):
        disp = body.displacement(t_end)
        rec.extra[f"{body.name}_x"] = float(disp[0])
        rec.extra[f"{body.name}_y"] = float(disp[1])
        # A body of revolution takes no net radial force.
        rec.extra[f"{body.name}_force_x"] = (
            0.0 if model.axisymmetric else float(force[0])
        )
        rec.extra[f"{body.name}_force_y"] = float(force[1])
        rec.extra[f"{body.name}_moment"] = 0.0 if model.axisymmetric else moment
        rec.extra[f"{body.name}_penetration"] = (
            0.0 if depth is None else float(depth[k])
        )


def _record_solids(
    rec: StepRecord,
    model: Model,
    sub: Contacts,
    body_ids: np.ndarray,
    sol: ConeSolution,
    sel: np.ndarray,
    x: np.ndarray,
    t_end: float,
    depth: np.ndarray | None,
) -> None:
    """Position, force and moment vectors and penetration of each 3D body."""
    loads = solid_loads(
        model.bodies, sub, body_ids, sol.lambda_n[sel], sol.lambda_t[sel], x, t_end
    )
    for k, (body, (force, moment)) in enumerate(zip(model.bodies, loads, strict=True)):
        disp = body.displacement(t_end)
        for i, axis in enumerate("xyz"):
            rec.extra[f"{body.name}_{axis}"] = float(disp[i])
            rec.extra[f"{body.name}_force_{axis}"] = float(force[i])
            rec.extra[f"{body.name}_moment_{axis}"] = float(moment[i])
        rec.extra[f"{body.name}_penetration"] = (
            0.0 if depth is None else float(depth[k])
        )


def _facets(model: Model, x: np.ndarray, local_t: np.ndarray) -> np.ndarray:
    """The boundary the body rows need: oriented edges (2D), faces for adhesion (3D)."""
    if model.dim == 2:
        return oriented_boundary(x, local_t)
    if any(b.adhesion > 0 for b in model.bodies):
        return boundary_faces(local_t)
    return np.zeros((3, 0), int)
