"""The physics and numerics shared by all steps of a run (:class:`Model`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..boundary import (
    BodyOfRevolution,
    Boundary,
    RigidBodies,
    RigidBody,
    RigidPlane,
    RigidWall,
    Walls,
)
from ..constants import GRAVITY
from ..errors import ParameterError
from ..materials import Material
from ..strength_laws import ClayStrength
from ..water.model import Water
from .solver import SolverOptions
from .stabilisation import STABILISATION_MODES

__all__ = ["NODAL_MASS", "Model"]

#: Allowed values of :attr:`Model.nodal_mass`.
NODAL_MASS = ("mesh", "particle")


@dataclass
class Model:
    """Physics and numerics shared by all steps of a run.

    Parameters
    ----------
    dim : int
        2 (plane strain) or 3.
    materials : list of Material
        Referenced by :attr:`Particles.material`.
    gravity : float
        Gravitational acceleration along ``-e_d``, m/s^2.
    mode : {"dynamic", "static"}
        Include inertia (theta1/theta2 scheme) or solve quasi-static steps.
    theta1, theta2 : float
        Time-integration parameters in [1/2, 1] (1, 1: backward Euler, the PFEM
        default; 1/2, 1/2: trapezoidal, energy conserving, elastic waves only).
    walls : list of RigidWall
        Rigid planes the particles may touch.
    bodies : list of RigidBody, RigidPlane or BodyOfRevolution
        Rigid bodies moving with a prescribed velocity
        (:mod:`skfem_npfem.boundary`): polygons (:class:`RigidBody`) in 2D
        models, planes and bodies of revolution in 3D ones.  Their lagged
        normal forces are the columns ``len(walls) ..`` of
        :attr:`Particles.wall_force` (added by :func:`~skfem_npfem.advance`
        when missing).
    objective_rotation : bool
        Rotate stresses with the smoothed spin (Hughes-Winget, exactly orthogonal).
    update_geometry : bool
        Move the particles by each increment (updated Lagrangian, large
        deformation).  False keeps the initial geometry (small-strain analysis, as
        in limit-load benchmarks); displacements still accumulate in ``u``.
    stress_scale : float or None
        Stress scale for non-dimensionalisation (None: automatic).
    solver : SolverOptions
        Clarabel settings.
    stabilisation : float
        Factor ``beta >= 0`` of the consistent element-residual stabilisation
        of the stresses (:mod:`skfem_npfem.step.stabilisation`); 0 switches it off.
    stabilisation_mode : {"full", "vertical", "sigma_v", "mean"}
        Which part of the residual the stabilisation couples: all of it
        (``"full"``, default), its vertical row, the vertical row with only
        ``sigma_v`` at the end of the step, or only the mean stress (one
        auxiliary scalar per particle); what is not coupled is taken at the
        start of the step or left out.  The reduced modes fill the step's
        factor less (:mod:`skfem_npfem.step.stabilisation`, "Modes").
    nodal_mass : {"mesh", "particle"}
        Masses of a step's nodes.  ``"mesh"`` (default): each node's cell
        volume times the mean density of its material over the current mesh
        (``sum m / sum V`` over that material's active particles), so that the
        load density is uniform and the total mass exact while the cells change
        from remesh to remesh.  ``"particle"``: each node carries its particle's
        own mass; a remeshed body then sees a body force ``m_i g`` that no
        longer matches its cell ``V_i``, which roughens the stresses (the
        remeshed column at rest in docs/validation.md).  On a fixed mesh whose
        particle masses are ``rho V_i`` the two agree.
    volume_correction : float
        Rate ``kappa`` in [0, 1] at which a uniform volumetric eigenstrain
        returns the body's volume deficit (:mod:`skfem_npfem.step.volume`): each
        material's particles should fill ``sum m / rho``; remeshing and
        linearised increments lose some of it, and this returns it through
        the solve, the deficit decaying as ``(1 + kappa n)(1 - kappa)^n`` over
        ``n`` steps (a critically damped filter; its state travels from
        step to step in :class:`~skfem_npfem.step.records.StepState`).
        0 (default) switches it off; needs ``rho > 0``.
        The plane-strain ``column-collapse`` scene defaults to 0.05 for a
        material whose own volume barely changes (psi = 0, rho g H0 / E <=
        0.01; docs/validation.md, "At the default spacing").
    axisymmetric : bool
        2D only: the mesh is the ``(r, z)`` half-section of a body of revolution
        about ``x = 0`` (:mod:`skfem_npfem.mesh.axisymmetric`).  Stresses are
        ``(rr, zz, tt, rz)`` with the hoop component in the ``zz`` slot, the
        cells are weighted by ``2 pi r`` and particle masses must be the full-ring
        masses ``rho V_i`` of those cells.  Needs cones with ``sigma_tt`` as a
        variable (Drucker-Prager, von Mises, AxisymmetricMohrCoulomb); particles
        on the axis should have ``u_r`` fixed.
    loads : ndarray (N, d) or None
        Dead external forces on the particles (N), added to their weight in
        every step while the particle is meshed: a surcharge on a surface,
        say, as the consistent nodal forces of the pressure
        (:func:`~skfem_npfem.loads.surface_load`).  Full-ring
        forces (``2 pi r`` times the load per unit length) in axisymmetry.
        N-PFEM only; None (default) applies none.
    water : Water or None
        The pore water (:mod:`skfem_npfem.water`): its drainage mode, water
        table and density.  With it the particles' stresses are effective
        stresses, the cones act on them and equilibrium is written in the
        total stress; the materials' ``rho`` is the saturated density.  None
        (default): a dry soil.  N-PFEM only.
    tied : list of (indices, axis) or None
        Tied degrees of freedom: each entry is a group of particles (indices
        into the particles) whose displacement along ``axis`` is one
        unknown, as under a rigid smooth plate that carries the group's
        loads (Mandel's plate).  The group's equilibrium rows are summed
        into one zero-cone row, so only its resultant is in balance, and a
        coupled step's facets whose nodes are all tied along their normal
        are impermeable, as the plate is.  Static N-PFEM steps; None
        (default): none.
    kh : float or ndarray (n, 2)
        Pseudo-static horizontal acceleration ``k_h g`` along ``+e_x``, as a
        coefficient of ``gravity``: a number, or rows ``[t, k_h]`` (s, -) with
        increasing ``t``, linear between rows and held beyond the first and
        the last (a recorded acceleration history).  Each step takes it at the
        step's end (backward Euler); a particle in free flight too.  0
        (default): none.  N-PFEM only.
    strength_law : ClayStrength or None
        Softening with the plastic shear strain and rise with its rate
        (:class:`~skfem_npfem.strength_laws.ClayStrength`), a factor on every
        particle's cohesion taken at the start of each step.  None
        (default): the strength is fixed.  N-PFEM only.
    """

    dim: int
    materials: list[Material]
    gravity: float = GRAVITY
    mode: str = "dynamic"
    theta1: float = 1.0
    theta2: float = 1.0
    walls: list[RigidWall] = field(default_factory=list)
    bodies: list[RigidBody] = field(default_factory=list)
    objective_rotation: bool = True
    update_geometry: bool = True
    stress_scale: float | None = None
    solver: SolverOptions = field(default_factory=SolverOptions)
    stabilisation: float = 0.0
    nodal_mass: str = "mesh"
    axisymmetric: bool = False
    volume_correction: float = 0.0
    stabilisation_mode: str = "full"
    loads: np.ndarray | None = None
    water: Water | None = None
    tied: list | None = None
    kh: float | np.ndarray = 0.0
    strength_law: ClayStrength | None = None

    def __post_init__(self) -> None:
        if self.dim not in (2, 3):
            raise ParameterError("dim", self.dim, "2 or 3")
        if isinstance(self.materials, Material | str) or not self.materials:
            raise ParameterError(
                "materials", self.materials, "a list of at least one Material"
            )
        for i, m in enumerate(self.materials):
            if not isinstance(m, Material):
                raise ParameterError(
                    f"materials[{i}]",
                    m,
                    "a Material object, e.g. MohrCoulomb(E, nu, rho, c=0, phi=30)",
                )
            m.check_dim(self.dim)
        if self.mode not in ("dynamic", "static"):
            raise ParameterError("mode", self.mode, "'dynamic' or 'static'")
        for name in ("theta1", "theta2"):
            val = getattr(self, name)
            if not (isinstance(val, int | float) and 0.5 <= val <= 1.0):
                raise ParameterError(name, val, "a number in [0.5, 1]")
        s = self.stress_scale
        if s is not None and not (
            isinstance(s, int | float) and math.isfinite(s) and s > 0
        ):
            raise ParameterError("stress_scale", s, "a stress > 0 (Pa) or None")
        g = self.gravity
        if not (isinstance(g, int | float) and math.isfinite(g) and g >= 0):
            raise ParameterError("gravity", g, "a finite number >= 0 (m/s^2)")
        for w in self.walls:
            if w.normal.size != self.dim:
                raise ParameterError("walls", w, f"walls must be {self.dim}D")
        self._check_bodies()
        self._check_kh()
        law = self.strength_law
        if law is not None and not isinstance(law, ClayStrength):
            raise ParameterError("strength_law", law, "a ClayStrength or None")
        b = self.stabilisation
        if isinstance(b, bool) or not (
            isinstance(b, int | float) and math.isfinite(b) and b >= 0
        ):
            raise ParameterError("stabilisation", b, "a finite number >= 0")
        if self.stabilisation_mode not in STABILISATION_MODES:
            raise ParameterError(
                "stabilisation_mode",
                self.stabilisation_mode,
                f"one of {', '.join(STABILISATION_MODES)}",
            )
        k = self.volume_correction
        if isinstance(k, bool) or not (
            isinstance(k, int | float) and math.isfinite(k) and 0 <= k <= 1
        ):
            raise ParameterError("volume_correction", k, "a number in [0, 1]")
        if k and any(m.rho <= 0 for m in self.materials):
            raise ParameterError(
                "volume_correction",
                k,
                "0 unless every material has a density rho > 0 (a particle's "
                "reference volume is its mass / rho)",
            )
        if self.nodal_mass not in NODAL_MASS:
            raise ParameterError("nodal_mass", self.nodal_mass, f"one of {NODAL_MASS}")
        if not isinstance(self.axisymmetric, bool):
            raise ParameterError("axisymmetric", self.axisymmetric, "True or False")
        if self.axisymmetric:
            self._check_axisymmetric()
        if self.loads is not None:
            self._check_loads()
        if self.water is not None and not isinstance(self.water, Water):
            raise ParameterError(
                "water",
                self.water,
                "a Water(drainage, table) or None (a dry soil)",
            )
        if self.tied is not None:
            self._check_tied()

    def _check_tied(self) -> None:
        """Tied groups: (particle indices, axis) pairs, at least two particles each."""
        if self.mode != "static":
            raise ParameterError(
                "tied", "tied dofs", "None in a dynamic model (static steps only)"
            )
        groups = []
        for entry in self.tied:
            try:
                idx, axis = entry
                idx = np.asarray(idx).astype(int, casting="safe").reshape(-1)
            except (TypeError, ValueError):
                idx, axis = np.zeros(0, int), -1
            if idx.size < 2 or axis not in range(self.dim) or np.any(idx < 0):
                raise ParameterError(
                    "tied",
                    entry,
                    "(particle indices, axis): at least 2 indices >= 0, "
                    f"axis in 0..{self.dim - 1}",
                )
            groups.append((np.unique(idx), int(axis)))
        self.tied = groups

    def _check_loads(self) -> None:
        """Dead loads: a finite array with one column per dimension."""
        try:
            f = np.array(self.loads, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(
                "loads", self.loads, f"an array of shape (N, {self.dim}) of forces (N)"
            ) from None
        if f.ndim != 2 or f.shape[1] != self.dim:
            raise ParameterError(
                "loads",
                f.shape,
                f"an array of shape (N, {self.dim}), one row a particle",
            )
        if not np.all(np.isfinite(f)):
            raise ParameterError("loads", "NaN or inf", "finite forces (N)")
        self.loads = f

    def refuse_loads(self, method: str) -> None:
        """Raise :class:`ParameterError` if a method without dead loads got some.

        Pore water is N-PFEM's only too: a model with water is refused the same way.
        """
        if self.water is not None:
            raise ParameterError(
                "water",
                f"{self.water.drainage} water",
                f"None with {method} (pore water is modelled by N-PFEM only)",
            )
        if self.tied:
            raise ParameterError(
                "tied", "tied dofs", f"None with {method} (N-PFEM only)"
            )
        if np.ndim(self.kh) or self.kh:
            raise ParameterError(
                "kh", "pseudo-static shaking", f"0 with {method} (N-PFEM only)"
            )
        if self.strength_law is not None:
            raise ParameterError(
                "strength_law", self.strength_law, f"None with {method} (N-PFEM only)"
            )
        if self.loads is not None:
            raise ParameterError(
                "loads",
                f"an array of shape {self.loads.shape}",
                f"None with {method} (dead loads are applied by N-PFEM only)",
            )

    def external_force(
        self,
        n: int,
        active: np.ndarray,
        mass: np.ndarray,
        time: float | None = None,
    ) -> np.ndarray:
        """Weight of a step's nodes plus the dead loads of their particles, N.

        ``n`` is the number of particles, ``active`` the indices of the
        step's nodes among them and ``mass`` their masses; ``time`` (s) is
        where a history of ``kh`` is read (:meth:`body_acceleration`).

        Examples
        --------
        >>> from skfem_npfem.materials import LinearElastic
        >>> m = Model(dim=2, materials=[LinearElastic(1e6, 0.3)], gravity=10.0,
        ...           loads=np.array([[0.0, -5.0], [1.0, 0.0], [0.0, 0.0]]))
        >>> m.external_force(3, np.array([0, 1]), np.array([2.0, 1.0]))
        array([[  0., -25.],
               [  1., -10.]])
        """
        force = mass[:, None] * self.body_acceleration(time)[None, :]
        if self.loads is None:
            return force
        if self.loads.shape[0] != n:
            raise ParameterError(
                "loads",
                self.loads.shape,
                f"one row per particle: shape ({n}, {self.dim})",
            )
        return force + self.loads[active]

    def _check_bodies(self) -> None:
        """Bodies of the model's dimension, with distinct names."""
        if isinstance(self.bodies, RigidBody | RigidPlane | BodyOfRevolution):
            self.bodies = [self.bodies]
        names = []
        for i, body in enumerate(self.bodies):
            if not isinstance(body, RigidBody | RigidPlane | BodyOfRevolution):
                raise ParameterError(
                    f"bodies[{i}]",
                    body,
                    "a RigidBody (2D), RigidPlane or BodyOfRevolution (3D)",
                )
            names.append(body.name)
            if body.dim != self.dim:
                allowed = (
                    "a RigidBody polygon in 2D models (plane strain or "
                    "axisymmetric); RigidPlane and BodyOfRevolution are for 3D"
                    if self.dim == 2
                    else "a RigidPlane or a BodyOfRevolution in 3D models "
                    "(RigidBody polygons are for 2D models)"
                )
                raise ParameterError(
                    f"bodies[{i}]",
                    f"a {type(body).__name__} in a {self.dim}D model",
                    allowed,
                )
        if len(set(names)) != len(names):
            raise ParameterError("bodies", names, "bodies with distinct names")

    def _check_axisymmetric(self) -> None:
        """Axisymmetry is 2D, and every plastic cone must see sigma_tt."""
        if self.dim != 2:
            raise ParameterError(
                "axisymmetric", True, "only with dim=2 (the (r, z) half-section)"
            )
        for m in self.materials:
            if m.plastic and not m.needs_zz(2):
                raise ParameterError(
                    "materials",
                    type(m).__name__,
                    "a cone with the hoop stress as a variable in axisymmetry: "
                    "DruckerPrager, VonMises or AxisymmetricMohrCoulomb "
                    "(plane-strain MohrCoulomb/Tresca ignore sigma_tt)",
                )

    def node_masses(
        self, mass: np.ndarray, material: np.ndarray, volumes: np.ndarray
    ) -> np.ndarray:
        """Masses of a step's nodes from their particles' (see ``nodal_mass``).

        Examples
        --------
        >>> from skfem_npfem.materials import LinearElastic
        >>> m = Model(dim=2, materials=[LinearElastic(1e6, 0.3)])
        >>> m.node_masses(np.array([1.0, 3.0]), np.array([0, 0]), np.ones(2))
        array([2., 2.])
        """
        if self.nodal_mass == "particle":
            return mass
        total = np.bincount(material, weights=mass)
        space = np.bincount(material, weights=volumes)
        density = np.divide(total, space, out=np.zeros_like(total), where=space > 0)
        return density[material] * volumes

    @property
    def components(self) -> tuple[int, ...]:
        """Full-Voigt components carried as cone variables."""
        if self.dim == 3:
            return (0, 1, 2, 3, 4, 5)
        if self.axisymmetric or any(m.needs_zz(2) for m in self.materials):
            return (0, 1, 2, 3)
        return (0, 1, 3)

    @property
    def boundaries(self) -> list[Boundary]:
        """The walls, then the bodies (if any), as the boundaries of a step.

        :class:`~skfem_npfem.boundary.walls.Walls` always (its contact rows
        come first, with ids ``0 .. len(walls)-1``), then
        :class:`~skfem_npfem.boundary.rigid_bodies.RigidBodies` when the model
        has bodies (ids from ``len(walls)``).
        """
        out: list[Boundary] = [Walls(self.walls, self.gravity)]
        if self.bodies:
            out.append(
                RigidBodies(
                    self.bodies,
                    len(self.walls),
                    self.dim,
                    self.axisymmetric,
                    self.gravity,
                )
            )
        return out

    @property
    def gravity_vector(self) -> np.ndarray:
        """Gravity as a vector (along ``-e_d``)."""
        g = np.zeros(self.dim)
        g[-1] = -self.gravity
        return g

    def kh_at(self, time: float | None) -> float:
        """The pseudo-static coefficient ``k_h`` at ``time`` (s).

        Examples
        --------
        >>> from skfem_npfem.materials import LinearElastic
        >>> m = Model(dim=2, materials=[LinearElastic(1e6, 0.3)],
        ...           kh=np.array([[0.0, 0.0], [1.0, 0.2], [2.0, -0.2]]))
        >>> [m.kh_at(t) for t in (-1.0, 0.5, 1.5, 3.0)]
        [0.0, 0.1, 0.0, -0.2]
        """
        kh = self.kh
        if np.ndim(kh) == 0:
            return float(kh)
        t = 0.0 if time is None else float(time)
        return float(np.interp(t, kh[:, 0], kh[:, 1]))

    def body_acceleration(self, time: float | None = None) -> np.ndarray:
        """Gravity plus the pseudo-static ``k_h g`` along ``+e_x`` at ``time``."""
        g = self.gravity_vector
        kh = self.kh_at(time)
        if kh:
            g[0] = kh * self.gravity
        return g

    def _check_kh(self) -> None:
        """``kh``: a finite number, or rows ``[t, k_h]`` with increasing ``t``."""
        kh = self.kh
        if isinstance(kh, bool):
            raise ParameterError("kh", kh, "a number or rows [t, k_h]")
        if np.ndim(kh) == 0:
            if not (isinstance(kh, int | float) and math.isfinite(kh)):
                raise ParameterError("kh", kh, "a finite number or rows [t, k_h]")
            return
        a = np.asarray(kh, float)
        if (
            a.ndim != 2
            or a.shape[1] != 2
            or a.shape[0] < 1
            or not np.all(np.isfinite(a))
            or np.any(np.diff(a[:, 0]) <= 0)
        ):
            raise ParameterError(
                "kh",
                f"an array of shape {a.shape}",
                "rows [t, k_h] (shape (n, 2), finite) with increasing t",
            )
        self.kh = a
