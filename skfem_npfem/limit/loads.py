"""The gravity load of a limit analysis, with the force of the pore water.

With water, the materials' density is the saturated one and the cones act on
the effective stress; the load that gravity puts on the skeleton is the
weight of the saturated soil plus the force of the pore pressure on it,
:func:`~skfem_npfem.water.water_force` (``Q p - integral p phi n``: for a
hydrostatic field the buoyancy, and the pressure of free water on the
surface).  Both are proportional to ``g``, so a gravity multiplier scales
them together.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError
from ..water import water_force

__all__ = ["gravity_load"]


def gravity_load(
    operator: Any,
    rho: np.ndarray,
    gravity: float,
    *,
    x: np.ndarray | None = None,
    pore_pressure: np.ndarray | None = None,
) -> np.ndarray:
    """Nodal gravity load ``-rho g V`` (last axis), plus the pore water's force.

    Parameters
    ----------
    operator : NodalIntegration or AxisymmetricIntegration
        Strain operator (its cell volumes; with water its ``G`` and elements).
    rho : array_like (N,)
        Density per node (saturated below the water table), kg/m^3.
    gravity : float
        Acceleration of gravity, m/s^2, along ``-`` the last axis.
    x : ndarray (N, d), optional
        Node positions, m (needed with ``pore_pressure``).
    pore_pressure : ndarray (N,), optional
        Nodal pore pressure, Pa (compression positive): its force
        :func:`~skfem_npfem.water.water_force` is added, so that the load is
        the one on the skeleton and the cones carry effective stress.  It must
        be the pore pressure *at* ``gravity`` (a hydrostatic field is ``rho_w
        g`` times a head): the load is then proportional to ``g``.

    Returns
    -------
    ndarray (N, d)
        N.

    Examples
    --------
    >>> from skfem import MeshTri
    >>> from skfem_npfem.mesh.smoothing import nodal_integration
    >>> m = MeshTri().refined(1)
    >>> ni = nodal_integration(m)
    >>> f = gravity_load(ni, np.full(m.p.shape[1], 2.0), 10.0,
    ...                  x=m.p.T, pore_pressure=1e1 * (1.0 - m.p[1]))
    >>> round(float(f[:, 1].sum()), 12)  # weight 20 less buoyancy 10, unit area
    -10.0
    """
    N, d = operator.n_nodes, operator.dim
    rho = np.asarray(rho, float).reshape(-1)
    if rho.shape != (N,):
        raise ParameterError("rho", f"shape {rho.shape}", f"one density per node ({N})")
    load = np.zeros((N, d))
    load[:, -1] = -rho * gravity * np.asarray(operator.volumes, float)
    if pore_pressure is None:
        return load
    if x is None or np.shape(x) != (N, d):
        shape = None if x is None else f"shape {np.shape(x)}"
        raise ParameterError("x", shape, f"node positions ({N}, {d})")
    p = np.asarray(pore_pressure, float).reshape(-1)
    if p.shape != (N,) or not np.all(np.isfinite(p)):
        raise ParameterError("pore_pressure", f"shape {p.shape}", f"finite, ({N},)")
    return load + water_force(operator, x, p)
