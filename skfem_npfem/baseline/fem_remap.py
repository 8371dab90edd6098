"""FEM-remap: the classical PFEM with Gauss-point state and remapping.

The particles are the vertices of the mesh, as in N-PFEM, but the stress and
the equivalent plastic strain live at the Gauss points of P1 (one point) or P2
(six-node triangles, ten-node tets; three/four points) elements built with
scikit-fem (:mod:`skfem_npfem.baseline.operators`).  Each step:

1. the mesh source (fixed connectivity or alpha-shape remesher) gives the
   step's mesh;
2. if it differs from the mesh the Gauss-point state lives on, the state is
   transferred to the new Gauss points (``transfer="nearest"`` or
   ``"recovery"``, :mod:`skfem_npfem.baseline.transfer`) and mapped stresses
   outside the yield cone are returned to it in closed form
   (:func:`~skfem_npfem.baseline.returnmap.return_map`); the number returned
   by more than :data:`VIOLATION_TOL` of the stress level is reported as
   ``yield_violations`` on the step record;
3. the library's cone step :func:`skfem_npfem.step.conic.solve_step` is solved with
   the Gauss points as stress points (:class:`~.operators.StressPoints`) and
   the nodal data of :mod:`skfem_npfem.baseline.fem_nodes`;
4. Gauss-point stresses are rotated with the Gauss-point spin (the library's
   Hughes-Winget rotation), the particles move with the vertex increments
   (:func:`skfem_npfem.step.update.move_particles`), and nodal stresses for output are
   recovered from the Gauss points by patch recovery.

So a comparison with N-PFEM isolates integration and mapping: the program,
the solver, the contact rules and the particle update are the same code.

Walls and rigid bodies (``model.boundaries``) enter as in N-PFEM, through the
same jobs of :mod:`skfem_npfem.step.boundary_jobs`: the elements that span a
body are dropped before the state is remapped
(:func:`~skfem_npfem.step.boundary_jobs.without_spanned`), the body contact
rows follow the wall rows
(:func:`~skfem_npfem.step.boundary_jobs.step_contacts`: the body's faces
against the soil's boundary nodes and its corners against the boundary
edges, friction or adhesion bounded with the lagged normal forces of the
body's column), the particles that end a step behind a wall or inside a
body are put back (:func:`~skfem_npfem.step.boundary_jobs.put_back`) and the
body's position, force, moment and penetration go on the step record under
the same keys (:func:`~skfem_npfem.step.boundary_jobs.record`).

With P2 elements the body rows act on the displacement nodes on the soil's
boundary, the vertices *and* the mid-side nodes, as the wall rows of
:mod:`skfem_npfem.baseline.fem_nodes` do: a mid-side node that only
followed its end vertices could bulge into a flat body (the consistent
load of a uniform contact pressure puts two thirds of each edge's force on
its mid-side node).  The boundary edges the bodies see are the half edges
vertex - mid-side node - vertex (straight, as the elements are); a corner
row interpolates linearly along a half edge.  A mid-side node's contact
force is stored half on each end particle, and its lagged normal force
comes back with the consistent shares
(:func:`~skfem_npfem.baseline.fem_nodes.split_wall_forces`), as for walls.
The adhesion area of a node is half its boundary half edges along the body
(``L/4, L/2, L/4`` of an edge of length ``L``, not the consistent ``L/6,
2L/3, L/6``): the total along a face is right, its split between vertices
and mid-side nodes is not the consistent one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from time import perf_counter

import numpy as np

from ..boundary import CLIP_DEPTH, Boundary, ContactNodes, oriented_boundary
from ..errors import ParameterError
from ..mesh.sources import MeshSource, mesh_particles
from ..particles import Particles
from ..step.boundary_jobs import record, step_contacts, with_columns, without_spanned
from ..step.conic import ConeSolution, solve_step
from ..step.kinematics import equivalent_strain, rotate_stress
from ..step.model import Model
from ..step.program import ConeInput
from ..step.stages import Step, StepRecord, StepState
from ..step.update import move_particles
from .fem_nodes import element_material, gauss_points, node_data, to_particles
from .operators import ELEMENTS, GaussMesh, gauss_mesh, quadrature
from .returnmap import return_map
from .transfer import TRANSFERS, recover_nodal, transfer_values

__all__ = ["VIOLATION_TOL", "FemRemap", "GaussState"]

#: A mapped stress counts as a yield violation when its return to the cone
#: changes it by more than this fraction of the largest mapped stress.
VIOLATION_TOL = 1e-6


@dataclass(frozen=True)
class GaussState(Particles):
    """Particles plus the Gauss-point state of the mesh it lives on.

    Attributes
    ----------
    cells : ndarray (ne, d+1) int
        Elements (global particle indices) of the mesh of the last step.
    gp_stress : ndarray (ne * nq, n_full)
        Gauss-point stresses (point ``e * nq + q``), Pa.
    gp_eps_p : ndarray (ne * nq,)
        Gauss-point equivalent plastic strain.

    Notes
    -----
    :attr:`stress` and :attr:`eps_p` of the particles are recovered from the
    Gauss points (for output); the Gauss-point arrays are the state.  All
    three arrays are fields, so checkpoints keep them and
    :meth:`~skfem_npfem.run.simulation.Simulation.restore` reads them back.
    """

    cells: np.ndarray
    gp_stress: np.ndarray
    gp_eps_p: np.ndarray

    @property
    def nq(self) -> int:
        """Gauss points per element."""
        return self.gp_stress.shape[0] // max(self.cells.shape[0], 1)

    def validate(self) -> None:
        """Particle checks plus the shapes of the Gauss-point state."""
        super().validate()
        ne, nv = self.cells.shape
        n_gp = self.gp_stress.shape[0]
        bad = (
            self.cells.dtype.kind not in "iu"
            or nv != self.dim + 1
            or (ne and (self.cells.min() < 0 or self.cells.max() >= self.n))
            or self.gp_stress.ndim != 2
            or self.gp_stress.shape[1] != self.stress.shape[1]
            or (ne and n_gp % ne)
            or self.gp_eps_p.shape != (n_gp,)
            or not np.all(np.isfinite(self.gp_stress))
            or not np.all(np.isfinite(self.gp_eps_p))
        )
        if bad:
            raise ParameterError(
                "state",
                (self.cells.shape, self.gp_stress.shape, self.gp_eps_p.shape),
                "cells (ne, d+1) of particle indices, gp_stress (ne*nq, n_full) "
                "and gp_eps_p (ne*nq,), finite",
            )


@dataclass(frozen=True)
class FemRemap:
    """The classical PFEM baseline (see the module docstring).

    Parameters
    ----------
    element : {"p1", "p2"}
        Linear or quadratic elements.
    transfer : {"nearest", "recovery"}
        How Gauss-point variables move to a new mesh.

    Examples
    --------
    >>> FemRemap("p2", "recovery").element
    'p2'
    """

    element: str = "p1"
    transfer: str = "recovery"

    def __post_init__(self) -> None:
        if self.element not in ELEMENTS:
            raise ParameterError("element", self.element, f"one of {ELEMENTS}")
        if self.transfer not in TRANSFERS:
            raise ParameterError("transfer", self.transfer, f"one of {TRANSFERS}")

    # -- state ----------------------------------------------------------------
    def initial_state(self, p: Particles, mesh_source: MeshSource) -> GaussState:
        """Gauss-point state interpolated (P1) from the particles' stress.

        The particles' stress and plastic strain are interpolated linearly at
        the Gauss points of the mesh ``mesh_source`` gives for ``p.x``, so a
        linear initial stress (geostatic) is taken over exactly.
        """
        active, local_t = mesh_particles(mesh_source, p)
        cells = np.ascontiguousarray(active[local_t].T)
        bary, _ = quadrature(p.dim, self.element)
        sig = np.einsum("qa,eam->eqm", bary, p.stress[cells]).reshape(
            -1, p.stress.shape[1]
        )
        eps = np.einsum("qa,ea->eq", bary, p.eps_p[cells]).reshape(-1)
        fields = {f: getattr(p, f) for f in Particles.__dataclass_fields__}
        return GaussState(**fields, cells=cells, gp_stress=sig, gp_eps_p=eps)

    def remap(
        self, state: GaussState, cells: np.ndarray, model: Model
    ) -> tuple[np.ndarray, np.ndarray, dict]:
        """Gauss-point state on new ``cells`` (transfer + return to the cones).

        Returns
        -------
        gp_stress, gp_eps_p : ndarray
            On the new Gauss points.
        info : dict
            ``remapped`` (0 or 1), ``yield_violations`` (mapped stresses
            returned to a cone), ``outside_old_mesh`` (points given the nearest
            value).
        """
        if state.cells.shape == cells.shape and np.array_equal(state.cells, cells):
            info = {"remapped": 0, "yield_violations": 0, "outside_old_mesh": 0}
            return state.gp_stress, state.gp_eps_p, info
        x = state.x
        old_gp = gauss_points(x, state.cells, self.element)
        if old_gp.shape[0] != state.gp_stress.shape[0]:
            raise ParameterError(
                "element", self.element, f"the element of the state ({state.nq} points)"
            )
        new_gp = gauss_points(x, cells, self.element)
        values = np.concatenate([state.gp_stress, state.gp_eps_p[:, None]], axis=1)
        moved, outside = transfer_values(
            self.transfer, x, state.cells, old_gp, values, new_gp
        )
        sig, eps = moved[:, :-1], np.maximum(moved[:, -1], 0.0)
        nq = new_gp.shape[0] // cells.shape[0]
        mat = np.repeat(element_material(state.material, cells), nq)
        back = return_map(model.materials, mat, model.dim, sig, sig)
        # Count what the mapping did, not the cone step's own tolerance: a
        # stress on the yield surface is on it to ~1e-8 of the stress scale
        # after a solve (near a cohesionless free surface that is a lot
        # relative to the point's own small stress).
        change = np.linalg.norm(back.sigma - sig, axis=1)
        scale = np.max(np.linalg.norm(sig, axis=1), initial=0.0)
        big = change > VIOLATION_TOL * scale
        info = {
            "remapped": 1,
            "yield_violations": int(np.count_nonzero(back.plastic & big)),
            "outside_old_mesh": outside,
        }
        return back.sigma, eps, info

    # -- step -----------------------------------------------------------------
    def check_state(self, state: Particles, model: Model, dt: float) -> None:
        """Raise :class:`ParameterError` unless ``state`` fits this method."""
        if not (math.isfinite(dt) and dt > 0):
            raise ParameterError("dt", dt, "a finite time step > 0 (s)")
        if not isinstance(state, GaussState):
            raise ParameterError(
                "state", type(state).__name__, "a GaussState (FemRemap.initial_state)"
            )
        if state.dim != model.dim:
            raise ParameterError("state", f"{state.dim}D", f"{model.dim}D positions")
        model.refuse_loads("FEM-remap")
        nq = quadrature(model.dim, self.element)[1].size
        if state.gp_stress.shape[0] != nq * state.cells.shape[0]:
            raise ParameterError(
                "element",
                self.element,
                f"the element of the state ({state.nq} Gauss points per element, "
                f"{self.element} has {nq}): use the FemRemap that made the state",
            )

    def advance(
        self,
        state: GaussState,
        model: Model,
        dt: float,
        mesh_source: MeshSource,
        step: int | None = None,
        start: StepState | None = None,
    ) -> tuple[GaussState, Step]:
        """Advance one step (the counterpart of :func:`skfem_npfem.advance`).

        Parameters
        ----------
        state : GaussState
            From :meth:`initial_state` or the previous step.
        model : Model
        dt : float
            Time step, s.
        mesh_source : MeshSource
            ``x -> (active, local_t)``.
        step : int, optional
            Step index (for error messages).
        start : StepState, optional
            The state at the start of the step (the previous step's
            ``result.state``): its time is where the model's rigid bodies
            are.  None: time 0.

        Returns
        -------
        GaussState, Step
            ``result.record.extra`` holds ``remapped``, ``yield_violations``
            and ``outside_old_mesh`` (and, with rigid bodies, the body keys of
            :func:`skfem_npfem.advance`); ``result.solution`` is on the
            particles (recovered nodal stresses, mid-edge reactions split to
            the ends); ``result.operator`` is the Gauss-point operator;
            ``result.state`` the state at the end of the step.
        """
        self.check_state(state, model, dt)
        start = StepState() if start is None else start
        t_start = float(start.time)
        boundaries = model.boundaries
        state = with_columns(boundaries, state)
        t0 = perf_counter()
        active, local_t = mesh_particles(mesh_source, state)
        # P2: no sliver, its mid-edge node would start inside the body.
        sliver = CLIP_DEPTH if self.element == "p1" else 0.0
        active, local_t, dropped = without_spanned(
            boundaries, state.x, active, local_t, t_start, sliver
        )
        cells = np.ascontiguousarray(active[local_t].T)
        ta = perf_counter()
        sig_gp, eps_gp, info = self.remap(state, cells, model)
        t_map = perf_counter() - ta
        gm = gauss_mesh(state.x[active], local_t, self.element, model.components)
        data, wall_ids = self._step_data(
            state, model, boundaries, dt, gm, active, local_t, cells, sig_gp, t_start
        )
        t1 = perf_counter()
        sol = solve_step(data, model.solver, step=step)
        t2 = perf_counter()
        new, out, marks = self._update(
            state, model, boundaries, dt, gm, active, cells, sol, eps_gp, t_start
        )
        new = new.replace(
            wall_force=self._wall_forces(state, gm, active, data, wall_ids, sol)
        )
        timings = {
            "mesh": t1 - t0 - t_map,
            "transfer": t_map,
            **sol.timings,
            "update": perf_counter() - t2,
        }
        rec = StepRecord.of_step(
            step, dt, new, model.gravity, active, gm.points, sol, timings, **info
        )
        record(
            boundaries,
            rec.extra,
            data.contacts,
            wall_ids,
            (sol.lambda_n, sol.lambda_t),
            gm.node_x,
            t_start + dt,
            marks,
            dropped,
        )
        end = start.after(dt, None)
        return new, Step(rec, out, active, local_t, gm.points, new, end)

    def _step_data(
        self,
        state,
        model,
        boundaries: list[Boundary],
        dt,
        gm: GaussMesh,
        active,
        local_t,
        cells,
        sig_gp,
        t,
    ):
        """The cone step's data on the Gauss points, and each contact's wall."""
        nodes = node_data(state, model, gm, active)
        vol_e = gm.points.volumes.reshape(-1, gm.nq).sum(axis=1)
        h = float(np.mean(vol_e)) ** (1 / model.dim)
        # The noise level of the lagged forces, one per column: the walls'
        # from the nodes' own lagged forces, the bodies' from the particles'.
        level = np.max(np.abs(state.wall_force), axis=0, initial=0.0)
        nw = len(model.walls)
        level[:nw] = np.max(np.abs(nodes.lagged[:, :nw]), axis=0, initial=0.0)
        contact_nodes = ContactNodes(
            x=gm.node_x,
            v=nodes.v,
            fixed=nodes.fixed,
            v_prescribed=nodes.v_prescribed,
            lagged=nodes.lagged,
            noise_ref=level[None],
            local_t=local_t,
            facets=lambda: _boundary_half_edges(gm, local_t),
        )
        contacts, wall_ids = step_contacts(boundaries, contact_nodes, dt, h, t)
        data = ConeInput(
            operator=gm.points,
            materials=model.materials,
            material=np.repeat(element_material(state.material, cells), gm.nq),
            sigma_n=sig_gp,
            force=nodes.force,
            fixed=nodes.fixed,
            du_prescribed=nodes.v_prescribed * dt,
            contacts=contacts,
            dt=dt,
            mass=nodes.mass,
            v_n=nodes.v,
            theta1=model.theta1,
            theta2=model.theta2,
            dynamic=model.mode == "dynamic",
            stress_scale=model.stress_scale,
        )
        return data, wall_ids

    def _update(
        self, state, model, boundaries, dt, gm: GaussMesh, active, cells, sol, eps_gp, t
    ):
        """Rotate Gauss-point stresses, recover nodal output, move particles."""
        sig = sol.sigma
        if model.objective_rotation:
            sig = rotate_stress(sig, gm.points.gradient(sol.du))
        eps = eps_gp + equivalent_strain(sol.deps_p)
        nv = gm.n_vertices
        nodal = recover_nodal(
            state.x[active], gm.mesh.t.T, gm.gp_x, np.column_stack([sig, eps])
        )
        stress = state.stress.copy()
        stress[active] = nodal[:, :-1]
        eps_p = state.eps_p.copy()
        eps_p[active] = np.maximum(nodal[:, -1], 0.0)
        motion, marks = move_particles(
            state,
            model,
            dt,
            active,
            sol.du[:nv],
            model.mode == "dynamic",
            boundaries,
            t + dt,
        )
        new = state.replace(
            **motion,
            stress=stress,
            eps_p=eps_p,
            cells=cells,
            gp_stress=sig,
            gp_eps_p=eps,
        )
        out = ConeSolution(
            du=sol.du[:nv],
            sigma=nodal[:, :-1],
            deps_p=np.zeros_like(nodal[:, :-1]),
            reaction=to_particles(gm, sol.reaction),
            lambda_n=sol.lambda_n,
            lambda_t=sol.lambda_t,
            status=sol.status,
            iterations=sol.iterations,
            timings=sol.timings,
            sizes=sol.sizes,
        )
        return new, out, marks

    def _wall_forces(self, state, gm: GaussMesh, active, data, wall_ids, sol):
        """Lagged normal forces per particle (mid-edge forces split to the ends)."""
        wall = np.zeros_like(state.wall_force)
        contacts = data.contacts
        if not contacts.size:
            return wall
        per_node = np.zeros((gm.node_x.shape[0], wall.shape[1]))
        # A body's corner row pushes on two nodes of an edge (weights 1 - s, s).
        nodes, w, _ = contacts.weights()
        np.add.at(per_node, (nodes, wall_ids[:, None]), w * sol.lambda_n[:, None])
        wall[active] = to_particles(gm, per_node)
        return wall


def _boundary_half_edges(gm: GaussMesh, local_t: np.ndarray) -> np.ndarray:
    """Boundary edges (2, nb) of the displacement nodes, the mesh on their left.

    P1: the mesh's boundary edges.  P2: each split at its mid-side node
    (vertex - mid-side node - vertex), so that the bodies see every boundary
    node of the element.
    """
    x = gm.node_x[: gm.n_vertices]
    facets = oriented_boundary(x, local_t)
    if gm.element == "p1" or not facets.size:
        return facets
    nv = gm.n_vertices
    key = np.sort(gm.edges, axis=1) @ np.array([nv, 1])
    order = np.argsort(key)
    want = np.sort(facets, axis=0).T @ np.array([nv, 1])
    mid = nv + order[np.searchsorted(key, want, sorter=order)]
    return np.concatenate([np.stack([facets[0], mid]), np.stack([mid, facets[1]])], 1)
