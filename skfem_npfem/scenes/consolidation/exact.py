"""Exact solutions of the ``consolidation`` scene: Terzaghi's and Mandel's.

Terzaghi (1925): a layer of height H, drained at its top, impermeable at its
base, loaded suddenly by q0; with ``T = c_v t / H^2`` its degree of
consolidation is ``U(T) = 1 - sum_m 2/M_m^2 exp(-M_m^2 T)``, ``M_m = pi (2m
+ 1) / 2``.

Mandel (1953), in the form of Abousleiman et al. (1996): a plane-strain
specimen of half-width a between rigid smooth plates carrying ``2 F``
(``F = sigma0 a`` on each half), drained at ``x = +-a``.  With Skempton's B
and the undrained Poisson's ratio ``nu_u``,

    p(x, t) = 2 F B (1 + nu_u) / (3 a) sum_n sin a_n / (a_n - sin a_n cos a_n)
              (cos(a_n x / a) - cos a_n) exp(-a_n^2 c t / a^2),
    tan a_n = (1 - nu) / (nu_u - nu) a_n,
    c = 2 kappa B^2 G (1 - nu) (1 + nu_u)^2 / (9 (1 - nu_u) (nu_u - nu)).

At ``t = 0+`` the sum is 1/2 (the series of the constant), so the pressure is
``p0 = B (1 + nu_u) F / (3 a)``: ``sigma0 / 2`` for incompressible
constituents (B = 1, nu_u = 1/2), which is also the undrained plane-strain
answer ``p = -(s_xx + s_yy + s_zz) / 3`` with ``s_xx = 0``, ``s_yy =
-sigma0`` and ``s_zz = nu_u (s_xx + s_yy)``.  With B = 1, nu_u = 1/2 the
consolidation coefficient is ``c = kappa M``, ``M`` the constrained modulus.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

__all__ = ["mandel_pressure", "mandel_roots", "terzaghi_degree"]


def terzaghi_degree(T: np.ndarray | float, terms: int = 400) -> np.ndarray:
    """Terzaghi's degree of consolidation ``U(T)`` (exact series)."""
    T = np.atleast_1d(np.asarray(T, float))
    mm = np.pi * (2 * np.arange(terms) + 1) / 2
    return 1 - np.sum(2 / mm**2 * np.exp(-np.outer(T, mm**2)), axis=1)


def mandel_roots(nu: float, nu_u: float = 0.5, terms: int = 400) -> np.ndarray:
    """The roots ``a_n`` of ``tan a = (1 - nu) / (nu_u - nu) a``, increasing.

    The ratio is > 1 for ``nu < nu_u``: one root in ``(0, pi/2)``, then one
    in each ``(n pi, n pi + pi/2)``.
    """
    ratio = (1 - nu) / (nu_u - nu)

    def f(a: float) -> float:
        return np.sin(a) - ratio * a * np.cos(a)

    eps = 1e-12
    roots = [brentq(f, eps, np.pi / 2 - eps)]
    roots += [
        brentq(f, n * np.pi + eps, n * np.pi + np.pi / 2 - eps) for n in range(1, terms)
    ]
    return np.array(roots)


def mandel_pressure(
    x: np.ndarray | float,
    tc: np.ndarray | float,
    nu: float,
    nu_u: float = 0.5,
    terms: int = 400,
) -> np.ndarray:
    """Mandel's pore pressure over its initial value, ``p(x, t) / p0``.

    Parameters
    ----------
    x : float or ndarray
        Position over the half-width, ``x / a`` in [0, 1].
    tc : float or ndarray (n_t,)
        Time factor ``c t / a^2`` (> 0).
    nu, nu_u : float
        Drained and undrained Poisson's ratios.

    Returns
    -------
    ndarray (n_t, n_x)
        ``p / p0`` with ``p0 = B (1 + nu_u) F / (3 a)``.
    """
    a = mandel_roots(nu, nu_u, terms)
    x = np.atleast_1d(np.asarray(x, float))
    tc = np.atleast_1d(np.asarray(tc, float))
    weight = np.sin(a) / (a - np.sin(a) * np.cos(a))
    shape = np.cos(np.outer(a, x)) - np.cos(a)[:, None]  # (n, n_x)
    decay = np.exp(-np.outer(tc, a**2))  # (n_t, n)
    return 2 * (decay * weight) @ shape
