"""Soil profiles: strength and stiffness that vary with depth, per particle.

A particle carries factors on its material's cohesive strength and elastic
moduli (:attr:`~skfem_npfem.Particles.strength`,
:attr:`~skfem_npfem.Particles.stiffness`); a step's yield cone of that
particle has the cohesion ``f c`` (``f s_u`` for Tresca, ``f sigma_y`` for von
Mises), its friction angle unchanged, and its compliance is divided by the
stiffness factor.  A profile is therefore a field of numbers on the
particles, set once; nothing is mapped between meshes, since the factors
travel with the particles like every other state.

The profile of site investigation is linear, ``s_u(z) = s_u0 + k z`` with
``z`` the depth below the ground: :func:`linear_strength` gives its factors
``s_u(z) / s_u0``.  ``E`` proportional to ``s_u`` keeps the rigidity index
``G / s_u`` uniform (the usual assumption of cone-factor studies): the same
factors serve as stiffness factors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError

__all__ = [
    "StrengthProfile",
    "check_factors",
    "linear_strength",
    "profile_point_data",
    "strength_factors",
]


def linear_strength(depth: np.ndarray, s0: float, gradient: float) -> np.ndarray:
    """Factors ``s(z) / s0 = 1 + gradient z / s0`` of a linear profile.

    Parameters
    ----------
    depth : array_like (N,)
        Depth of each particle below the ground, m; particles above it
        (negative depth) take the ground's strength.
    s0 : float
        Strength at the ground (the material's ``c`` or ``s_u``), Pa, > 0.
    gradient : float
        Increase of the strength with depth ``k``, Pa/m, >= 0.

    Returns
    -------
    ndarray (N,)
        Factors >= 1 on the material's cohesive strength.

    Raises
    ------
    ParameterError
        If ``s0 <= 0`` (no strength at the ground to scale) or ``gradient``
        is negative or not finite.

    Examples
    --------
    >>> linear_strength([0.0, 1.0, 2.0, -0.5], 1e3, 2e3)
    array([1., 3., 5., 1.])
    """
    return StrengthProfile.linear(s0, gradient).at(depth) / s0


def strength_factors(strength: np.ndarray, n: int) -> np.ndarray:
    """Per-node strength factors (n,), checked finite and >= 0.

    Examples
    --------
    >>> strength_factors([1.0, 2.5], 2)
    array([1. , 2.5])
    """
    f = np.asarray(strength, float).reshape(-1)
    if f.shape != (n,) or not np.all(np.isfinite(f)) or np.any(f < 0.0):
        raise ParameterError(
            "strength",
            f"{f.shape[0]} values, min {f.min(initial=0.0):g}",
            f"{n} finite factors >= 0 (one per node of the material)",
        )
    return f


def check_factors(name: str, factors: object, n: int, positive: bool) -> None:
    """Refuse per-point factors that are not ``n`` finite numbers ``>= 0``.

    ``positive``: ``> 0`` (a stiffness factor; a strength factor may be 0).

    Raises
    ------
    ParameterError
        Naming ``name``, the shape given and what is allowed.
    """
    f = np.asarray(factors, float)
    ok = f.shape == (n,) and bool(np.all(np.isfinite(f)))
    if ok:
        ok = bool(np.all(f > 0)) if positive else bool(np.all(f >= 0))
    if not ok:
        sign = "> 0" if positive else ">= 0"
        raise ParameterError(
            name, f"array of shape {f.shape}", f"({n},) finite factors {sign}"
        )


def profile_point_data(particles: object) -> dict[str, np.ndarray]:
    """The particles' ``strength`` and ``stiffness`` factors that are set."""
    out = {}
    for name in ("strength", "stiffness"):
        if getattr(particles, name, None) is not None:
            out[name] = getattr(particles, name)
    return out


@dataclass(frozen=True)
class StrengthProfile:
    """An undrained strength by layers: ``s_u(z) = s_i + k_i (z - top_i)``.

    Layer ``i`` runs from depth ``top_i`` (m below the ground) to the next
    layer's top; the first starts at the ground (``top = 0``).  A uniform
    soil is one layer with ``k = 0``, the linear profile one layer with its
    gradient.

    Parameters
    ----------
    tops, strengths, gradients : tuple of float
        Each layer's top (m, increasing from 0), its strength there (Pa, >
        0) and its gradient (Pa/m, >= 0).

    Examples
    --------
    >>> p = StrengthProfile.from_rows([[0.0, 10e3, 2e3], [5.0, 40e3]])
    >>> [float(s) for s in p.at(np.array([0.0, 4.0, 5.0, 9.0, -1.0]))]
    [10000.0, 18000.0, 40000.0, 40000.0, 10000.0]
    """

    tops: tuple[float, ...]
    strengths: tuple[float, ...]
    gradients: tuple[float, ...]

    @classmethod
    def linear(cls, s0: float, gradient: float) -> StrengthProfile:
        """One layer from the ground: ``s0 + gradient z``.

        Raises
        ------
        ParameterError
            If ``s0 <= 0`` (no strength at the ground) or ``gradient`` is
            negative or not finite.
        """
        finite = isinstance(gradient, int | float) and math.isfinite(gradient)
        if not finite or gradient < 0:
            raise ParameterError(
                "su_gradient", gradient, "a finite increase >= 0 (Pa/m)"
            )
        if not s0 > 0:
            raise ParameterError(
                "su",
                s0,
                "a strength at the ground > 0 (Pa): the profile s_u0 + k z scales it",
            )
        return cls((0.0,), (float(s0),), (float(gradient),))

    @classmethod
    def from_rows(cls, rows: object, name: str = "layers") -> StrengthProfile:
        """Layers from rows ``[top, s_u]`` or ``[top, s_u, k]`` (m, Pa, Pa/m).

        Raises
        ------
        ParameterError
            Naming ``name``: not a list of such rows, a first top other than
            0, tops not increasing, a strength <= 0 or a gradient < 0.
        """
        allowed = (
            "a list of [top, s_u] or [top, s_u, k] rows: depth of the layer's "
            "top below the ground (m; the first 0, then increasing), its "
            "undrained strength there (Pa, > 0) and its increase with depth "
            "(Pa/m, >= 0, default 0)"
        )
        try:
            table = [[float(v) for v in row] for row in rows]  # type: ignore[union-attr]
        except (TypeError, ValueError):
            raise ParameterError(name, rows, allowed) from None
        ok = bool(table) and all(len(r) in (2, 3) for r in table)
        ok = ok and all(math.isfinite(v) for r in table for v in r)
        if not ok:
            raise ParameterError(name, rows, allowed)
        tops = [r[0] for r in table]
        if tops[0] != 0.0 or np.any(np.diff(tops) <= 0):
            raise ParameterError(name, rows, allowed + "; tops " + str(tops))
        strengths = [r[1] for r in table]
        gradients = [r[2] if len(r) == 3 else 0.0 for r in table]
        if min(strengths) <= 0 or min(gradients) < 0:
            raise ParameterError(name, rows, allowed)
        return cls(tuple(tops), tuple(strengths), tuple(gradients))

    @property
    def uniform(self) -> bool:
        """One layer without a gradient."""
        return len(self.tops) == 1 and self.gradients[0] == 0.0

    def at(self, depth: np.ndarray) -> np.ndarray:
        """``s_u`` at depths below the ground (above it: the ground's), Pa."""
        z = np.maximum(np.asarray(depth, float), 0.0)
        i = np.searchsorted(np.asarray(self.tops), z, side="right") - 1
        s, k = np.asarray(self.strengths), np.asarray(self.gradients)
        return s[i] + k[i] * (z - np.asarray(self.tops)[i])
