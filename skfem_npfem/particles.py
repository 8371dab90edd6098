"""Particle state: everything that survives a remesh lives here.

A mesh is a disposable view of the particles for one step; no variable is ever
mapped between meshes.  :class:`Particles` is immutable in spirit: the step
function takes particles and returns *new* particles.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace

import numpy as np
from skfem import Mesh

from .errors import ParameterError
from .materials import Material, full_voigt_size
from .mesh.axisymmetric import axisymmetric_integration
from .mesh.smoothing import check_p1_mesh, nodal_integration

__all__ = ["Particles"]


@dataclass(frozen=True)
class Particles:
    """State of N particles in d dimensions (SI units).

    Attributes
    ----------
    x : ndarray (N, d)
        Current positions, m.
    v : ndarray (N, d)
        Velocity, m/s.
    a : ndarray (N, d)
        Acceleration, m/s^2.
    u : ndarray (N, d)
        Total displacement since the start, m.
    stress : ndarray (N, n_full)
        Cauchy stress, full Voigt (2D ``xx, yy, zz, xy``; 3D ``xx, yy, zz, xy, yz,
        zx``), tension positive, Pa.
    eps_p : ndarray (N,)
        Equivalent plastic strain.
    mass : ndarray (N,)
        Fixed particle mass, kg (mass is conserved exactly).
    material : ndarray (N,) int
        Index into the model's material list.
    fixed : ndarray (N, d) bool
        Prescribed degrees of freedom.
    v_prescribed : ndarray (N, d)
        Velocity of prescribed dofs, m/s (0: fixed support).
    wall_force : ndarray (N, n_walls)
        Normal force of each wall on the particle from the previous step (N), the
        lagged bound of Coulomb friction.
    pore_pressure : ndarray (N,) or None
        Pore pressure after the last step, Pa (compression positive): the
        static field plus the excess.  None for a dry soil; with water
        (:class:`~skfem_npfem.water.Water`) ``stress`` is the *effective*
        stress and the total stress is ``stress - pore_pressure`` on the
        normal components.
    excess_pore_pressure : ndarray (N,) or None
        The part of ``pore_pressure`` above the static field, Pa: the state an
        undrained step carries to the next (zero when drained).
    strength : ndarray (N,) or None
        Factor on the cohesive strength of the particle's material (``c``,
        ``s_u``, ``sigma_y``; the friction angle is kept), >= 0: a soil
        profile whose strength varies from particle to particle (e.g.
        ``s_u(z) / s_u0``, :func:`~skfem_npfem.profiles.linear_strength`).
        None: 1 everywhere.
    stiffness : ndarray (N,) or None
        Factor on the elastic moduli of the particle's material (``E``; the
        Poisson's ratio is kept), > 0: e.g. ``E`` proportional to ``s_u``.
        None: 1 everywhere.
    shear_rate : ndarray (N,) or None
        Plastic shear-strain rate of the last step, 1/s (``sqrt(3)`` times
        the increment of ``eps_p`` over ``dt``): what a rate-dependent
        strength (:attr:`~skfem_npfem.Model.strength_law`) reads, and a
        refinement by the plastic strain rate marks by
        (:class:`~skfem_npfem.run.refining.Refiner`, ``strain_share``).  None
        without either.
    ids : ndarray (N,) int or None
        Stable particle ids (a particle keeps its id when particles are
        added, so ParaView can follow it; written as ``particle_id``).  None:
        the row index (no particle was ever added).
    spacing : ndarray (N,) or None
        Target spacing of each particle, m, where particles are added as the
        soil stretches (:mod:`skfem_npfem.run.refining`).  None: not refined.
    """

    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    u: np.ndarray
    stress: np.ndarray
    eps_p: np.ndarray
    mass: np.ndarray
    material: np.ndarray
    fixed: np.ndarray
    v_prescribed: np.ndarray
    wall_force: np.ndarray
    pore_pressure: np.ndarray | None = field(default=None, kw_only=True)
    excess_pore_pressure: np.ndarray | None = field(default=None, kw_only=True)
    strength: np.ndarray | None = field(default=None, kw_only=True)
    stiffness: np.ndarray | None = field(default=None, kw_only=True)
    shear_rate: np.ndarray | None = field(default=None, kw_only=True)
    ids: np.ndarray | None = field(default=None, kw_only=True)
    spacing: np.ndarray | None = field(default=None, kw_only=True)

    @classmethod
    def create(
        cls,
        x: np.ndarray,
        mass: np.ndarray,
        *,
        stress: np.ndarray | None = None,
        material: np.ndarray | None = None,
        fixed: np.ndarray | None = None,
        v: np.ndarray | None = None,
        n_walls: int = 0,
    ) -> Particles:
        """Build particles at rest with validated inputs.

        Parameters
        ----------
        x : array_like (N, d)
            Positions, m.
        mass : array_like (N,)
            Particle masses, kg, > 0.
        stress, material, fixed, v : optional
            Initial stress (N, n_full), material ids, fixed dofs, velocities.
        n_walls : int
            Number of rigid walls of the model.

        Raises
        ------
        ParameterError
            If an array cannot be read as numbers, has the wrong shape or holds
            NaN/inf, a mass is <= 0, or a material id is not an integer >= 0.
            The message names the argument, the offending value (or shape,
            or the first bad entry) and what is allowed.

        Examples
        --------
        >>> p = Particles.create(np.zeros((3, 2)), np.ones(3))
        >>> p.stress.shape
        (3, 4)
        """
        x = _float_array("x", x, "positions of shape (N, 2|3)")
        if x.ndim != 2 or x.shape[1] not in (2, 3) or x.shape[0] < 1:
            raise ParameterError("x", x.shape, "positions must have shape (N, 2|3)")
        n, d = x.shape
        zeros = np.zeros((n, d))
        m = _float_array("mass", mass, f"a number or an array of shape ({n},)")
        if m.ndim == 0:
            m = np.full(n, float(m))
        elif m.shape != (n,):
            raise ParameterError(
                "mass",
                m.shape,
                f"a number or an array of shape ({n},) (one per particle)",
            )
        if material is None:
            mat = np.zeros(n, int)
        else:
            mat = _index_array("material", material, n)
        if isinstance(n_walls, bool) or not isinstance(n_walls, int | np.integer):
            raise ParameterError("n_walls", n_walls, "an integer >= 0")
        if n_walls < 0:
            raise ParameterError("n_walls", n_walls, "an integer >= 0")
        p = cls(
            x=x,
            v=zeros.copy() if v is None else _float_array("v", v, f"shape ({n}, {d})"),
            a=zeros.copy(),
            u=zeros.copy(),
            stress=np.zeros((n, full_voigt_size(d)))
            if stress is None
            else _float_array("stress", stress, f"shape ({n}, {full_voigt_size(d)})"),
            eps_p=np.zeros(n),
            mass=m.copy(),
            material=mat,
            fixed=np.zeros((n, d), bool)
            if fixed is None
            else _bool_array("fixed", fixed, f"shape ({n}, {d})"),
            v_prescribed=zeros.copy(),
            wall_force=np.zeros((n, int(n_walls))),
        )
        p.validate()
        return p

    @classmethod
    def from_mesh(
        cls,
        mesh: Mesh,
        materials: Material | Sequence[Material],
        *,
        material: np.ndarray | None = None,
        fixed: np.ndarray | None = None,
        stress: np.ndarray | None = None,
        v: np.ndarray | None = None,
        n_walls: int = 0,
        axisymmetric: bool = False,
    ) -> Particles:
        """Particles at the nodes of a scikit-fem mesh, at rest.

        Particle ``i`` is node ``i`` of ``mesh`` (at ``mesh.p[:, i]``), and its
        mass is ``rho V_i``: the density of its material times the volume of
        its smoothing cell (:func:`~skfem_npfem.nodal_integration`; with
        ``axisymmetric=True`` the ``2 pi r``-weighted ring volume of
        :func:`~skfem_npfem.axisymmetric_integration`, kg of the full ring).
        The masses add up to ``rho`` times the mesh's area or volume.  The same
        mesh is the mesh source of a small-deformation step:
        ``advance(p, model, dt, mesh)`` or ``FixedMesh(mesh)``.

        Parameters
        ----------
        mesh : skfem.MeshTri or skfem.MeshTet
            P1 triangles (2D; ``(r, z)`` half-section if ``axisymmetric``) or
            tetrahedra (3D); every node in an element.
        materials : Material or sequence of Material
            The material, or the model's material list (then ``material``
            picks one per particle).
        material : array_like (N,) of int, optional
            Index into ``materials`` per particle (default 0).
        fixed : array_like (N, d) or (N,) of bool, optional
            Prescribed degrees of freedom; a row of one flag fixes every
            component of that particle.
        stress, v : array_like, optional
            Initial stress (N, n_full), Pa, and velocity (N, d), m/s.
        n_walls : int
            Number of rigid walls of the model.
        axisymmetric : bool
            Masses of an axisymmetric model (``Model(axisymmetric=True)``).

        Returns
        -------
        Particles

        Raises
        ------
        ParameterError
            If ``mesh`` is not a P1 simplex mesh, a material has no positive
            density, an index is outside ``materials``, or an array has the
            wrong shape (as :meth:`create`).

        Examples
        --------
        >>> from skfem import MeshTri
        >>> from skfem_npfem import LinearElastic
        >>> soil = LinearElastic(E=1e7, nu=0.3, rho=2000.0)
        >>> mesh = MeshTri.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 2, 5))
        >>> base = mesh.p[1] == 0.0
        >>> p = Particles.from_mesh(mesh, soil, fixed=base)
        >>> p.n, float(p.mass.sum()), int(p.fixed.sum())
        (15, 4000.0, 6)
        """
        if not isinstance(mesh, Mesh):
            raise ParameterError(
                "mesh", type(mesh).__name__, "a scikit-fem MeshTri or MeshTet"
            )
        check_p1_mesh(mesh)
        mats = [materials] if isinstance(materials, Material) else list(materials)
        if not mats or not all(isinstance(m, Material) for m in mats):
            raise ParameterError(
                "materials", _describe(materials), "a Material or a list of them"
            )
        rho = np.array([m.rho for m in mats], float)
        if not np.all(rho > 0):
            i = int(np.flatnonzero(~(rho > 0))[0])
            raise ParameterError(
                "materials",
                f"{type(mats[i]).__name__} with rho={rho[i]:g}",
                "a density rho > 0 (kg/m^3) for the masses rho V_i",
            )
        x = mesh.p.T
        n, d = x.shape
        ids = (
            np.zeros(n, np.int64)
            if material is None
            else _index_array("material", material, n)
        )
        if ids.size and ids.max() >= len(mats):
            raise ParameterError(
                "material",
                int(ids.max()),
                f"indices into the {len(mats)} material(s) given (0..{len(mats) - 1})",
            )
        cells = (
            axisymmetric_integration(mesh) if axisymmetric else nodal_integration(mesh)
        )
        mass = rho[ids] * cells.volumes
        if fixed is not None:
            fixed = _bool_array("fixed", fixed, f"shape ({n}, {d}) or ({n},)")
            if fixed.shape == (n,):
                fixed = np.repeat(fixed[:, None], d, axis=1)
        return cls.create(
            x,
            mass,
            stress=stress,
            material=ids,
            fixed=fixed,
            v=v,
            n_walls=n_walls,
        )

    @property
    def n(self) -> int:
        """Number of particles."""
        return self.x.shape[0]

    @property
    def dim(self) -> int:
        """Spatial dimension."""
        return self.x.shape[1]

    def replace(self, **changes: np.ndarray) -> Particles:
        """Return new particles with some fields replaced."""
        return replace(self, **changes)

    def validate(self) -> None:
        """Check shapes and finiteness; raise :class:`ParameterError` otherwise."""
        n, d = self.x.shape
        shapes = {
            "x": (n, d),
            "v": (n, d),
            "a": (n, d),
            "u": (n, d),
            "stress": (n, full_voigt_size(d)),
            "eps_p": (n,),
            "mass": (n,),
            "material": (n,),
            "fixed": (n, d),
            "v_prescribed": (n, d),
        }
        for name, shape in shapes.items():
            arr = getattr(self, name)
            if arr.shape != shape:
                raise ParameterError(name, arr.shape, f"expected shape {shape}")
            _check_finite(name, arr)
        if self.wall_force.ndim != 2 or self.wall_force.shape[0] != n:
            raise ParameterError("wall_force", self.wall_force.shape, "(N, n_walls)")
        _check_finite("wall_force", self.wall_force)
        for name in _OPTIONAL:
            arr = getattr(self, name)
            if arr is None:
                continue
            if arr.shape != (n,):
                raise ParameterError(name, arr.shape, f"expected shape ({n},) or None")
            _check_finite(name, arr)
        if self.ids is not None and self.ids.dtype.kind not in "iu":
            raise ParameterError("ids", self.ids.dtype, "integer particle ids")
        if self.spacing is not None and np.any(self.spacing <= 0.0):
            raise ParameterError("spacing", float(self.spacing.min()), "spacings > 0")
        if self.strength is not None and np.any(self.strength < 0.0):
            raise ParameterError(
                "strength",
                float(self.strength.min()),
                "strength factors >= 0 (a factor on the material's cohesion)",
            )
        if self.stiffness is not None and np.any(self.stiffness <= 0.0):
            raise ParameterError(
                "stiffness",
                float(self.stiffness.min()),
                "stiffness factors > 0 (a factor on the material's moduli)",
            )
        if np.any(self.mass <= 0):
            i = int(np.argmin(self.mass))
            raise ParameterError(
                "mass",
                float(self.mass[i]),
                f"particle masses must be > 0 (particle {i})",
            )
        if self.material.dtype.kind not in "iu" or np.any(self.material < 0):
            raise ParameterError(
                "material",
                f"{self.material.dtype} array, min {self.material.min(initial=0)}",
                "integer indices >= 0 into the model's material list",
            )

    def arrays(self) -> dict[str, np.ndarray]:
        """All fields as a dict of arrays (used by checkpoints; None left out)."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        return {k: v for k, v in out.items() if v is not None}

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray]) -> Particles:
        """Inverse of :meth:`arrays`; validates the result."""
        try:
            p = cls(
                **{
                    f.name: np.asarray(arrays[f.name])
                    for f in fields(cls)
                    if f.name not in _OPTIONAL or f.name in arrays
                }
            )
        except KeyError as err:
            raise ParameterError("arrays", sorted(arrays), f"missing {err}") from None
        p.validate()
        return p


