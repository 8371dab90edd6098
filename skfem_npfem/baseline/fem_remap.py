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
   (:func:`~skfem_npfem.baseline.returnmap.return_map`); their number is
   reported as ``yield_violations`` on the step record;
3. the same cone program as N-PFEM is solved with Gauss-point stresses
   (:func:`~skfem_npfem.baseline.program.solve_gauss_step`);
4. Gauss-point stresses are rotated with the Gauss-point spin (the library's
   Hughes-Winget rotation), the particles move with the vertex increments
   (the library's θ-scheme update), and nodal stresses for output are
   recovered from the Gauss points by patch recovery.

P2 specifics (the mid-edge nodes are displacement nodes, not particles): their
velocity, prescribed motion and fixity are those of the straight edge (mean of
the two end particles; fixed only when both ends are); masses are HRZ-lumped
from the element density ``rho_e``, the density of the element's material (a
particle-based density ``sum m_i / sum V_i`` over its vertices only for
materials with ``rho = 0``: with alpha-shape meshes the cell volumes ``V_i``
change with the diagonals, by up to +-30 % on a lattice, so particle masses
over current cells are a noisy density); gravity is the consistent load ``int
rho_e g phi_j`` in static steps (exact for the geostatic column) and the lumped
``m_j g`` in dynamic ones (the consistent load puts no weight on triangle
vertices, so with lumped inertia a falling body would stretch; the lumped load
makes free fall exact and costs an O(h) stress error at rest, 0.5 % on the
elastic column with 20 elements over its height); a wall contact force on a
mid-edge node is stored half on each end particle, and the lagged friction
bound is split back with the consistent P2 shares (``_split_wall_forces``): the
total bound is ``mu`` times the total stored force, as for P1 and N-PFEM.

P1 uses the particle masses and ``m g``, exactly as N-PFEM.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..particles import Particles
from ..simulation import (
    MeshSource,
    Model,
    StepRecord,
    energies,
    equivalent_strain,
    rotate_stress,
)
from .common import node_contacts, update_particles
from .operators import (
    ELEMENTS,
    GaussMesh,
    body_force,
    gauss_mesh,
    lumped_masses,
    quadrature,
)
from .program import GaussStepData, solve_gauss_step
from .returnmap import return_map
from .transfer import TRANSFERS, recover_nodal, transfer_values

__all__ = ["FemRemap", "GaussState"]


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
    Gauss points (for output); the Gauss-point arrays are the state.
    """

    cells: np.ndarray
    gp_stress: np.ndarray
    gp_eps_p: np.ndarray

    @property
    def nq(self) -> int:
        """Gauss points per element."""
        return self.gp_stress.shape[0] // max(self.cells.shape[0], 1)


def _element_material(material: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Most frequent material among an element's vertices (ties: first vertex)."""
    m = material[cells]  # (ne, d+1)
    counts = (m[:, :, None] == m[:, None, :]).sum(axis=2)
    return m[np.arange(m.shape[0]), np.argmax(counts, axis=1)]


def _split_wall_forces(lam, active, a, b) -> np.ndarray:
    """Lagged wall forces of P2 nodes from the per-particle stored forces.

    An edge lies on a wall when both ends touched it.  With ``k_i`` such edges
    at particle ``i``, the vertex gets ``lam_i / 3`` (``lam_i`` if ``k_i = 0``)
    and an edge's mid-node ``2/3 (lam_a / k_a + lam_b / k_b)``: the consistent
    P2 shares (1/6, 2/3, 1/6 of ``p L`` per edge) under a uniform pressure,
    and in every case the total equals the total stored force.
    """
    noise = 1e-8 * np.max(np.abs(lam), axis=0, initial=0.0)
    on = (lam[a] > noise) & (lam[b] > noise)  # (n_edges, n_walls)
    k = np.zeros(lam.shape)
    for ends in (a, b):  # the two ends of every edge
        np.add.at(k, ends, on.astype(float))
    per_edge = np.divide(lam, k, out=np.zeros(lam.shape), where=k > 0)
    vertex = np.where(k[active] > 0, lam[active] / 3.0, lam[active])
    mid = np.where(on, 2.0 / 3.0 * (per_edge[a] + per_edge[b]), 0.0)
    return np.concatenate([vertex, mid])


