"""One step: particles in, particles out.

:func:`advance` runs the data flow of one N-PFEM step in three stages:

1. :func:`~skfem_npfem.step.operators.build_operators` -- the mesh of this
   step (from the mesh source, without the elements that span a rigid body),
   its strain operator (:mod:`skfem_npfem.mesh.operators`), the contact rows
   of the model's boundaries, walls then bodies (:mod:`skfem_npfem.boundary`),
   and the :class:`~skfem_npfem.step.program.ConeInput`;
2. :func:`~skfem_npfem.step.conic.solve_step` -- the cone program;
3. :func:`~skfem_npfem.step.update.update_particles` -- *new* particles from
   the solution (stress rotation, plastic strain, velocities, ballistic
   particles, put back from walls and bodies).

The boundaries then write their keys into the record
(:func:`~skfem_npfem.step.boundary_jobs.record`), and the step hands the next
one its :class:`StepState` (time, volume correction).

The mesh is then forgotten: nothing is mapped between meshes.  The step's
arrays (solution, mesh, operator) travel in a :class:`Step` that the
caller uses and drops; only the scalar :class:`StepRecord` is kept for the run.

The step's types, from the inside out:
:class:`~skfem_npfem.step.program.ConeInput` (the cone program's input) ->
:class:`~skfem_npfem.step.conic.ConeSolution` (the solver's raw solution) ->
:class:`Step` (what :func:`advance` returns: mesh, fields, solution) ->
:class:`StepRecord` (its scalars, kept in the run's history).
"""

from __future__ import annotations

import math
from time import perf_counter

import numpy as np
from skfem import Mesh

from ..errors import ParameterError
from ..mesh.sources import MeshSource, as_mesh_source
from ..particles import Particles
from .boundary_jobs import record
from .conic import solve_step
from .model import Model
from .operators import build_operators
from .records import Step, StepRecord, StepState, skfem_fields
from .update import update_particles

__all__ = ["Step", "StepRecord", "StepState", "advance", "skfem_fields"]


def advance(
    p: Particles,
    model: Model,
    dt: float,
    mesh_source: MeshSource | Mesh | np.ndarray,
    step: int | None = None,
    start: StepState | None = None,
) -> tuple[Particles, Step]:
    """Advance the particles by one step.

    Parameters
    ----------
    p : Particles
        State at the start of the step.
    model : Model
        Materials, loads, walls and solver settings.
    dt : float
        Time step, s (pseudo-time in static mode).
    mesh_source : callable, skfem.Mesh or ndarray (d+1, ne)
        ``x -> (active_index, local_t)`` (for example
        :class:`~skfem_npfem.mesh.sources.FixedMesh` or
        :class:`~skfem_npfem.mesh.sources.AlphaShapeMesher`); a scikit-fem
        ``MeshTri``/``MeshTet`` whose nodes are the particles (as made by
        :meth:`~skfem_npfem.Particles.from_mesh`), or its connectivity, is
        ``FixedMesh(mesh)``.
    step : int, optional
        Step index (used in error messages).
    start : StepState, optional
        The state at the start of the step besides the particles: the time
        (where the model's rigid bodies are) and the volume correction's
        filter state; the previous step's ``step.state``.  None: time 0, no
        filter state (the start of a run).  :class:`~skfem_npfem.Simulation`
        passes it.

    Returns
    -------
    Particles, Step
        New particles, and the step (its :class:`StepRecord` as ``.record``,
        the solution and the mesh, the state at its end as ``.state`` for the
        next step's ``start``; ``step.to_skfem()`` gives the mesh and the
        fields for scikit-fem).  With the volume correction on, the
        record's ``extra["volume_correction_strain"]`` holds this step's
        volumetric eigenstrain per material (as ``step.state.volume_strain``).
        With rigid bodies it holds, per
        body ``<name>``: ``<name>_x``, ``<name>_y`` (displacement of the body
        at the end of the step, m), ``<name>_force_x``, ``<name>_force_y``
        (force of the soil on the body, N per m in plane strain, N of the
        ring in axisymmetry, where ``force_x`` is 0), ``<name>_moment``
        (N m per m, about its reference point; 0 in axisymmetry) and
        ``<name>_penetration`` (the deepest a particle got inside it before
        being put back on its outline, m); and ``dropped_elements``.  A 3D
        body (:class:`~skfem_npfem.RigidPlane`,
        :class:`~skfem_npfem.BodyOfRevolution`) has ``<name>_x``, ``_y``,
        ``_z``, ``<name>_force_x``, ``_y``, ``_z`` (N, on the modelled part:
        a quarter domain carries a quarter of the load), ``<name>_moment_x``,
        ``_y``, ``_z`` (N m) and ``<name>_penetration``.

    Raises
    ------
    SolverError
        If the cone program fails; ``p`` is untouched.
    ParameterError
        For a bad ``dt``, particles of another dimension than the model, or a
        mesh source that is none of the above.

    Examples
    --------
    A soil column under gravity, two quasi-static steps on a scikit-fem mesh:

    >>> import numpy as np
    >>> from skfem import MeshTri
    >>> import skfem_npfem as npfem
    >>> soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=2000.0)
    >>> mesh = MeshTri.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 2, 5))
    >>> p = npfem.Particles.from_mesh(mesh, soil, fixed=mesh.p[1] == 0.0)
    >>> model = npfem.Model(dim=2, materials=[soil], mode="static")
    >>> p, step = npfem.advance(p, model, dt=1.0, mesh_source=mesh)
    >>> step.record.status, step.record.n_active
    ('Solved', 15)
    >>> p, step = npfem.advance(p, model, 1.0, mesh, start=step.state)
    >>> step.state.time
    2.0
    """
    if not (math.isfinite(dt) and dt > 0):
        raise ParameterError("dt", dt, "a finite time step > 0 (s)")
    if p.dim != model.dim:
        raise ParameterError(
            "particles",
            f"{p.dim}D positions",
            f"{model.dim}D positions for a {model.dim}D model",
        )
    mesh_source = as_mesh_source(mesh_source)
    start = StepState() if start is None else start
    boundaries = model.boundaries
    t0 = perf_counter()
    ops = build_operators(p, model, dt, mesh_source, start, boundaries)
    t1 = perf_counter()
    sol = solve_step(ops.data, model.solver, step=step)
    t2 = perf_counter()
    new, marks = update_particles(p, model, dt, ops, sol, boundaries)
    timings = {"mesh": t1 - t0, **sol.timings, "update": perf_counter() - t2}
    extra = {}
    if ops.volume_strains is not None:
        extra["volume_correction_strain"] = [float(x) for x in ops.volume_strains]
    pore = ops.data.pore
    if pore is not None and pore.diffusion_number is not None:
        extra["diffusion_number"] = pore.diffusion_number
    record(
        boundaries,
        extra,
        ops.contacts,
        ops.wall_ids,
        (sol.lambda_n, sol.lambda_t),
        p.x[ops.active],
        ops.time + dt,
        marks,
        ops.dropped,
    )
    end = start.after(dt, ops.volume_strains)
    rec = StepRecord.of_step(
        step, dt, new, model.gravity, ops.active, ops.operator, sol, timings
    )
    rec.n_contacts = ops.contacts.size
    rec.extra.update(extra)
    return new, Step(rec, sol, ops.active, ops.local_t, ops.operator, new, end)
