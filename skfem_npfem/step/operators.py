"""Stage 1 of a step: the mesh, its strain operator, contacts and cone-step data.

:func:`build_operators` asks, in this order, the model's
boundaries for the elements they span (:mod:`skfem_npfem.boundary`), the mesh
for its strain operator (:mod:`skfem_npfem.mesh`), the boundaries for their
contact rows, the model for the nodes' masses and loads and the volume
correction for its eigenstrain, and packs it all into the
:class:`~skfem_npfem.step.program.ConeInput` of the step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..boundary import Boundary, Contacts
from ..errors import ParameterError
from ..mesh.delaunay import p1_mesh
from ..mesh.operators import strain_operator
from ..mesh.smoothing import NodalIntegration
from ..mesh.sources import MeshSource, mesh_particles
from ..particles import Particles
from ..water.forces import darcy_matrix, drained_nodes, projection_matrix, water_force
from .boundary_jobs import (
    particle_nodes,
    step_contacts,
    with_columns,
    without_spanned,
)
from .model import Model
from .program import ConeInput, PoreInput
from .records import StepState
from .volume import volume_eigenstrain, volume_strains

__all__ = ["StepOperators", "build_operators", "pore_input"]


@dataclass
class StepOperators:
    """What :func:`build_operators` makes of the particles for one step.

    Attributes
    ----------
    active : ndarray (N_a,) int
        Particles in the mesh (the mesh nodes).
    local_t : ndarray (d+1, ne) int
        Connectivity in node numbers ``0 .. N_a-1``.
    operator : NodalIntegration
        Smoothing cells of the mesh.
    wall_ids : ndarray (nc,) int
        Wall or body (lagged-force column) of each contact candidate of
        ``data.contacts``.
    data : ConeInput
        The cone step's input.
    volume_strains : ndarray (n_materials,) or None
        Volumetric eigenstrain of the volume correction per material
        (:func:`~skfem_npfem.step.volume.volume_strains`; None when it is off).
    time : float
        Time at the start of the step, s (where the model's bodies are).
    dropped : int
        Elements of the mesh source's mesh dropped because they span a body.
    columns : int
        Lagged-force columns of the particles after the step: one per wall,
        then one per body (:attr:`Particles.wall_force`).

    Notes
    -----
    With rigid bodies, :attr:`wall_ids` numbers the bodies after the walls
    (``len(model.walls) + k`` for body ``k``): the columns of
    :attr:`Particles.wall_force`.
    """

    active: np.ndarray
    local_t: np.ndarray
    operator: NodalIntegration
    wall_ids: np.ndarray
    data: ConeInput
    volume_strains: np.ndarray | None = None
    time: float = 0.0
    dropped: int = 0
    columns: int = 0

    @property
    def contacts(self) -> Contacts:
        """Contact candidates (node indices local to :attr:`active`)."""
        return self.data.contacts


def build_operators(
    p: Particles,
    model: Model,
    dt: float,
    mesh_source: MeshSource,
    start: StepState | None = None,
    boundaries: Sequence[Boundary] | None = None,
) -> StepOperators:
    """Stage 1: the mesh, smoothing cells, contacts and cone-step data of a step.

    ``start`` is the state at the start of the step (its time: where the
    model's rigid bodies are; the volume correction's filter state);
    ``boundaries`` those of the model (default ``model.boundaries``): the
    elements they span are dropped and their contact rows join the program,
    on the particles' lagged forces with a column for every wall and body.
    """
    start = StepState() if start is None else start
    boundaries = model.boundaries if boundaries is None else boundaries
    time = float(start.time)
    active, local_t = mesh_particles(mesh_source, p)
    active, local_t, dropped = without_spanned(boundaries, p.x, active, local_t, time)
    mesh = p1_mesh(p.x[active], local_t)
    op, h = strain_operator(mesh, model.components, model.axisymmetric)
    nodes = particle_nodes(with_columns(boundaries, p), active, local_t)
    contacts, wall_ids = step_contacts(boundaries, nodes, dt, h, time)
    mass = model.node_masses(p.mass[active], p.material[active], op.volumes)
    force = model.external_force(p.x.shape[0], active, mass, time + dt)
    # The volume's share (weight, k_h): the stabilisation's residual must not
    # read the dead loads (tractions, point loads) as a body force.
    body = mass[:, None] * model.body_acceleration(time + dt)[None, :]
    pore = None
    if model.water is not None:
        pore, water = pore_input(model, p, active, op, contacts, dt)
        force, body = force + water, body + water
    strains = volume_strains(
        model.volume_correction,
        p.mass[active],
        p.material[active],
        op.volumes,
        np.array([m.rho for m in model.materials], float),
        start.volume_strain,
    )
    eigenstrain = volume_eigenstrain(
        strains,
        p.material[active],
        p.stress.shape[1],
        (0, 1, 2) if model.dim == 3 or model.axisymmetric else (0, 1),
    )
    data = ConeInput(
        operator=op,
        materials=model.materials,
        material=p.material[active],
        sigma_n=p.stress[active],
        force=force,
        fixed=p.fixed[active],
        du_prescribed=p.v_prescribed[active] * dt,
        contacts=contacts,
        dt=dt,
        mass=mass,
        v_n=p.v[active],
        theta1=model.theta1,
        theta2=model.theta2,
        dynamic=model.mode == "dynamic",
        stress_scale=model.stress_scale,
        stabilisation=model.stabilisation,
        stabilisation_mode=model.stabilisation_mode,
        a_n=p.a[active],
        eigenstrain=eigenstrain,
        pore=pore,
        tied=tied_dofs(model, active),
        strength=step_strength(model, p, active),
        stiffness=None if p.stiffness is None else p.stiffness[active],
        body_force=None if model.loads is None else body,
    )
    columns = nodes.lagged.shape[1]
    return StepOperators(
        active, local_t, op, wall_ids, data, strains, time, dropped, columns
    )


def step_strength(model: Model, p: Particles, active: np.ndarray) -> np.ndarray | None:
    """The step's strength factors: the profile's times the strength law's.

    The law (:attr:`Model.strength_law`) takes each particle's plastic strain
    and shear rate at the start of the step.  None: no factor at all.
    """
    law = model.strength_law
    if law is None:
        return None if p.strength is None else p.strength[active]
    rate = None if p.shear_rate is None else p.shear_rate[active]
    f = law.factors(p.eps_p[active], rate, p.x[active], p.mass[active])
    return f if p.strength is None else p.strength[active] * f


def pore_input(
    model: Model,
    p: Particles,
    active: np.ndarray,
    op: NodalIntegration,
    contacts: Contacts | None = None,
    dt: float = 1.0,
) -> tuple[PoreInput, np.ndarray]:
    """The pore water of a step and the force of its static pore pressure.

    The static field (the water table's hydrostatic pressure at the nodes,
    or the pore pressure of a steady seepage solved on the step's mesh)
    loads the skeleton through :func:`~skfem_npfem.water.water_force`; the
    excess pore pressure the particles carry enters the program as
    :class:`~skfem_npfem.step.program.PoreInput`, with its increments as
    variables in undrained and coupled steps.  A coupled step adds Darcy's
    term ``dt H`` (:func:`~skfem_npfem.water.darcy_matrix`, ``kappa = k /
    (rho_w g)``) and drains the free part of the boundary
    (:func:`~skfem_npfem.water.drained_nodes`: not held by a support along
    its normal, not touching a wall or a body, i.e. not in ``contacts``).
    """
    water = model.water
    if water.seepage is not None and model.axisymmetric:
        raise ParameterError(
            "seepage", "an axisymmetric model", "a plane-strain section (dim=2)"
        )
    x = p.x[active]
    static = water.static_pressure(x, model.gravity, op.t, p.material[active])
    force = water_force(op, x, static)
    excess = np.zeros(active.size)
    if p.excess_pore_pressure is not None:
        excess = np.asarray(p.excess_pore_pressure, float)[active]
    projection = None
    if water.undrained and water.projection > 0:
        shear = np.array([m.E / (2.0 * (1.0 + m.nu)) for m in model.materials])
        compliance = 1.0 / (2.0 * shear[p.material[active]])
        projection = projection_matrix(op, compliance, water.projection)
    pore = PoreInput(excess, water.undrained, projection, static)
    if water.storage > 0:
        pore.storage = water.storage * op.volumes
    if water.drainage == "coupled":
        gamma_w = water.rho_w * model.gravity
        if not gamma_w > 0:
            raise ParameterError(
                "gravity",
                model.gravity,
                "> 0 with coupled drainage (Darcy's law uses gamma_w = rho_w g)",
            )
        kappa = water.conductivity(p.material[active]) / gamma_w
        pore.darcy = dt * darcy_matrix(op, kappa)
        walled = np.zeros(active.size, bool)
        if contacts is not None and contacts.size:
            nodes, _, used = contacts.weights()
            walled[nodes[used]] = True
        held = p.fixed[active] | tied_mask(model, active)  # a plate is impermeable
        pore.drained = drained_nodes(op, held, walled)
        modulus = np.array(
            [m.E * (1 - m.nu) / ((1 + m.nu) * (1 - 2 * m.nu)) for m in model.materials]
        )
        c_v = kappa * modulus[p.material[active]]
        h = float(np.sum(op.volumes) / max(active.size, 1)) ** (1.0 / model.dim)
        pore.diffusion_number = float(dt * c_v.min() / h**2)
        pore.excess = np.where(
            np.isin(np.arange(active.size), pore.drained), 0.0, excess
        )
    return pore, force


def tied_mask(model: Model, active: np.ndarray) -> np.ndarray:
    """(n_active, d) bool: the step's dofs in a tied group (:attr:`Model.tied`)."""
    mask = np.zeros((active.size, model.dim), bool)
    for idx, axis in model.tied or []:
        mask[np.isin(active, idx), axis] = True
    return mask


def tied_dofs(model: Model, active: np.ndarray) -> list[np.ndarray] | None:
    """The tied groups as the step's node-major dofs (None: no group)."""
    if not model.tied:
        return None
    local = [np.flatnonzero(np.isin(active, idx)) for idx, _ in model.tied]
    return [
        model.dim * n + axis for n, (_, axis) in zip(local, model.tied, strict=True)
    ]
