"""Undrained limit analysis in effective stress: per-point undrained strengths.

An associated Mohr-Coulomb skeleton dilates as it yields, so a
volume-preserving (undrained) limit analysis of it has no mechanism: every
plastic strain rate of the cone changes the volume.  Undrained collapse is
therefore analysed with the strength the initial effective stress implies:
with the mean effective stress held at its initial value ``s'_0`` (the
excess pore pressure takes every change of the total mean stress), the
Mohr-Coulomb cone cut at ``s'_0`` is a Tresca cone of strength

    s_u = c' cos(phi') + s'_0 sin(phi')        (plane strain)

with ``s'_0 = -(s'_xx + s'_yy) / 2`` (tension positive), the centre of the
in-plane Mohr circle.  :class:`UndrainedStrength` is that cone per point;
:func:`undrained_materials` builds it for every material of a body from the
particles' initial effective stresses, and :func:`undrained_strength` gives
the strengths themselves (for a summary).  Its pressure-independent cone
leaves the mean total stress free, so the excess pore pressure needs no
variable of its own: it is the difference between the mean stress of the
collapse state and ``-s'_0``.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from ..materials import (
    ConeRows,
    DruckerPrager,
    Material,
    MohrCoulomb,
    _dp_rows,
    strength_factors,
)
from ..mesh.axisymmetric import AxisymmetricMohrCoulomb, mohr_coulomb_cones

__all__ = [
    "UndrainedStrength",
    "mean_effective_stress",
    "undrained_materials",
    "undrained_strength",
]


def _kind(material: Material) -> str:
    """Which undrained cone a drained material turns into."""
    if isinstance(material, AxisymmetricMohrCoulomb):
        return "axisymmetric"
    if isinstance(material, DruckerPrager):
        return "drucker-prager"
    if isinstance(material, MohrCoulomb):
        return "plane-strain"
    raise ParameterError(
        "material",
        type(material).__name__,
        "MohrCoulomb, Tresca, AxisymmetricMohrCoulomb or DruckerPrager "
        "(a material with c' and phi')",
    )


def mean_effective_stress(stress: np.ndarray, kind: str = "plane-strain") -> np.ndarray:
    """The effective pressure ``s'_0`` an undrained cone is cut at, Pa.

    Parameters
    ----------
    stress : ndarray (n, n_full)
        Effective stresses (full Voigt, tension positive), Pa.
    kind : {"plane-strain", "axisymmetric", "drucker-prager"}
        ``plane-strain``: ``-(s_xx + s_yy) / 2``, the centre of the in-plane
        Mohr circle; otherwise the mean effective stress ``-(s_xx + s_yy +
        s_zz) / 3``.

    Returns
    -------
    ndarray (n,)
        Compression positive.
    """
    s = np.atleast_2d(np.asarray(stress, float))
    if kind == "plane-strain":
        return -(s[:, 0] + s[:, 1]) / 2.0
    return -(s[:, 0] + s[:, 1] + s[:, 2]) / 3.0


class UndrainedStrength(Material):
    """A drained material's undrained (Tresca-type) cone at fixed ``s'_0``.

    Per point ``i`` the strength is that of the drained cone at the effective
    pressure ``s'_0,i``, held fixed:

    * Mohr-Coulomb in plane strain: Tresca ``R <= s_u`` with ``s_u = c'
      cos(phi') + s'_0 sin(phi')``, ``s'_0 = -(s'_xx + s'_yy)/2``;
    * Mohr-Coulomb in axisymmetry (:class:`AxisymmetricMohrCoulomb`): the
      axisymmetric Tresca cones with the same ``s_u`` and ``s'_0`` the mean
      effective stress ``-I'_1/3``, because the hoop stress is a principal
      stress that may be the major or minor one, so only the invariant mean
      is a pressure every cone shares;
    * Drucker-Prager (plane strain and 3D): von Mises ``sqrt(J2) <= k + 3
      alpha s'_0`` with ``s'_0 = -I'_1/3``, the Drucker-Prager cone cut at
      the initial mean effective stress (the same construction for the
      invariant cone).

    Strengths below zero (effective tension beyond the apex) are clamped at
    zero.  The material carries ``c``, ``phi`` (and ``psi = phi``) of the
    drained one, so :func:`~skfem_npfem.limit.safety.reduced_strength`
    divides ``c'`` and ``tan(phi')`` by ``F`` and the strengths follow: the
    factor of safety of an undrained analysis is the one on the effective
    strength parameters, with ``s'_0`` kept.

    Parameters
    ----------
    material : Material
        The drained material (MohrCoulomb, Tresca, AxisymmetricMohrCoulomb or
        DruckerPrager); its elastic constants and density are kept.
    pressure : array_like (n,)
        ``s'_0`` of the points of this material, in the order of the points
        that carry it (:func:`undrained_materials` builds it), Pa.

    Examples
    --------
    >>> mc = MohrCoulomb(1e7, 0.3, c=1e3, phi=30.0)
    >>> u = UndrainedStrength(mc, [0.0, 2e3])
    >>> [round(float(s)) for s in u.s_u]
    [866, 1866]
    """

    plastic = True

    def __init__(self, material: Material, pressure: np.ndarray) -> None:
        kind = _kind(material)
        super().__init__(material.E, material.nu, material.rho)
        self.dims = material.dims
        self.kind = kind
        self.c = float(material.c)
        self.phi = float(material.phi)
        self.psi = self.phi
        self.tension_cutoff = False
        self.match = getattr(material, "match", None)
        p = np.asarray(pressure, float).reshape(-1)
        if not np.all(np.isfinite(p)):
            raise ParameterError("pressure", "NaN or inf", "finite s'_0 (Pa)")
        self.pressure = p

    def needs_zz(self, dim: int) -> bool:  # noqa: D102
        return self.kind != "plane-strain"

    @property
    def s_u(self) -> np.ndarray:
        """Undrained strength per point (the shear strength ``R``), Pa."""
        return self.strengths(None)

    def strengths(self, strength: np.ndarray | None) -> np.ndarray:
        """``s_u`` per point with the cohesion scaled by ``strength`` (n,), Pa."""
        f = 1.0 if strength is None else strength_factors(strength, self.pressure.size)
        phi = math.radians(self.phi)
        if self.kind == "drucker-prager":
            dp = DruckerPrager(
                self.E, self.nu, c=self.c, phi=self.phi, match=self.match
            )
            alpha, k = dp.alpha_k(self.phi)
            return np.maximum(f * k + 3.0 * alpha * self.pressure, 0.0)
        cohesive = self.c * math.cos(phi)
        return np.maximum(f * cohesive + self.pressure * math.sin(phi), 0.0)

    def cone(  # noqa: D102
        self,
        dim: int,
        components: tuple[int, ...],
        sigma_n: np.ndarray,
        strength: np.ndarray | None = None,
    ) -> ConeRows | list[ConeRows]:
        n = np.atleast_2d(sigma_n).shape[0]
        if n != self.pressure.size:
            raise ParameterError(
                "pressure",
                f"{self.pressure.size} values",
                f"one s'_0 per point of the material ({n})",
            )
        comp = list(components)
        zero = np.zeros((n, len(comp)))
        s_u = self.s_u if strength is None else self.strengths(strength)
        if self.kind == "drucker-prager":
            return ConeRows(a=zero, k=s_u, M=_dp_rows(dim)[:, comp])
        if self.kind == "plane-strain":
            M = np.array([[1.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 2.0]])
            return ConeRows(a=zero, k=2.0 * s_u, M=M[:, comp])
        # Axisymmetric Tresca: the three cones of phi = 0, strengths s_u, 2 s_u, 2 s_u.
        return [
            ConeRows(
                a=np.broadcast_to(a[comp], (n, len(comp))).copy(),
                k=k * s_u,
                M=M[:, comp],
            )
            for a, k, M in mohr_coulomb_cones(0.0, 1.0)
        ]


def undrained_strength(material: Material, stress: np.ndarray) -> np.ndarray:
    """The undrained strengths a drained material has at effective stresses.

    Parameters
    ----------
    material : Material
        MohrCoulomb, Tresca, AxisymmetricMohrCoulomb or DruckerPrager.
    stress : ndarray (n, n_full)
        Effective stresses of its points (full Voigt, tension positive), Pa.

    Returns
    -------
    ndarray (n,)
        ``s_u`` per point, Pa (:class:`UndrainedStrength`).

    Examples
    --------
    >>> mc = MohrCoulomb(1e7, 0.3, c=0.0, phi=30.0)
    >>> undrained_strength(mc, np.array([[-1e3, -3e3, -1e3, 0.0]]))
    array([1000.])
    """
    kind = _kind(material)
    return UndrainedStrength(material, mean_effective_stress(stress, kind)).s_u


def undrained_materials(
    materials: list[Material], material: np.ndarray, stress: np.ndarray
) -> list[Material]:
    """Every drained material of a body turned into its :class:`UndrainedStrength`.

    Parameters
    ----------
    materials : list of Material
        The body's (drained, effective-strength) materials.  Elastic ones are
        kept as they are.
    material : ndarray (n_p,) int
        Material index per stress point.
    stress : ndarray (n_p, n_full)
        The points' initial effective stresses, Pa.

    Returns
    -------
    list of Material
        In the order of ``materials``; pass it with the same ``material`` to
        :func:`~skfem_npfem.limit.limit_analysis` or
        :func:`~skfem_npfem.limit.strength_reduction`.

    Raises
    ------
    ParameterError
        For a plastic material without ``c'`` and ``phi'``, or shapes that
        disagree.
    """
    material = np.asarray(material)
    stress = np.atleast_2d(np.asarray(stress, float))
    if stress.shape[0] != material.shape[0]:
        raise ParameterError(
            "stress", f"{stress.shape[0]} rows", f"one per point ({material.shape[0]})"
        )
    out: list[Material] = []
    for m_id, mat in enumerate(materials):
        if not mat.plastic:
            out.append(mat)
            continue
        kind = _kind(mat)
        points = material == m_id
        out.append(UndrainedStrength(mat, mean_effective_stress(stress[points], kind)))
    return out
