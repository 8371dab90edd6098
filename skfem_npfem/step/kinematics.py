"""Kinematics of the particle update: stress rotation, strain measures, energies.

:func:`rotate_stress` turns stresses with the smoothed spin of a step (exactly
orthogonal Hughes-Winget rotation), :func:`equivalent_strain` measures plastic
strain increments, and :func:`energies` sums mass, kinetic and potential energy.
Stress vectors are full Voigt (:mod:`skfem_npfem.mesh.smoothing`).
"""

from __future__ import annotations

import numpy as np

from ..particles import Particles

__all__ = [
    "energies",
    "equivalent_strain",
    "rotate_stress",
    "tensor_to_voigt",
    "voigt_to_tensor",
]


def rotate_stress(stress: np.ndarray, grad_du: np.ndarray) -> np.ndarray:
    """Rotate stresses by the exactly orthogonal Hughes-Winget (Cayley) rotation.

    ``R = (I - W/2)^-1 (I + W/2)`` with ``W = skew(grad du)``; ``s <- R s R^T``.
    Orthogonality keeps every invariant, so a stress inside a yield cone stays
    inside (a first-order Jaumann update does not).

    Parameters
    ----------
    stress : ndarray (N, n_full)
        Full Voigt stresses.
    grad_du : ndarray (N, d, d)
        Smoothed gradients of the displacement increment.

    Returns
    -------
    ndarray (N, n_full)
    """
    n, d, _ = grad_du.shape
    if d == 2:
        return _rotate_plane(stress, grad_du)
    W = np.zeros((n, 3, 3))
    W[:, :d, :d] = 0.5 * (grad_du - np.swapaxes(grad_du, 1, 2))
    eye = np.eye(3)
    R = np.linalg.solve(eye - 0.5 * W, eye + 0.5 * W)
    S = voigt_to_tensor(stress)
    return tensor_to_voigt(R @ S @ np.swapaxes(R, 1, 2), stress.shape[1])


def _rotate_plane(stress: np.ndarray, grad_du: np.ndarray) -> np.ndarray:
    """The 2D Cayley rotation in closed form (no 3x3 solves).

    With ``W = [[0, w], [-w, 0]]`` and ``t = w/2``, ``R = [[c, s], [-s, c]]``,
    ``c = (1 - t^2)/(1 + t^2)``, ``s = 2t/(1 + t^2)`` (exactly orthogonal);
    ``zz`` is unchanged.
    """
    t = 0.25 * (grad_du[:, 0, 1] - grad_du[:, 1, 0])
    q = 1.0 + t * t
    c, s = (1.0 - t * t) / q, 2.0 * t / q
    xx, yy, xy = stress[:, 0], stress[:, 1], stress[:, 3]
    out = np.array(stress, dtype=float, copy=True)
    out[:, 0] = c * c * xx + 2 * c * s * xy + s * s * yy
    out[:, 1] = s * s * xx - 2 * c * s * xy + c * c * yy
    out[:, 3] = c * s * (yy - xx) + (c * c - s * s) * xy
    return out


def voigt_to_tensor(s: np.ndarray) -> np.ndarray:
    """Full Voigt (N, 4|6) stresses to (N, 3, 3) tensors."""
    n = s.shape[0]
    T = np.zeros((n, 3, 3))
    T[:, 0, 0], T[:, 1, 1], T[:, 2, 2] = s[:, 0], s[:, 1], s[:, 2]
    T[:, 0, 1] = T[:, 1, 0] = s[:, 3]
    if s.shape[1] == 6:
        T[:, 1, 2] = T[:, 2, 1] = s[:, 4]
        T[:, 2, 0] = T[:, 0, 2] = s[:, 5]
    return T


def tensor_to_voigt(T: np.ndarray, size: int) -> np.ndarray:
    """(N, 3, 3) tensors to full Voigt vectors of length ``size`` (4 or 6)."""
    cols = [T[:, 0, 0], T[:, 1, 1], T[:, 2, 2], T[:, 0, 1]]
    if size == 6:
        cols += [T[:, 1, 2], T[:, 2, 0]]
    return np.stack(cols, axis=1)


def equivalent_strain(deps: np.ndarray) -> np.ndarray:
    """``sqrt(2/3 e:e)`` of full-Voigt strains (engineering shear)."""
    normal = deps[:, :3]
    dev = normal - normal.mean(axis=1, keepdims=True)
    shear = deps[:, 3:]
    return np.sqrt(
        2.0 / 3.0 * (np.sum(dev**2, axis=1) + 0.5 * np.sum(shear**2, axis=1))
    )


def energies(p: Particles, gravity: float) -> dict[str, float]:
    """Total mass (kg), kinetic and gravitational potential energy (J) of particles.

    The potential energy is ``sum m g x_d`` (zero at ``x_d = 0``; gravity
    ``gravity`` (m/s^2) acts along ``-e_d``).

    Examples
    --------
    >>> p = Particles.create([[0.0, 2.0]], [3.0], v=[[1.0, 0.0]])
    >>> e = energies(p, gravity=10.0)
    >>> e["mass"], e["kinetic_energy"], e["potential_energy"]
    (3.0, 1.5, 60.0)
    """
    m = p.mass
    return {
        "mass": float(m.sum()),
        "kinetic_energy": float(0.5 * np.sum(m * np.sum(p.v * p.v, axis=1))),
        "potential_energy": float(gravity * np.sum(m * p.x[:, -1])),
    }
