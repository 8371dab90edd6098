"""Holes the alpha test would open inside the body, and which of them to seal.

The alpha test drops a simplex whose circumradius exceeds ``alpha h``.  Where
the soil is stretched (under a footing's centre the soil flows outward from
the symmetry axis), a few elongated simplices inside the body can fail it and
open a hole that reaches no free surface: the particles round it then move
into it at little cost and the body's collapse load falls for a step (on the
pushed footing the collapse load of the configuration a dip step starts from
is about 0.63 of its neighbours'; docs/validation/particle_insertion.md).  A failed
region is a real opening only where it reaches the outside of the particle
cloud through particles that are free to part from it; where its only way out
is onto supports (particles whose velocity is prescribed in a direction: a
symmetry axis, a fixed base), or where it has no way out at all, it is
*sealed*: its simplices are kept.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ParameterError
from .simplices import _facet_groups, _open_region

__all__ = ["seal", "sealed_cavities"]


def sealed_cavities(
    simplices: NDArray[np.intp],
    failed: NDArray[np.bool_],
    closed: NDArray[np.bool_],
) -> NDArray[np.bool_]:
    """The ``failed`` simplices whose region opens only onto ``closed`` particles.

    Parameters
    ----------
    simplices : ndarray (m, d + 1) int
        Every simplex of the triangulation of the particle cloud (its convex
        hull).
    failed : ndarray (m,) bool
        The simplices the alpha test drops.
    closed : ndarray (N,) bool
        Particles that cannot part from where they are (a prescribed velocity).

    Returns
    -------
    ndarray (m,) bool
        Failed simplices connected (through failed simplices sharing facets)
        to no hull facet with a particle that is not closed.

    Examples
    --------
    Two triangles of a unit square, one failed; its hull edges both end on
    closed particles: sealed.

    >>> import numpy as np
    >>> t = np.array([[0, 1, 2], [1, 3, 2]])
    >>> failed = np.array([False, True])
    >>> sealed_cavities(t, failed, np.array([False, True, True, True])).tolist()
    [False, True]
    >>> sealed_cavities(t, failed, np.array([True, True, True, False])).tolist()
    [False, False]
    """
    if simplices.shape[0] == 0 or not failed.any():
        return np.zeros(simplices.shape[0], dtype=bool)
    faces, owner, inverse, count = _facet_groups(simplices)
    hull = count[inverse] == 1
    open_face = hull & ~closed[faces].all(axis=1)
    return failed & ~_open_region(inverse, owner, open_face, failed)


def seal(
    simplices: NDArray[np.intp],
    in_alpha: NDArray[np.bool_],
    radius: NDArray[np.float64],
    closed: ArrayLike,
) -> NDArray[np.bool_]:
    """``in_alpha`` with the sealed cavities' simplices added (see the module).

    ``radius`` is the simplices' circumradius (``inf``: degenerate, never
    kept); ``closed`` one flag per particle of the cloud.
    """
    n = int(simplices.max()) + 1 if simplices.size else 0
    flags = np.asarray(closed)
    if flags.dtype != bool or flags.ndim != 1 or flags.size < n:
        raise ParameterError(
            "closed", f"{flags.dtype} of shape {flags.shape}", "one bool per particle"
        )
    failed = ~in_alpha & np.isfinite(radius)
    return in_alpha | sealed_cavities(simplices, failed, flags)