#: Fields that may be None (left out of :meth:`Particles.arrays`).
_OPTIONAL = (
    "pore_pressure",
    "excess_pore_pressure",
    "strength",
    "stiffness",
    "shear_rate",
    "ids",
    "spacing",
)


def _describe(value: object) -> object:
    """The value itself if its repr is short, else a truncated repr."""
    text = repr(value)
    return value if len(text) <= 60 else text[:57] + "..."


def _float_array(name: str, value: object, allowed: str) -> np.ndarray:
    """``np.array(value, float)`` that raises :class:`ParameterError`."""
    try:
        return np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(
            name, _describe(value), f"real numbers, {allowed}"
        ) from None


def _bool_array(name: str, value: object, allowed: str) -> np.ndarray:
    """``np.array(value, bool)`` that raises :class:`ParameterError`."""
    try:
        return np.array(value, dtype=bool)
    except (TypeError, ValueError):
        raise ParameterError(name, _describe(value), f"booleans, {allowed}") from None


def _index_array(name: str, value: object, n: int) -> np.ndarray:
    """Integer indices >= 0 of shape (n,); floats must be integral."""
    allowed = f"integer indices >= 0, a number or shape ({n},)"
    a = _float_array(name, value, allowed)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ParameterError(name, a.shape, allowed)
    bad = ~np.isfinite(a) | (a < 0) | (a != np.round(a))
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise ParameterError(name, float(a[i]), f"{allowed} (particle {i})")
    return a.astype(np.int64)


def _check_finite(name: str, arr: np.ndarray) -> None:
    """Raise :class:`ParameterError` naming the first NaN/inf entry of ``arr``."""
    if arr.dtype.kind not in "fc":
        return
    bad = ~np.isfinite(arr)
    if np.any(bad):
        idx = np.argwhere(bad)[0]
        where = ", ".join(str(int(k)) for k in idx)
        first = arr[tuple(idx)]
        raise ParameterError(
            name,
            f"{int(bad.sum())} non-finite value(s), first {first} at [{where}]",
            "all values finite",
        )
