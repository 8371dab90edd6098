"""Linear isotropic elasticity: the compliance of a stress point."""

from __future__ import annotations

import numpy as np

__all__ = ["compliance_matrix"]


def compliance_matrix(E: float, nu: float, dim: int, components: tuple[int, ...]):
    """Elastic compliance ``C`` (strain = C stress) on the selected components.

    Parameters
    ----------
    E : float
        Young's modulus, Pa.
    nu : float
        Poisson's ratio.
    dim : int
        2 (plane strain) or 3.
    components : tuple of int
        Selected full-Voigt components.  In 2D, omitting ``zz`` (index 2) gives the
        plane-strain compliance with ``sigma_zz`` eliminated by ``eps_zz = 0``.

    Returns
    -------
    ndarray, shape (n_s, n_s)

    Examples
    --------
    >>> C = compliance_matrix(1.0, 0.25, 2, (0, 1, 3))
    >>> float(C[2, 2])
    2.5
    """
    c3 = np.zeros((6, 6))
    c3[:3, :3] = -nu / E
    c3[range(3), range(3)] = 1.0 / E
    c3[range(3, 6), range(3, 6)] = 2.0 * (1.0 + nu) / E
    if dim == 3:
        full = c3
    else:
        full = c3[np.ix_([0, 1, 2, 3], [0, 1, 2, 3])]
        if 2 not in components:
            f = (1.0 + nu) / E
            full = full.copy()
            full[np.ix_([0, 1], [0, 1])] = f * np.array(
                [[1.0 - nu, -nu], [-nu, 1.0 - nu]]
            )
    return full[np.ix_(components, components)]
