"""Dead loads: a pressure on a surface as forces on its particles.

The loads are handed to ``Model(loads=...)`` and added to the particles'
weight in every N-PFEM step (:meth:`~skfem_npfem.Model.external_force`).
They are dead: computed once, on the particles' starting positions, so they
suit surfaces that stay nearly where they are (a surcharge far from where
the soil flows, say).
"""

from __future__ import annotations

import math

import numpy as np

from .errors import ParameterError

__all__ = ["surface_load"]


def surface_load(
    x: np.ndarray,
    on: np.ndarray,
    pressure: float,
    *,
    axisymmetric: bool = False,
) -> np.ndarray:
    """Dead nodal loads of a uniform pressure on a flat top surface (2D).

    The particles ``on`` lie on one horizontal line (the soil's top, say)
    and take the consistent loads of linear elements between neighbours:
    ``integral N_i p`` over the line, pushing down.  Per unit thickness in
    plane strain (half of each neighbouring segment); full rings in
    axisymmetry (``integral N_i p 2 pi r dr``, the ``x`` coordinate being
    the radius), which is what the nodal integration's internal force of a
    uniform stress ``-p`` gives at those particles.

    Parameters
    ----------
    x : ndarray (N, 2)
        Particle positions, m.
    on : ndarray (N,) bool
        The particles on the loaded surface (at least two).
    pressure : float
        Pressure, Pa (positive pushes into the body, along ``-y``).
    axisymmetric : bool
        Full-ring forces of the ``(r, z)`` half-section.

    Returns
    -------
    ndarray (N, 2)
        Forces, N (zero off the surface); they sum to the pressure times the
        surface's length (plane strain) or annulus area (axisymmetry).

    Raises
    ------
    ParameterError
        If ``x`` is not 2D, ``on`` selects fewer than two particles or they
        are not on one horizontal line, or the pressure is not finite.

    Examples
    --------
    >>> x = np.array([[0.0, 1.0], [1.0, 1.0], [3.0, 1.0], [0.0, 0.0]])
    >>> surface_load(x, x[:, 1] == 1.0, 10.0)[:, 1]
    array([ -5., -15., -10.,   0.])
    """
    x = np.asarray(x, float)
    if x.ndim != 2 or x.shape[1] != 2:
        raise ParameterError("x", x.shape, "positions of shape (N, 2): a 2D surface")
    on = np.asarray(on, bool)
    if on.shape != (x.shape[0],) or on.sum() < 2:
        raise ParameterError(
            "on", int(on.sum()), "a mask of shape (N,) selecting at least 2 particles"
        )
    if not math.isfinite(pressure):
        raise ParameterError("pressure", pressure, "a finite pressure (Pa)")
    y = x[on, 1]
    if np.ptp(y) > 1e-9 * max(1.0, float(np.ptp(x[:, 0]))):
        raise ParameterError(
            "on",
            f"heights {y.min():.6g} to {y.max():.6g} m",
            "particles on one horizontal line",
        )
    idx = np.flatnonzero(on)
    order = np.argsort(x[idx, 0], kind="stable")
    t = x[idx[order], 0]
    length = np.diff(t)
    if axisymmetric:  # int N_i 2 pi r dr of the linear shape functions
        left = math.pi * length * (2 * t[:-1] + t[1:]) / 3
        right = math.pi * length * (t[:-1] + 2 * t[1:]) / 3
    else:
        left = right = 0.5 * length
    share = np.zeros(t.size)
    share[:-1] += left
    share[1:] += right
    loads = np.zeros_like(x)
    loads[idx[order], 1] = -pressure * share
    return loads
