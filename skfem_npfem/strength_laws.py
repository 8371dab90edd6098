"""Strength that softens with remoulding and rises with the shear-strain rate.

:class:`ClayStrength` is the law of large-deformation studies of spudcans,
T-bars and sensitive-clay slides (Einav & Randolph 2005): the undrained
strength of a particle is its intact (profile) strength times

    [1/S_t + (1 - 1/S_t) exp(-3 xi / xi_95)] * [1 + mu log10(max(g, g_ref) / g_ref)]

with ``xi`` the accumulated plastic shear strain, ``S_t`` the sensitivity
(intact over remoulded strength), ``xi_95`` the ductility (the ``xi`` at
which 95 % of the loss has taken place: ``exp(-3) = 0.05``), ``g`` the plastic
shear-strain rate, ``mu`` the rate parameter (the rise per decade of rate)
and ``g_ref`` the reference rate below which the strength is the reference
one.

In the cone program the factor is a per-particle strength factor
(:attr:`~skfem_npfem.Particles.strength`): each step's cones take the factor
of the particle's ``xi`` and rate at the *start* of the step, i.e. the law is
integrated explicitly, lagged by one step, as the frozen friction of a
non-associated flow is (docs/theory.md).  ``xi = sqrt(3) eps_p`` (the
library's ``eps_p`` is the von Mises equivalent strain ``sqrt(2/3 e:e)``, so
``xi`` is ``gamma_p`` in simple shear) and ``g`` is the step's ``Delta xi /
dt``.  The factor scales the cohesion only: for a Mohr-Coulomb soil it
softens ``c'`` and leaves the friction angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .errors import ParameterError

__all__ = ["ClayStrength", "nonlocal_average"]

#: ``xi = SHEAR_FROM_EQUIVALENT * eps_p``: simple shear's engineering strain.
SHEAR_FROM_EQUIVALENT = math.sqrt(3.0)


def _number(name: str, value: float, lo: float, closed: bool, what: str) -> float:
    """A finite real ``>= lo`` (``> lo`` unless ``closed``) or a named error."""
    ok = isinstance(value, int | float) and not isinstance(value, bool)
    ok = ok and math.isfinite(value) and (value >= lo if closed else value > lo)
    if not ok:
        sign = ">=" if closed else ">"
        raise ParameterError(name, value, f"{what}: a finite number {sign} {lo:g}")
    return float(value)


@dataclass(frozen=True)
class ClayStrength:
    """Strain softening and rate dependence of an undrained strength.

    Parameters
    ----------
    sensitivity : float
        ``S_t >= 1``: intact over fully remoulded strength (1: no softening).
    ductility : float
        ``xi_95 > 0``: accumulated plastic shear strain at 95 % of the loss.
    rate_parameter : float
        ``mu >= 0``: the strength's rise per decade of shear-strain rate
        (0: rate independent; 0.1 is typical of clays).
    reference_rate : float
        ``g_ref > 0``, 1/s: the rate of the reference strength.
    length : float
        ``l >= 0``, m: the softening reads the nonlocal ``xi``, the average
        of the particles' ``xi`` within ``l`` weighted by their masses and
        ``(1 - r^2/l^2)^2`` (:func:`nonlocal_average`); 0: each particle's
        own (local, and dependent on the spacing once a band forms).

    Examples
    --------
    >>> law = ClayStrength(sensitivity=4.0, ductility=10.0)
    >>> [round(float(f), 4) for f in law.softening(np.array([0.0, 10.0, 1e3]))]
    [1.0, 0.2873, 0.25]
    >>> float(ClayStrength(rate_parameter=0.1, reference_rate=1.0).rate_factor(
    ...     np.array([100.0]))[0])
    1.2
    """

    sensitivity: float = 1.0
    ductility: float = 10.0
    rate_parameter: float = 0.0
    reference_rate: float = 1.0
    length: float = 0.0

    def __post_init__(self) -> None:
        _number("sensitivity", self.sensitivity, 1.0, True, "intact / remoulded")
        _number("ductility", self.ductility, 0.0, False, "xi_95")
        _number("rate_parameter", self.rate_parameter, 0.0, True, "mu per decade")
        _number("reference_rate", self.reference_rate, 0.0, False, "1/s")
        _number("length", self.length, 0.0, True, "m")

    def softening(self, xi: np.ndarray) -> np.ndarray:
        """``1/S_t + (1 - 1/S_t) exp(-3 xi / xi_95)`` of shear strains ``xi``."""
        rem = 1.0 / self.sensitivity
        xi = np.maximum(np.asarray(xi, float), 0.0)
        return rem + (1.0 - rem) * np.exp(-3.0 * xi / self.ductility)

    def rate_factor(self, rate: np.ndarray) -> np.ndarray:
        """``1 + mu log10(max(g, g_ref) / g_ref)`` of shear-strain rates ``g``."""
        g = np.maximum(np.asarray(rate, float), self.reference_rate)
        return 1.0 + self.rate_parameter * np.log10(g / self.reference_rate)

    def factors(
        self,
        eps_p: np.ndarray,
        rate: np.ndarray | None,
        x: np.ndarray | None = None,
        weights: np.ndarray | None = None,
    ) -> np.ndarray:
        """The strength factor of particles with ``eps_p`` and shear rate ``rate``.

        With a ``length``, ``x`` (positions) and ``weights`` (masses) give the
        nonlocal ``xi`` the softening reads.
        """
        xi = SHEAR_FROM_EQUIVALENT * np.asarray(eps_p, float)
        if self.length > 0.0:
            if x is None or weights is None:
                raise ParameterError("x", None, "positions and weights with a length")
            xi = nonlocal_average(x, xi, weights, self.length)
        f = self.softening(xi)
        if rate is not None and self.rate_parameter > 0.0:
            f = f * self.rate_factor(rate)
        return f


def nonlocal_average(
    x: np.ndarray, values: np.ndarray, weights: np.ndarray, length: float
) -> np.ndarray:
    """Average of ``values`` within ``length`` of each point, by weight.

    ``sum_j w_j a_ij v_j / sum_j w_j a_ij`` with ``a_ij = (1 - r_ij^2 /
    length^2)^2`` over the points ``j`` closer than ``length`` (the point
    itself included, so every sum is positive).

    Examples
    --------
    >>> x = np.array([[0.0, 0.0], [1.0, 0.0], [5.0, 0.0]])
    >>> nonlocal_average(x, np.array([0.0, 3.0, 9.0]), np.ones(3), 2.0).round(4)
    array([1.08, 1.92, 9.  ])
    """
    _number("length", length, 0.0, False, "m")
    x = np.asarray(x, float)
    tree = cKDTree(x)
    d = tree.sparse_distance_matrix(tree, length, output_type="coo_matrix")
    n = x.shape[0]
    # The pairs include each point with itself (r = 0, a = 1).
    a = sp.csr_matrix(((1.0 - (d.data / length) ** 2) ** 2, (d.row, d.col)), (n, n))
    w = np.asarray(weights, float)
    return (a @ (w * np.asarray(values, float))) / (a @ w)
