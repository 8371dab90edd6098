"""Geometry of unit normals shared by the contact rows and the rigid bodies."""

from __future__ import annotations

import numpy as np

__all__ = ["tangents"]


def tangents(normals: np.ndarray) -> np.ndarray:
    """Unit tangents (n, d-1, d) orthogonal to unit normals (n, d).

    In 2D the normal turned by +90 degrees; in 3D the coordinate axis least
    aligned with each normal, made orthogonal to it (Gram-Schmidt), and the
    cross product of the two.

    Examples
    --------
    >>> tangents(np.array([[0.0, 1.0]])).tolist()
    [[[-1.0, 0.0]]]
    """
    d = normals.shape[1]
    if d == 2:
        return np.stack([-normals[:, 1], normals[:, 0]], axis=1)[:, None, :]
    # 3D: pick the coordinate axis least aligned with n, Gram-Schmidt.
    ref = np.eye(3)[np.argmin(np.abs(normals), axis=1)]
    t1 = ref - np.sum(ref * normals, axis=1, keepdims=True) * normals
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    return np.stack([t1, t2], axis=1)
