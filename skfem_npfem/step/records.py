"""What a step leaves behind.

:class:`StepRecord` holds the scalars of a step that the run keeps in its
history (and in checkpoints); :class:`Step` is the finished step with its
arrays (particles, cone solution, smoothing cells, the mesh as a scikit-fem
mesh), handed to callbacks and the writer and then dropped;
:func:`skfem_fields` gives the particle fields as P1 degrees of freedom.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from skfem import MeshTet, MeshTri

from ..errors import ParameterError
from ..mesh.delaunay import p1_mesh
from ..mesh.smoothing import FULL_VOIGT
from ..particles import Particles
from .conic import ConeSolution
from .kinematics import energies
from .program import StrainOperator

__all__ = ["Step", "StepRecord", "StepState", "skfem_fields"]


@dataclass(frozen=True)
class StepState:
    """What one step hands the next besides the particles.

    :func:`~skfem_npfem.step.stages.advance` takes it as ``start`` and returns
    the state at the end of the step as :attr:`Step.state`.

    Attributes
    ----------
    time : float
        Time, s (where the model's rigid bodies are).
    volume_strain : tuple of float or None
        The volume correction's filter state: the volumetric eigenstrain of
        the step that ended here, one number per material
        (:func:`~skfem_npfem.step.volume.volume_strains`); None at the start
        of a run or with the correction off.

    Examples
    --------
    >>> StepState().after(0.5, None)
    StepState(time=0.5, volume_strain=None)
    """

    time: float = 0.0
    volume_strain: tuple[float, ...] | None = None

    @classmethod
    def resumed(cls, time: float, last: StepRecord | None) -> StepState:
        """The state of a run resumed at ``time`` after the record ``last``.

        A checkpoint keeps the records: the filter state is the last one's
        ``extra["volume_correction_strain"]`` (None: the correction is off).
        """
        strain = None if last is None else last.extra.get("volume_correction_strain")
        return cls(time, None if strain is None else tuple(strain))

    def after(self, dt: float, volume_strain: np.ndarray | None) -> StepState:
        """The state at the end of a step of ``dt`` that used ``volume_strain``."""
        strain = None
        if volume_strain is not None:
            strain = tuple(float(x) for x in volume_strain)
        return StepState(self.time + dt, strain)


@dataclass
class StepRecord:
    """The record of one step kept in a run's history: scalars only.

    :attr:`Step.record` of each step; ``Simulation.records`` and the JSON
    summary's ``history`` hold one per step.

    Attributes
    ----------
    step : int
        Index of the step (1 for the first).
    time : float
        Time at the end of the step, s.
    dt : float
        Time step used, s (after any halving).
    status : str
        Clarabel's status (``"Solved"``, ``"AlmostSolved"``; explicit methods
        report their own).
    iterations : int
        Interior-point iterations (0 for an elastic program: one KKT solve).
    timings : dict of str to float
        Wall time per phase, s: ``mesh``, ``assembly``, ``setup``, ``solve``,
        ``update``, ``output``.
    n_active : int
        Particles in the step's mesh.
    n_inactive : int
        Particles outside it (moved ballistically).
    mesh_volume : float
        Area (2D, m^2 per m) or volume (3D, m^3) of the step's mesh.
    n_contacts : int
        Contact candidates of the step.
    retries : int
        Times the step was halved and repeated after a solver failure.
    """

    step: int
    time: float
    dt: float
    status: str
    iterations: int
    timings: dict[str, float]
    n_active: int
    n_inactive: int
    mesh_volume: float
    n_contacts: int
    retries: int = 0
    #: Sum of the particle masses, kg (exactly conserved).
    mass: float = float("nan")
    #: ``1/2 sum m |v|^2`` at the end of the step, J.
    kinetic_energy: float = float("nan")
    #: ``sum m g x_d`` at the end of the step (zero at ``x_d = 0``), J.
    potential_energy: float = float("nan")
    #: ``mesh_volume / (mesh volume of the first step) - 1``.
    volume_change: float = float("nan")
    #: Clarabel's linear solver of the step (``""`` if unknown).
    linear_solver: str = ""
    #: Scene diagnostics (numbers) added by callbacks, e.g. ``runout``, and
    #: ``volume_correction_strain`` (a list, one number per material) when the
    #: volume correction is on.
    extra: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def of_step(
        cls,
        step: int | None,
        dt: float,
        new: Particles,
        gravity: float,
        active: np.ndarray,
        operator: StrainOperator,
        sol: ConeSolution,
        timings: dict[str, float],
        **extra: Any,
    ) -> StepRecord:
        """The record of a finished step of any method.

        Solver status, mesh size and volume, contacts (``sol.lambda_n``) and
        the energies of the new particles; ``extra`` goes to :attr:`extra`,
        ``time`` is set by the time loop.
        """
        return cls(
            step=-1 if step is None else step,
            time=float("nan"),
            dt=dt,
            status=sol.status,
            iterations=sol.iterations,
            timings=timings,
            n_active=int(active.size),
            n_inactive=int(new.n - active.size),
            mesh_volume=float(operator.volumes.sum()),
            n_contacts=int(sol.lambda_n.size),
            linear_solver=str(sol.sizes.get("linear_solver", "")),
            extra=dict(extra),
            **energies(new, gravity),
        )

    def as_dict(self) -> dict[str, Any]:
        """Plain dict of the diagnostics (for JSON); ``extra`` is merged in."""
        out = {k: v for k, v in vars(self).items() if k != "extra"}
        out.update({k: v for k, v in self.extra.items() if k not in out})
        return out

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> StepRecord:
        """Inverse of :meth:`as_dict` (unknown keys go to ``extra``)."""
        names = {f.name for f in fields(cls)} - {"extra"}
        known = {k: v for k, v in d.items() if k in names}
        known["extra"] = {k: v for k, v in d.items() if k not in names}
        return cls(**known)


@dataclass
class Step:
    """One finished step: its mesh, its fields, the cone solution and its record.

    :func:`advance` returns it beside the new particles; a
    :class:`~skfem_npfem.Simulation` hands it to the callbacks and the writer
    and keeps only :attr:`record`.  :meth:`to_skfem` gives the step's mesh as
    a scikit-fem mesh with the particle fields as P1 degrees of freedom.

    Attributes
    ----------
    record : StepRecord
        The scalar diagnostics (kept by :class:`~skfem_npfem.Simulation`).
    solution : ConeSolution
        The cone solution on the active particles (``du``, ``sigma``,
        ``reaction``, contact forces, sizes).
    active : ndarray (N_a,) int
        Particles of the step's mesh: node ``i`` is particle ``active[i]``.
    local_t : ndarray (d+1, ne) int
        Its connectivity in positions of ``active``.
    operator : StrainOperator
        Its strain operator (N-PFEM: the smoothing cells; FEM-remap: the
        Gauss points of its elements).
    particles : Particles or None
        The particles at the end of the step (the first value :func:`advance`
        returns); needed by :attr:`mesh` and :meth:`to_skfem`.
    state : StepState or None
        The state at the end of the step, for the next step's ``start``
        (every method of the library sets it).
    """

    record: StepRecord
    solution: ConeSolution
    active: np.ndarray
    local_t: np.ndarray
    operator: StrainOperator
    particles: Particles | None = None
    state: StepState | None = None

    @property
    def cells(self) -> np.ndarray:
        """Global connectivity (ne, d+1) of the step's mesh."""
        return self.active[self.local_t].T

    @property
    def mesh(self) -> MeshTri | MeshTet:
        """The step's mesh as a scikit-fem ``MeshTri``/``MeshTet``.

        Its nodes are the active particles at their end-of-step positions
        (node ``i`` is particle ``active[i]``; particles outside the mesh are
        not in it), its elements those the step was solved on.
        """
        if self.particles is None:
            raise ParameterError(
                "step.particles",
                None,
                "the particles at the end of the step (advance sets them)",
            )
        return p1_mesh(self.particles.x[self.active], self.local_t)

    def to_skfem(self) -> tuple[MeshTri | MeshTet, dict[str, np.ndarray]]:
        """The step's mesh and the particle fields as scikit-fem P1 DOFs.

        Returns
        -------
        mesh : skfem.MeshTri or skfem.MeshTet
            :attr:`mesh`.
        fields : dict of str to ndarray
            End-of-step particle values on the mesh nodes, ready for
            ``Basis(mesh, ElementTriP1()).interpolate(fields[name])``
            (:func:`skfem_fields` lists them): ``stress_xx``, ``stress_yy``,
            ... (Pa, tension positive), ``plastic_strain_eq``,
            ``displacement_x``, ... (m), ``velocity_x``, ... (m/s), each of
            shape (N_a,); ``displacement`` and ``velocity`` of shape
            (d N_a,) for ``ElementVector(ElementTriP1())``.

        Examples
        --------
        The integral of the vertical stress over a soil column of height
        ``H = 2`` and width ``W = 1`` (exact: ``-rho g H^2 W / 2``):

        >>> import numpy as np
        >>> from skfem import Basis, ElementTriP1, Functional, MeshTri
        >>> import skfem_npfem as npfem
        >>> soil = npfem.LinearElastic(E=1e7, nu=0.3, rho=2000.0)
        >>> column = MeshTri.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 2, 5))
        >>> x = column.p.T
        >>> fixed = np.zeros(x.shape, bool)
        >>> fixed[x[:, 1] == 0.0] = True  # fixed base
        >>> fixed[(x[:, 0] == 0.0) | (x[:, 0] == 1.0), 0] = True  # smooth sides
        >>> p = npfem.Particles.from_mesh(column, soil, fixed=fixed)
        >>> model = npfem.Model(dim=2, materials=[soil], mode="static")
        >>> p, step = npfem.advance(p, model, dt=1.0, mesh_source=column)
        >>> mesh, fields = step.to_skfem()
        >>> basis = Basis(mesh, ElementTriP1())
        >>> integral = Functional(lambda w: w["s"])
        >>> s = integral.assemble(basis, s=basis.interpolate(fields["stress_yy"]))
        >>> round(float(s) / (-2000.0 * 9.81 * 2.0**2 * 1.0 / 2), 3)
        0.998
        """
        mesh = self.mesh  # refuses a step without its particles
        return mesh, skfem_fields(self.particles, self.active)