def _gauss_points(x: np.ndarray, cells: np.ndarray, element: str) -> np.ndarray:
    """Gauss-point coordinates (ne * nq, d) of straight-sided elements."""
    bary, _ = quadrature(x.shape[1], element)
    return np.einsum("qa,ead->eqd", bary, x[cells]).reshape(-1, x.shape[1])


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
        active, local_t = mesh_source(p.x)
        cells = np.ascontiguousarray(active[local_t].T)
        bary, _ = quadrature(p.dim, self.element)
        sig = np.einsum("qa,eam->eqm", bary, p.stress[cells]).reshape(
            -1, p.stress.shape[1]
        )
        eps = np.einsum("qa,ea->eq", bary, p.eps_p[cells]).reshape(-1)
        fields = {f: getattr(p, f) for f in p.arrays()}
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
            ``remapped`` (bool), ``yield_violations`` (mapped stresses returned
            to a cone), ``outside_old_mesh`` (points given the nearest value).
        """
        if state.cells.shape == cells.shape and np.array_equal(state.cells, cells):
            info = {"remapped": False, "yield_violations": 0, "outside_old_mesh": 0}
            return state.gp_stress, state.gp_eps_p, info
        if state.nq * state.cells.shape[0] != state.gp_stress.shape[0]:
            raise ParameterError("state", state.gp_stress.shape, "ne * nq Gauss points")
        x = state.x
        old_gp = _gauss_points(x, state.cells, self.element)
        if old_gp.shape[0] != state.gp_stress.shape[0]:
            raise ParameterError(
                "element", self.element, f"the element of the state ({state.nq} points)"
            )
        new_gp = _gauss_points(x, cells, self.element)
        values = np.concatenate([state.gp_stress, state.gp_eps_p[:, None]], axis=1)
        moved, outside = transfer_values(
            self.transfer, x, state.cells, old_gp, values, new_gp
        )
        sig, eps = moved[:, :-1], np.maximum(moved[:, -1], 0.0)
        nq = new_gp.shape[0] // cells.shape[0]
        mat = np.repeat(_element_material(state.material, cells), nq)
        back = return_map(model.materials, mat, model.dim, sig, sig)
        info = {
            "remapped": True,
            "yield_violations": int(np.count_nonzero(back.plastic)),
            "outside_old_mesh": outside,
        }
        return back.sigma, eps, info

    # -- step -----------------------------------------------------------------
    def _node_data(self, state: GaussState, model: Model, gm: GaussMesh, active):
        """Masses, forces, fixity, velocities and lagged wall forces of nodes."""
        d, e = model.dim, gm.edges
        a, b = active[e[:, 0]], active[e[:, 1]]
        fixed = np.concatenate([state.fixed[active], state.fixed[a] & state.fixed[b]])
        vp = state.v_prescribed
        v_pres = np.concatenate([vp[active], 0.5 * (vp[a] + vp[b])])
        v = np.concatenate([state.v[active], 0.5 * (state.v[a] + state.v[b])])
        g = model.gravity_vector
        lam = state.wall_force
        if self.element == "p1":
            mass = state.mass[active]
            force = mass[:, None] * g[None, :]
            lagged = lam[active]
        else:
            t = gm.mesh.t
            rho_mat = np.array([m.rho for m in model.materials])
            rho_e = rho_mat[_element_material(state.material, active[t].T)]
            light = rho_e <= 0.0
            if np.any(light):  # weightless material: density of the particles
                vol_e = gm.points.weights.reshape(gm.n_elements, gm.nq).sum(axis=1)
                cell_v = np.bincount(
                    t.ravel(), np.tile(vol_e / (d + 1), d + 1), minlength=gm.n_vertices
                )
                m_act = state.mass[active]
                rho_e[light] = (m_act[t].sum(0) / cell_v[t].sum(0))[light]
            mass = lumped_masses(gm, rho_e)
            if model.mode == "static":
                force = body_force(gm, rho_e, g)
            else:  # lumped, so that free fall is exact (see module docstring)
                force = mass[:, None] * g[None, :]
            lagged = _split_wall_forces(lam, active, a, b)
        return mass, force, fixed, v_pres, v, lagged

    def advance(
        self,
        state: GaussState,
        model: Model,
        dt: float,
        mesh_source: MeshSource,
        step: int | None = None,
    ) -> tuple[GaussState, StepRecord]:
        """Advance one step (the counterpart of :func:`skfem_npfem.simulation.advance`).

        Parameters
        ----------
        state : GaussState
            From :meth:`initial_state` or a previous step.
        model : Model
            Materials, loads, walls, time integration, solver settings.
        dt : float
            Time step, s (pseudo-time in static mode).
        mesh_source : callable
            ``x -> (active, local_t)``.
        step : int, optional
            Step index for error messages.

        Returns
        -------
        GaussState, StepRecord
            ``record.extra`` holds ``remapped``, ``yield_violations`` and
            ``outside_old_mesh``.
        """
        if not (math.isfinite(dt) and dt > 0):
            raise ParameterError("dt", dt, "a finite time step > 0 (s)")
        if not isinstance(state, GaussState):
            raise ParameterError(
                "state", type(state).__name__, "a GaussState (FemRemap.initial_state)"
            )
        if state.dim != model.dim:
            raise ParameterError("state", f"{state.dim}D", f"{model.dim}D positions")
        nq = quadrature(model.dim, self.element)[1].size
        if state.gp_stress.shape[0] != nq * state.cells.shape[0]:
            raise ParameterError(
                "element",
                self.element,
                f"the element of the state ({state.nq} Gauss points per element, "
                f"{self.element} has {nq}): use the FemRemap that made the state",
            )
        t0 = time.perf_counter()
        active, local_t = mesh_source(state.x)
        cells = np.ascontiguousarray(active[local_t].T)
        ta = time.perf_counter()
        sig_gp, eps_gp, info = self.remap(state, cells, model)
        t_map = time.perf_counter() - ta
        gm = gauss_mesh(state.x[active], local_t, self.element, model.components)
        data, wall_ids = self._step_data(state, model, dt, gm, active, cells, sig_gp)
        t1 = time.perf_counter()
        sol = solve_gauss_step(data, model.solver, step=step)
        t2 = time.perf_counter()
        new, sol_out = self._update(state, model, dt, gm, active, cells, sol, eps_gp)
        new_wall = self._wall_forces(state, gm, active, data.contacts, wall_ids, sol)
        new = new.replace(wall_force=new_wall)
        timings = {
            "mesh": t1 - t0 - t_map,
            "transfer": t_map,
            **sol.timings,
            "update": time.perf_counter() - t2,
        }
        rec = StepRecord(
            step=-1 if step is None else step,
            time=float("nan"),
            dt=dt,
            status=sol.status,
            iterations=sol.iterations,
            timings=timings,
            n_active=int(active.size),
            n_inactive=int(state.n - active.size),
            mesh_volume=float(gm.points.weights.sum()),
            n_contacts=data.contacts.size,
            extra=dict(info),
            **energies(new, model),
            solution=sol_out,
            active=active,
            local_t=local_t,
        )
        return new, rec

    def _step_data(self, state, model, dt, gm, active, cells, sig_gp):
        """The stress-point program's data for this step, and contact walls."""
        mass, force, fixed, v_pres, v, lagged = self._node_data(
            state, model, gm, active
        )
        mat_gp = np.repeat(_element_material(state.material, cells), gm.nq)
        vol_e = gm.points.weights.reshape(-1, gm.nq).sum(axis=1)
        h = float(np.mean(vol_e)) ** (1 / model.dim)
        contacts, wall_ids = node_contacts(
            model, gm.node_x, v, fixed, v_pres, lagged, dt, h
        )
        data = GaussStepData(
            points=gm.points,
            materials=model.materials,
            material=mat_gp,
            sigma_n=sig_gp,
            force=force,
            fixed=fixed,
            du_prescribed=v_pres * dt,
            contacts=contacts,
            dt=dt,
            mass=mass,
            v_n=v,
            theta1=model.theta1,
            theta2=model.theta2,
            dynamic=model.mode == "dynamic",
            stress_scale=model.stress_scale,
        )
        return data, wall_ids

    def _update(self, state, model, dt, gm, active, cells, sol, eps_gp):
        """Rotate Gauss-point stresses, recover nodal output, move particles."""
        sig = sol.sigma
        if model.objective_rotation:
            sig = rotate_stress(sig, gm.points.gradient(sol.du))
        eps = eps_gp + equivalent_strain(sol.deps_p)
        nv = gm.n_vertices
        x_act = state.x[active]
        local = gm.mesh.t.T
        nodal = recover_nodal(x_act, local, gm.gp_x, np.column_stack([sig, eps]))
        stress = state.stress.copy()
        stress[active] = nodal[:, :-1]
        eps_p = state.eps_p.copy()
        eps_p[active] = np.maximum(nodal[:, -1], 0.0)
        # Reactions of mid-edge nodes go half to each end particle.
        reaction = sol.reaction[:nv].copy()
        if gm.edges.size:
            half = 0.5 * sol.reaction[nv:]
            for k in (0, 1):  # the two ends of every edge
                np.add.at(reaction, gm.edges[:, k], half)
        new = update_particles(
            state,
            model,
            dt,
            active,
            sol.du[:nv],
            stress=stress,
            eps_p=eps_p,
            cells=cells,
            gp_stress=sig,
            gp_eps_p=eps,
        )
        out = type(sol)(
            du=sol.du[:nv],
            sigma=nodal[:, :-1],
            deps_p=np.zeros_like(nodal[:, :-1]),
            reaction=reaction,
            lambda_n=sol.lambda_n,
            lambda_t=sol.lambda_t,
            status=sol.status,
            iterations=sol.iterations,
            timings=sol.timings,
            sizes=sol.sizes,
        )
        return new, out

    def _wall_forces(self, state, gm, active, contacts, wall_ids, sol):
        """Lagged normal forces per particle (mid-edge forces split to the ends)."""
        wall = np.zeros_like(state.wall_force)
        if not contacts.size:
            return wall
        nv = gm.n_vertices
        per_node = np.zeros((gm.node_x.shape[0], wall.shape[1]))
        per_node[contacts.node, wall_ids] = sol.lambda_n
        per_vert = per_node[:nv].copy()
        if gm.edges.size:
            for k in (0, 1):
                np.add.at(per_vert, gm.edges[:, k], 0.5 * per_node[nv:])
        wall[active] = per_vert
        return wall
