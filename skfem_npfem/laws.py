"""Published reference values the library is checked against: one home for each.

* :func:`lube2005_runout` -- run-out of 2D (channel) granular column collapses,
  Lube et al. (2005);
* :func:`lube2004_runout` -- run-out of axisymmetric column collapses, Lube et
  al. (2004);
* :func:`lajeunesse2004_runout` -- the same, Lajeunesse et al. (2004);
* :func:`prandtl_nc` -- the exact bearing factor ``N_c`` of a smooth strip
  footing on a weightless Mohr-Coulomb soil (Prandtl 1920, Reissner 1924);
* :func:`teh_houlsby_nc` -- the cone factor of a smooth cone in undrained
  clay against the rigidity index (Teh & Houlsby 1991);
* :func:`davis_booker_factor` -- the factor ``F`` of a strip footing on a clay
  whose strength grows linearly with depth (Davis & Booker 1973, as the
  offshore design code fits it).

References are listed in ``docs/references.md``.
"""

from __future__ import annotations

import math

from .errors import ParameterError

__all__ = [
    "davis_booker_factor",
    "lajeunesse2004_runout",
    "lube2004_runout",
    "lube2005_runout",
    "prandtl_nc",
    "teh_houlsby_nc",
]


def lube2005_runout(aspect: float) -> float:
    """Normalised run-out ``(L_inf - L0)/L0`` of Lube et al. (2005), 2D channel.

    ``1.2 a`` for ``a <= 1.8`` and ``1.9 a^(2/3)`` for ``a >= 2.8``; inside the
    transition band the two laws are joined linearly in log-log coordinates.

    Examples
    --------
    >>> lube2005_runout(1.0), round(lube2005_runout(8.0), 4)
    (1.2, 7.6)
    """
    lo, hi = 1.8, 2.8
    if aspect <= lo:
        return 1.2 * aspect
    if aspect >= hi:
        return 1.9 * aspect ** (2.0 / 3.0)
    w = math.log(aspect / lo) / math.log(hi / lo)
    return math.exp((1 - w) * math.log(1.2 * lo) + w * math.log(1.9 * hi ** (2 / 3)))


def lube2004_runout(aspect: float) -> float:
    """Normalised run-out ``(r_inf - r0)/r0`` of Lube et al. (2004), axisymmetric.

    ``1.24 a`` for ``a <= 1.7`` and ``1.6 a^(1/2)`` above (the two laws meet
    within 1 % at ``a = 1.7``).

    Examples
    --------
    >>> round(lube2004_runout(2.0), 4)
    2.2627
    """
    return 1.24 * aspect if aspect <= 1.7 else 1.6 * math.sqrt(aspect)


def lajeunesse2004_runout(aspect: float) -> float:
    """Normalised run-out ``(r_inf - r0)/r0`` of Lajeunesse et al. (2004), axisymmetric.

    ``a`` for ``a <= 0.74`` and ``2 a^(1/2)`` above, as quoted by Staron &
    Hinch (2005, section 3) beside Lube et al.'s laws (the primary paper was
    not available to check; 0.74 is also where the paper's deposits change from
    truncated cones to cones, and the two branches do not meet there).  At
    ``a = 2`` it gives 2.83, 25 % above :func:`lube2004_runout`: the two
    experimental laws bound the band a model of the seed column is read
    against (docs/seed_column.md).

    Examples
    --------
    >>> round(lajeunesse2004_runout(2.0), 4), lajeunesse2004_runout(0.5)
    (2.8284, 0.5)
    """
    return aspect if aspect <= 0.74 else 2.0 * math.sqrt(aspect)


def prandtl_nc(phi_deg: float) -> float:
    """Exact bearing factor ``N_c`` of a smooth strip footing (``2 + pi`` at phi = 0).

    ``N_c = (N_q - 1) cot(phi)`` with ``N_q = exp(pi tan phi) tan^2(45 + phi/2)``.

    Examples
    --------
    >>> round(prandtl_nc(0.0), 4), round(prandtl_nc(30.0), 2)
    (5.1416, 30.14)
    """
    if phi_deg == 0.0:
        return 2.0 + math.pi
    f = math.radians(phi_deg)
    nq = math.exp(math.pi * math.tan(f)) * math.tan(math.pi / 4 + f / 2) ** 2
    return (nq - 1.0) / math.tan(f)


