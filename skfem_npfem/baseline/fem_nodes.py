"""Displacement nodes of the FEM baseline: what P1/P2 nodes take from particles.

The particles are the mesh vertices.  P2 elements add one displacement node
per edge, which is not a particle; its velocity, prescribed motion and fixity
are those of the straight edge (mean of the two end particles; fixed only when
both ends are).  Masses are HRZ-lumped from the element density ``rho_e`` (the
density of the element's material; a particle-based density ``sum m_i / sum
V_i`` over its vertices only for materials with ``rho = 0``: with alpha-shape
meshes the cell volumes change with the diagonals, by up to +-30 % on a
lattice, so particle masses over current cells are a noisy density).  Gravity
is the consistent load ``int rho_e g phi_j`` in static steps (exact for the
geostatic column) and the lumped ``m_j g`` in dynamic ones (the consistent
load puts no weight on triangle vertices, so with lumped inertia a falling
body would stretch; the lumped load makes free fall exact and costs an O(h)
stress error at rest, 0.5 % on the elastic column with 20 elements over its
height).  A wall contact force on a mid-edge node is stored half on each end
particle, and the lagged friction bound is split back with the consistent P2
shares (:func:`split_wall_forces`): the total bound is ``mu`` times the total
stored force, as for P1 and N-PFEM.

P1 nodes are the particles: their masses, ``m g`` and wall forces, exactly as
N-PFEM.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..particles import Particles
from ..step.model import Model
from .operators import GaussMesh, body_force, lumped_masses, quadrature

__all__ = [
    "NodeData",
    "element_material",
    "gauss_points",
    "node_data",
    "split_wall_forces",
    "to_particles",
]


@dataclass(frozen=True)
class NodeData:
    """Nodal inputs of one FEM step (vertices first, then P2 mid-edge nodes)."""

    mass: np.ndarray
    force: np.ndarray
    fixed: np.ndarray
    v_prescribed: np.ndarray
    v: np.ndarray
    lagged: np.ndarray


def element_material(material: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Most frequent material among an element's vertices (ties: first vertex)."""
    m = material[cells]  # (ne, d+1)
    counts = (m[:, :, None] == m[:, None, :]).sum(axis=2)
    return m[np.arange(m.shape[0]), np.argmax(counts, axis=1)]


def gauss_points(x: np.ndarray, cells: np.ndarray, element: str) -> np.ndarray:
    """Gauss-point coordinates (ne * nq, d) of straight-sided elements."""
    bary, _ = quadrature(x.shape[1], element)
    return np.einsum("qa,ead->eqd", bary, x[cells]).reshape(-1, x.shape[1])


def split_wall_forces(lam, active, a, b) -> np.ndarray:
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


def node_data(
    p: Particles, model: Model, gm: GaussMesh, active: np.ndarray
) -> NodeData:
    """Masses, forces, fixity, velocities and lagged wall forces of the nodes."""
    e = gm.edges
    a, b = active[e[:, 0]], active[e[:, 1]]
    fixed = np.concatenate([p.fixed[active], p.fixed[a] & p.fixed[b]])
    vp = p.v_prescribed
    v_pres = np.concatenate([vp[active], 0.5 * (vp[a] + vp[b])])
    v = np.concatenate([p.v[active], 0.5 * (p.v[a] + p.v[b])])
    g = model.gravity_vector
    if gm.element == "p1":
        mass = p.mass[active]
        force = mass[:, None] * g[None, :]
        return NodeData(mass, force, fixed, v_pres, v, p.wall_force[active])
    rho_e = _element_density(p, model, gm, active)
    mass = lumped_masses(gm, rho_e)
    if model.mode == "static":
        force = body_force(gm, rho_e, g)
    else:  # lumped, so that free fall is exact (see the module docstring)
        force = mass[:, None] * g[None, :]
    lagged = split_wall_forces(p.wall_force, active, a, b)
    return NodeData(mass, force, fixed, v_pres, v, lagged)


def _element_density(
    p: Particles, model: Model, gm: GaussMesh, active: np.ndarray
) -> np.ndarray:
    """Density of each element's material (particle-based where ``rho = 0``)."""
    t, d = gm.mesh.t, model.dim
    rho_mat = np.array([m.rho for m in model.materials])
    rho_e = rho_mat[element_material(p.material, active[t].T)]
    light = rho_e <= 0.0
    if np.any(light):  # weightless material: density of the particles
        vol_e = gm.points.volumes.reshape(gm.n_elements, gm.nq).sum(axis=1)
        cell_v = np.bincount(
            t.ravel(), np.tile(vol_e / (d + 1), d + 1), minlength=gm.n_vertices
        )
        m_act = p.mass[active]
        rho_e[light] = (m_act[t].sum(0) / cell_v[t].sum(0))[light]
    return rho_e


def to_particles(gm: GaussMesh, per_node: np.ndarray) -> np.ndarray:
    """Node values (forces) on the vertices: a mid-edge value half to each end."""
    nv = gm.n_vertices
    out = np.array(per_node[:nv], dtype=float, copy=True)
    if gm.edges.size:
        half = 0.5 * per_node[nv:]
        for k in (0, 1):  # the two ends of every edge
            np.add.at(out, gm.edges[:, k], half)
    return out
