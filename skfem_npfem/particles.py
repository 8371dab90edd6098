"""Particle state: everything that survives a remesh lives here.

A mesh is a disposable view of the particles for one step; no variable is ever
mapped between meshes.  :class:`Particles` is immutable in spirit: the step
function takes particles and returns *new* particles.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from .errors import ParameterError
from .materials import full_voigt_size

__all__ = ["Particles"]


@dataclass(frozen=True)
class Particles:
    """State of N particles in d dimensions (SI units).

    Attributes
    ----------
    x : ndarray (N, d)
        Current positions, m.
    v, a : ndarray (N, d)
        Velocity (m/s) and acceleration (m/s^2).
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

        Examples
        --------
        >>> p = Particles.create(np.zeros((3, 2)), np.ones(3))
        >>> p.stress.shape
        (3, 4)
        """
        x = np.array(x, dtype=float)
        if x.ndim != 2 or x.shape[1] not in (2, 3) or x.shape[0] < 1:
            raise ParameterError("x", x.shape, "positions must have shape (N, 2|3)")
        n, d = x.shape
        zeros = np.zeros((n, d))
        p = cls(
            x=x,
            v=zeros.copy() if v is None else np.array(v, float),
            a=zeros.copy(),
            u=zeros.copy(),
            stress=np.zeros((n, full_voigt_size(d)))
            if stress is None
            else np.array(stress, float),
            eps_p=np.zeros(n),
            mass=np.broadcast_to(np.asarray(mass, float), (n,)).copy(),
            material=np.zeros(n, int) if material is None else np.array(material, int),
            fixed=np.zeros((n, d), bool) if fixed is None else np.array(fixed, bool),
            v_prescribed=zeros.copy(),
            wall_force=np.zeros((n, n_walls)),
        )
        p.validate()
        return p

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
            if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
                raise ParameterError(name, "non-finite values", "all values finite")
        if self.wall_force.shape[0] != n:
            raise ParameterError("wall_force", self.wall_force.shape, "(N, n_walls)")
        if np.any(self.mass <= 0):
            raise ParameterError(
                "mass", float(self.mass.min()), "particle masses must be > 0"
            )

    def arrays(self) -> dict[str, np.ndarray]:
        """All fields as a dict of arrays (used by checkpoints)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray]) -> Particles:
        """Inverse of :meth:`arrays`; validates the result."""
        try:
            p = cls(**{f.name: np.asarray(arrays[f.name]) for f in fields(cls)})
        except KeyError as err:
            raise ParameterError("arrays", sorted(arrays), f"missing {err}") from None
        p.validate()
        return p