def teh_houlsby_nc(rigidity_index: float) -> float:
    """Cone factor ``N_c = (q_c - sigma_0)/s_u = 1.25 + 1.84 ln I_r`` of a smooth cone.

    Teh & Houlsby (1991), the simplified fit of their strain-path and
    finite-element results for a 60-degree smooth cone in undrained clay, in
    the rigidity index ``I_r = G/s_u``.

    Raises
    ------
    ParameterError
        For a rigidity index that is not a finite number > 0.

    Examples
    --------
    >>> round(teh_houlsby_nc(100.0), 3)
    9.724
    """
    if not (math.isfinite(rigidity_index) and rigidity_index > 0):
        raise ParameterError(
            "rigidity_index", rigidity_index, "a finite number > 0 (G/s_u)"
        )
    return 1.25 + 1.84 * math.log(rigidity_index)


#: The coefficients ``a, b, c, d`` of the fit ``F = a + b x - sqrt((c + b x)^2
#: + d^2)`` to Davis & Booker's chart, by footing roughness.
_DAVIS_BOOKER_FIT = {
    "smooth": (1.372, 0.07, -0.128, 0.342),
    "rough": (2.56, 0.457, 0.713, 1.38),
}


def davis_booker_factor(kappa: float, interface: str = "smooth") -> float:
    """Davis & Booker's ``F`` of a strip on clay with ``s_u = s_u0 + k z``.

    The collapse pressure of a rigid strip of width ``B`` on a weightless
    Tresca clay whose strength grows linearly with depth is ``q = F ((2 +
    pi) s_u0 + k B / 4)`` (Davis & Booker 1973), ``F`` a function of ``kappa
    = k B / s_u0`` and of the footing's roughness. This is the closed-form fit
    to their chart that API RP 2GEO (2011, annex A) and ISO 19901-4 give for
    ``0 <= kappa <= 25``: ``F = a + b kappa - sqrt((c + b kappa)^2 + d^2)``.
    The fit is within about 1 % of the chart (at ``kappa = 4``, smooth:
    1.278 against the exact 1.270; at 0 it gives 1.007 for 1).

    Parameters
    ----------
    kappa : float
        ``k B / s_u0``, in [0, 25].
    interface : {"smooth", "rough"}
        The footing's base.

    Raises
    ------
    ParameterError
        A ``kappa`` outside the fit's range or an unknown interface.

    Examples
    --------
    >>> round(davis_booker_factor(4.0), 3), round(davis_booker_factor(4.0, "rough"), 3)
    (1.278, 1.496)
    """
    if interface not in _DAVIS_BOOKER_FIT:
        raise ParameterError("interface", interface, "smooth or rough")
    if not (math.isfinite(kappa) and 0.0 <= kappa <= 25.0):
        raise ParameterError("kappa", kappa, "a finite number in [0, 25] (k B / s_u0)")
    a, b, c, d = _DAVIS_BOOKER_FIT[interface]
    return a + b * kappa - math.sqrt((c + b * kappa) ** 2 + d**2)


def prandtl_depth(phi_deg: float) -> float:
    """Depth of Prandtl's mechanism under a smooth strip footing, in half-widths b.

    The mechanism of :func:`prandtl_nc`: an active wedge under the footing
    (apex ``b tan(45 + phi/2)`` deep), log-spiral fans ``r = r0 exp(theta tan
    phi)`` about the footing's edges (``r0 = b / cos(45 + phi/2)``, ``theta``
    from 0 to 90 degrees) and passive wedges.  The deepest point is on a fan,
    at ``r0 exp(theta tan phi) sin(45 + phi/2 + theta)``, maximised over
    ``theta``; it grows like ``exp(pi/2 tan phi)``: 6.0 b at 45 degrees,
    11.6 b at 55, 18.6 b at 60, 91 b at 70.

    Examples
    --------
    >>> round(prandtl_depth(0.0), 3), round(prandtl_depth(45.0), 2)
    (1.414, 6.0)
    """
    f = math.radians(phi_deg)
    a = math.pi / 4 + f / 2
    r0 = 1.0 / math.cos(a)
    # d/dtheta [exp(theta tan f) sin(a + theta)] = 0 at a + theta = 90 + phi,
    # theta = 45 + phi/2: inside the fan for every phi.
    theta = math.pi / 2 + f - a
    return r0 * math.exp(theta * math.tan(f)) * math.sin(a + theta)
