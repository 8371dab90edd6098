"""Materials: elastic compliance and yield cones.

Every yield criterion is written as one second-order cone per node,

    k_i - a_i^T sigma_i >= || M sigma_i ||,

in the full Voigt order of :mod:`skfem_npfem.mesh.smoothing` (2D: ``xx, yy, zz, xy``;
3D: ``xx, yy, zz, xy, yz, zx``), tension positive, Pa.  Angles are in degrees.

Available materials

=====================  ======  ==========================================
class                  dims    cone
=====================  ======  ==========================================
:class:`LinearElastic`  2, 3   none (an elastic scene pays no cone)
:class:`MohrCoulomb`    2      plane-strain Mohr-Coulomb (exact), SOC(3)
:class:`Tresca`         2      plane-strain Tresca (= von Mises), SOC(3)
:class:`DruckerPrager`  2, 3   Drucker-Prager, SOC(4) in 2D, SOC(6) in 3D
:class:`VonMises`       2, 3   von Mises, SOC(4) in 2D, SOC(6) in 3D
=====================  ======  ==========================================

Non-associated flow (dilation angle ``psi < phi``) uses the frozen-friction device
of Krabbenhoft et al. (2012): the cone has friction ``psi`` and the difference
``(a_phi - a_psi)^T sigma_n`` is moved onto the strength with the *previous*
stress, clamped at zero.  An optional tension cut-off bounds the mean stress by
the apex of the true (``phi``) cone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .elasticity import compliance_matrix
from .errors import ParameterError
from .profiles import strength_factors

__all__ = [
    "ConeRows",
    "DruckerPrager",
    "LinearElastic",
    "Material",
    "MohrCoulomb",
    "Tresca",
    "VonMises",
    "compliance_matrix",
    "full_voigt_size",
    "strength_factors",
]


def full_voigt_size(dim: int) -> int:
    """Number of full Voigt stress components (4 in 2D plane strain, 6 in 3D)."""
    return 4 if dim == 2 else 6


def _check_number(name: str, value: float, lo: float, hi: float, closed: str) -> float:
    """Validate a finite real number in an interval; ``closed`` is e.g. "[)" ."""
    if isinstance(value, bool | np.bool_):  # float(True) would pass silently
        raise ParameterError(name, value, "a real number, not a boolean")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, value, "a real number") from None
    ok = math.isfinite(v)
    if ok:
        ok = (v >= lo if closed[0] == "[" else v > lo) and (
            v <= hi if closed[1] == "]" else v < hi
        )
    if not ok:

        def fmt(x: float) -> str:
            return "inf" if math.isinf(x) else f"{x:g}"

        interval = f"{closed[0]}{fmt(lo)}, {fmt(hi)}{closed[1]}"
        raise ParameterError(name, value, f"must be a finite number in {interval}")
    return v


@dataclass(frozen=True)
class ConeRows:
    """One yield cone per node: ``k - a^T s >= ||M s||`` (and an optional cut-off).

    Attributes
    ----------
    a : ndarray, shape (n, n_s)
        Linear part per node.
    k : ndarray, shape (n,)
        Strength per node (Pa), ``>= 0``.
    M : ndarray, shape (m, n_s)
        Norm rows (the same for every node).
    cutoff_a, cutoff_k : ndarray (n_s,), float (or ndarray (n,)), or None
        Tension cut-off ``cutoff_a^T s <= cutoff_k`` (``cutoff_k`` per node
        when the strength varies from node to node).
    """

    a: np.ndarray
    k: np.ndarray
    M: np.ndarray
    cutoff_a: np.ndarray | None = None
    cutoff_k: float | np.ndarray | None = None


class Material:
    """Base class: elastic constants, density and (optionally) a yield cone.

    Parameters
    ----------
    E : float
        Young's modulus, Pa, > 0.
    nu : float
        Poisson's ratio, in (-1, 0.5).
    rho : float
        Density, kg/m^3, >= 0 (default 0).

    Raises
    ------
    ParameterError
        If a constant is not a finite number in its range (booleans are
        refused too), naming it and the allowed interval.
    """

    #: True when the material contributes a yield cone.
    plastic: bool = False
    #: Spatial dimensions the material supports.
    dims: tuple[int, ...] = (2, 3)

    def __init__(self, E: float, nu: float, rho: float = 0.0) -> None:
        self.E = _check_number("E", E, 0.0, math.inf, "()")
        self.nu = _check_number("nu", nu, -1.0, 0.5, "()")
        self.rho = _check_number("rho", rho, 0.0, math.inf, "[)")

    def check_dim(self, dim: int) -> None:
        """Raise :class:`ParameterError` if the material is not available in ``dim``."""
        if dim not in self.dims:
            raise ParameterError(
                "dim",
                dim,
                f"{type(self).__name__} is available for dim in {self.dims}; "
                "in 3D use DruckerPrager or VonMises",
            )

    def needs_zz(self, dim: int) -> bool:
        """Whether ``sigma_zz`` must be a cone variable in plane strain."""
        return False

    def compliance(self, dim: int, components: tuple[int, ...]) -> np.ndarray:
        """Elastic compliance on ``components`` (see :func:`compliance_matrix`)."""
        return compliance_matrix(self.E, self.nu, dim, components)

    def cone(
        self,
        dim: int,
        components: tuple[int, ...],
        sigma_n: np.ndarray,
        strength: np.ndarray | None = None,
    ) -> ConeRows | None:
        """Cone rows for nodes with previous stresses ``sigma_n`` (n, n_full).

        ``strength`` (n,), when given, scales each node's cohesive strength
        (``c``, ``sigma_y``): the per-particle strength of a soil profile
        (:attr:`~skfem_npfem.Particles.strength`); the friction is kept.
        """
        return None

    @property
    def p_wave_modulus(self) -> float:
        """Constrained (oedometric) modulus ``E(1-nu)/((1+nu)(1-2nu))``, Pa."""
        return self.E * (1 - self.nu) / ((1 + self.nu) * (1 - 2 * self.nu))

    def __repr__(self) -> str:
        fields = ", ".join(f"{k}={v!r}" for k, v in vars(self).items())
        return f"{type(self).__name__}({fields})"


class LinearElastic(Material):
    """Linear isotropic elasticity (no yield cone).

    Parameters
    ----------
    E, nu, rho : float
        Young's modulus (Pa, > 0), Poisson's ratio (in (-1, 0.5)) and density
        (kg/m^3, >= 0, default 0), as :class:`Material`; out-of-range values
        raise :class:`~skfem_npfem.errors.ParameterError`.

    Examples
    --------
    >>> LinearElastic(E=1e7, nu=0.3, rho=1800).p_wave_modulus > 1e7
    True
    """


class _Frictional(Material):
    """Shared parameter handling of frictional-cohesive cones."""

    def __init__(
        self,
        E: float,
        nu: float,
        rho: float = 0.0,
        *,
        c: float = 0.0,
        phi: float = 0.0,
        psi: float | None = None,
        tension_cutoff: bool = False,
    ) -> None:
        super().__init__(E, nu, rho)
        self.c = _check_number("c", c, 0.0, math.inf, "[)")
        self.phi = _check_number("phi", phi, 0.0, 90.0, "[)")
        psi = self.phi if psi is None else psi
        self.psi = _check_number("psi", psi, 0.0, self.phi, "[]")
        if self.c == 0.0 and self.phi == 0.0:
            raise ParameterError(
                "c", c, "must be > 0 when phi = 0 (the material would have no strength)"
            )
        self.tension_cutoff = bool(tension_cutoff)

    def _a_k(self, friction_deg: float) -> tuple[np.ndarray, float]:
        raise NotImplementedError

    def cone(
        self,
        dim: int,
        components: tuple[int, ...],
        sigma_n: np.ndarray,
        strength: np.ndarray | None = None,
    ) -> ConeRows:
        """Cone rows with the frozen-friction strength for ``psi < phi``."""
        sigma_n = np.atleast_2d(sigma_n)
        a_phi, k0 = self._a_k(self.phi)
        a_psi, _ = self._a_k(self.psi)
        if strength is not None:
            k0 = k0 * strength_factors(strength, sigma_n.shape[0])
        # Frozen friction: strength lagged on the previous stress, clamped >= 0.
        k = np.maximum(k0 - sigma_n @ (a_phi - a_psi), 0.0)
        comp = list(components)
        n = sigma_n.shape[0]
        cut_a = cut_k = None
        if self.tension_cutoff and self.phi > 0.0:
            # Mean stress bounded by the apex of the true cone: a_phi^T s <= k0.
            cut_a, cut_k = a_phi[comp], k0
        return ConeRows(
            a=np.broadcast_to(a_psi[comp], (n, len(comp))).copy(),
            k=k,
            M=self._norm_rows(dim)[:, comp],
            cutoff_a=cut_a,
            cutoff_k=cut_k,
        )

    def _norm_rows(self, dim: int) -> np.ndarray:
        raise NotImplementedError


class MohrCoulomb(_Frictional):
    """Plane-strain Mohr-Coulomb: ``2R <= 2c cos(phi) - sin(phi)(s_xx + s_yy)``.

    ``R`` is the radius of the in-plane Mohr circle.  Exact in plane strain; 3D
    Mohr-Coulomb is not a second-order cone, use :class:`DruckerPrager` there.

    Parameters
    ----------
    E, nu, rho : float
        Elastic constants (Pa, -, kg/m^3).
    c : float
        Cohesion, Pa, >= 0.
    phi : float
        Friction angle, degrees, in [0, 90).
    psi : float, optional
        Dilation angle, degrees, in [0, phi]; default ``phi`` (associated).
    tension_cutoff : bool
        Add ``s_xx + s_yy <= 2c cot(phi)`` (default False).

    Raises
    ------
    ParameterError
        If a constant is out of its range, ``psi > phi``, or ``c = 0`` with
        ``phi = 0`` (no strength at all); in 3D (use :class:`DruckerPrager`)
        when the model is built.

    Examples
    --------
    >>> mc = MohrCoulomb(1e7, 0.3, c=1e3, phi=30.0)
    >>> rows = mc.cone(2, (0, 1, 3), np.zeros((1, 4)))
    >>> bool(float(rows.k[0]) == 2e3 * np.cos(np.radians(30.0)))
    True
    """

    dims = (2,)

    def _a_k(self, friction_deg: float) -> tuple[np.ndarray, float]:
        f = math.radians(friction_deg)
        return math.sin(f) * np.array([1.0, 1.0, 0.0, 0.0]), 2 * self.c * math.cos(
            math.radians(self.phi)
        )

    def _norm_rows(self, dim: int) -> np.ndarray:
        return np.array([[1.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 2.0]])


class Tresca(MohrCoulomb):
    """Plane-strain Tresca with cohesion ``c`` (Pa): ``R <= c``.

    Identical to von Mises with ``sigma_y = sqrt(3) c`` in plane strain.

    Parameters
    ----------
    E, nu, rho : float
        Elastic constants (Pa, -, kg/m^3; ``rho`` default 0).
    c : float
        Cohesion (undrained shear strength), Pa, > 0; keyword only.

    Raises
    ------
    ParameterError
        If ``c <= 0`` or an elastic constant is out of its range.
    """

    def __init__(self, E: float, nu: float, rho: float = 0.0, *, c: float) -> None:
        super().__init__(E, nu, rho, c=c, phi=0.0)
        if self.c <= 0.0:
            raise ParameterError("c", c, "Tresca cohesion must be > 0")


_DP_MATCHES = ("plane-strain", "compression", "extension")


class DruckerPrager(_Frictional):
    """Drucker-Prager ``sqrt(J2) + alpha I1 <= k`` (2D plane strain and 3D).

    Parameters
    ----------
    E, nu, rho, c, phi, psi : float
        As :class:`MohrCoulomb` (Pa, -, kg/m^3, Pa, degrees, degrees).
    tension_cutoff : bool
        Add ``I1 <= k / alpha`` (default False).
    match : {"plane-strain", "compression", "extension"}
        How ``alpha, k`` are fitted to Mohr-Coulomb: the plane-strain match
        (identical collapse loads to MC in plane strain; the default in 2D), the
        triaxial-compression (outer) or triaxial-extension (inner) cone (default
        "compression" in 3D is *not* implied: pass it explicitly).

    Raises
    ------
    ParameterError
        As :class:`MohrCoulomb`, and for an unknown ``match``.
    """

    def __init__(
        self,
        E: float,
        nu: float,
        rho: float = 0.0,
        *,
        c: float = 0.0,
        phi: float = 0.0,
        psi: float | None = None,
        tension_cutoff: bool = False,
        match: str = "plane-strain",
    ) -> None:
        super().__init__(
            E, nu, rho, c=c, phi=phi, psi=psi, tension_cutoff=tension_cutoff
        )
        if match not in _DP_MATCHES:
            raise ParameterError("match", match, f"one of {_DP_MATCHES}")
        self.match = match

    def needs_zz(self, dim: int) -> bool:  # noqa: D102
        return True

    def _norm_rows(self, dim: int) -> np.ndarray:
        return _dp_rows(dim)

    def alpha_k(self, friction_deg: float) -> tuple[float, float]:
        """Return ``(alpha, k)`` for a friction angle (degrees) and this cohesion."""
        f = math.radians(friction_deg)
        fphi = math.radians(self.phi)
        if self.match == "plane-strain":
            alpha = math.tan(f) / math.sqrt(9 + 12 * math.tan(f) ** 2)
            k = 3 * self.c / math.sqrt(9 + 12 * math.tan(fphi) ** 2)
        else:
            sgn = -1.0 if self.match == "compression" else 1.0
            alpha = 2 * math.sin(f) / (math.sqrt(3) * (3 + sgn * math.sin(f)))
            k = (
                6
                * self.c
                * math.cos(fphi)
                / (math.sqrt(3) * (3 + sgn * math.sin(fphi)))
            )
        return alpha, k

    def _a_k(self, friction_deg: float) -> tuple[np.ndarray, float]:
        alpha, k = self.alpha_k(friction_deg)
        return alpha * np.array([1.0, 1, 1, 0, 0, 0]), k

    def cone(  # noqa: D102
        self,
        dim: int,
        components: tuple[int, ...],
        sigma_n: np.ndarray,
        strength: np.ndarray | None = None,
    ) -> ConeRows:
        sigma_n = np.atleast_2d(sigma_n)
        nfull = full_voigt_size(dim)
        pad = np.zeros((sigma_n.shape[0], 6))
        pad[:, :nfull] = sigma_n
        rows = super().cone(3, tuple(range(6)), pad, strength)
        comp = list(components)
        return ConeRows(
            a=rows.a[:, comp],
            k=rows.k,
            M=_dp_rows(dim)[:, comp],
            cutoff_a=None if rows.cutoff_a is None else rows.cutoff_a[comp],
            cutoff_k=rows.cutoff_k,
        )


def _dp_rows(dim: int) -> np.ndarray:
    """Rows M with ``||M s||^2 = J2`` (engineering-position shear entries)."""
    rows = [
        [0.5, -0.5, 0, 0, 0, 0],
        np.array([1.0, 1.0, -2.0, 0, 0, 0]) / math.sqrt(12.0),
        [0, 0, 0, 1.0, 0, 0],
    ]
    if dim == 3:
        rows += [[0, 0, 0, 0, 1.0, 0], [0, 0, 0, 0, 0, 1.0]]
    return np.array(rows, dtype=float)[:, : full_voigt_size(dim)]


class VonMises(Material):
    """Von Mises ``sqrt(J2) <= sigma_y / sqrt(3)`` (2D plane strain and 3D).

    Parameters
    ----------
    E, nu, rho : float
        Elastic constants.
    sigma_y : float
        Uniaxial yield stress, Pa, > 0.
    """

    plastic = True

    def __init__(self, E: float, nu: float, rho: float = 0.0, *, sigma_y: float):
        super().__init__(E, nu, rho)
        self.sigma_y = _check_number("sigma_y", sigma_y, 0.0, math.inf, "()")

    def needs_zz(self, dim: int) -> bool:  # noqa: D102
        return True

    def cone(  # noqa: D102
        self,
        dim: int,
        components: tuple[int, ...],
        sigma_n: np.ndarray,
        strength: np.ndarray | None = None,
    ) -> ConeRows:
        n = np.atleast_2d(sigma_n).shape[0]
        comp = list(components)
        k = np.full(n, self.sigma_y / math.sqrt(3.0))
        if strength is not None:
            k = k * strength_factors(strength, n)
        return ConeRows(
            a=np.zeros((n, len(comp))),
            k=k,
            M=_dp_rows(dim)[:, comp],
        )


_Frictional.plastic = True