def skfem_fields(particles: Particles, nodes: np.ndarray) -> dict[str, np.ndarray]:
    """Particle fields as scikit-fem P1 DOF arrays on a mesh of ``nodes``.

    Node ``i`` of the mesh is particle ``nodes[i]``, so the P1 DOF ``i`` of a
    scalar field is that particle's value; a vector field is node-major
    (``u_0x, u_0y, u_1x, ...``), the DOF order of
    ``ElementVector(ElementTriP1())``.

    Parameters
    ----------
    particles : Particles
        The particles (positions are not used).
    nodes : ndarray (N_a,) int
        The particles that are the mesh's nodes, in node order.

    Returns
    -------
    dict of str to ndarray
        ``stress_<c>`` for each full-Voigt component ``c`` (``xx, yy, zz,
        xy`` in 2D; also ``yz, zx`` in 3D), ``plastic_strain_eq``,
        ``displacement_<k>`` and ``velocity_<k>`` for ``k`` in ``x, y(, z)``,
        all (N_a,); ``displacement`` and ``velocity`` (d N_a,).

    Examples
    --------
    >>> import skfem_npfem as npfem
    >>> p = npfem.Particles.create([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], 1.0)
    >>> sorted(skfem_fields(p, np.array([2, 0, 1])))[:4]
    ['displacement', 'displacement_x', 'displacement_y', 'plastic_strain_eq']
    """
    nodes = np.asarray(nodes, dtype=np.int64)
    d = particles.dim
    out = {
        f"stress_{c}": particles.stress[nodes, k].copy()
        for k, c in enumerate(FULL_VOIGT[d])
    }
    out["plastic_strain_eq"] = particles.eps_p[nodes].copy()
    for name, arr in (("displacement", particles.u), ("velocity", particles.v)):
        vec = arr[nodes]
        out.update({f"{name}_{'xyz'[k]}": vec[:, k].copy() for k in range(d)})
        out[name] = vec.reshape(-1).copy()
    return out
