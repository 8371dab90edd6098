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

from .errors import ParameterError

__all__ = ["ClayStrength", "regularised_ductility"]

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

    def __post_init__(self) -> None:
        _number("sensitivity", self.sensitivity, 1.0, True, "intact / remoulded")
        _number("ductility", self.ductility, 0.0, False, "xi_95")
        _number("rate_parameter", self.rate_parameter, 0.0, True, "mu per decade")
        _number("reference_rate", self.reference_rate, 0.0, False, "1/s")

    def softening(self, xi: np.ndarray) -> np.ndarray:
        """``1/S_t + (1 - 1/S_t) exp(-3 xi / xi_95)`` of shear strains ``xi``."""
        rem = 1.0 / self.sensitivity
        xi = np.maximum(np.asarray(xi, float), 0.0)
        return rem + (1.0 - rem) * np.exp(-3.0 * xi / self.ductility)

    def rate_factor(self, rate: np.ndarray) -> np.ndarray:
        """``1 + mu log10(max(g, g_ref) / g_ref)`` of shear-strain rates ``g``."""
        g = np.maximum(np.asarray(rate, float), self.reference_rate)
        return 1.0 + self.rate_parameter * np.log10(g / self.reference_rate)

    def factors(self, eps_p: np.ndarray, rate: np.ndarray | None) -> np.ndarray:
        """The strength factor of particles with ``eps_p`` and shear rate ``rate``."""
        f = self.softening(SHEAR_FROM_EQUIVALENT * np.asarray(eps_p, float))
        if rate is not None and self.rate_parameter > 0.0:
            f = f * self.rate_factor(rate)
        return f


def regularised_ductility(ductility: float, band: float, spacing: float) -> float:
    """The ductility that softens a band of width ``band`` on a lattice ``spacing``.

    A softening shear band localises in about one spacing, so the plastic
    shear strain behind a slip ``delta`` is about ``delta / spacing``: the
    same ``xi_95`` softens after a slip that shrinks with the spacing, and
    the response depends on the lattice.  Holding the slip of 95 % loss at
    ``xi_95 * band`` (the band width of the soil, or of the lattice the law
    was calibrated on) gives ``xi_95 * band / spacing``.

    Examples
    --------
    >>> regularised_ductility(10.0, 0.02, 0.01)
    20.0
    """
    _number("softening_band", band, 0.0, False, "m")
    _number("spacing", spacing, 0.0, False, "m")
    return ductility * band / spacing
