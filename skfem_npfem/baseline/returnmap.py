"""Closed-form return mapping onto the library's yield cones.

The cone step of N-PFEM returns, at every stress point, the closest point of
the yield cone to the elastic trial stress in the *energy* (compliance) norm
``1/2 (s - s_tr)^T C (s - s_tr)``.  For the cones of :mod:`skfem_npfem.materials`
that projection has a closed form in two invariants:

* plane-strain Mohr-Coulomb and Tresca (:class:`~skfem_npfem.materials.MohrCoulomb`):
  the in-plane mean stress ``p = (s_xx + s_yy)/2`` and the radius of the
  in-plane Mohr circle ``r = sqrt(((s_xx - s_yy)/2)^2 + s_xy^2)``; cone
  ``r <= k/2 - sin(psi) p``; energy ``(p'-p)^2/(2 K_ps) + (r'-r)^2/(2 G)`` with
  ``K_ps = lambda + G``.  ``s_zz`` follows elastically,
  ``s_zz = s_zz,n + nu (ds_xx + ds_yy)``, exactly as in the library.
* Drucker-Prager and von Mises: ``p = I1/3`` and ``r = sqrt(J2)``; cone
  ``r <= k - 3 alpha p``; energy with the bulk modulus ``K``.

The strength ``k`` and slope come from the material's own
:meth:`~skfem_npfem.materials.Material.cone` rows evaluated at the stress at
the start of the step, so non-associated flow (``psi < phi``) uses the same
frozen-friction strength ``max(k - (a_phi - a_psi)^T s_n, 0)`` as the cone
program, and the tension cut-off (``a_phi^T s <= k_phi``) is the same plane.
The feasible set in the ``(p, r)`` half-plane is a polygon (cone line, cut-off
line, apex); the projection is the nearest of its candidate points (interior,
each edge, each vertex) that is feasible, chosen point by point without loops.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..materials import Material, MohrCoulomb, compliance_matrix, full_voigt_size

__all__ = ["ReturnResult", "elastic_trial", "project_invariants", "return_map"]


@dataclass(frozen=True)
class ReturnResult:
    """Result of :func:`return_map` (full Voigt arrays, tension positive).

    Attributes
    ----------
    sigma : ndarray (n, n_full)
        Returned stresses.
    deps_p : ndarray (n, n_full)
        Plastic strain increments ``C (s_trial - s)`` (engineering shear).
    plastic : ndarray (n,) bool
        Points whose trial stress was outside the cone.
    """

    sigma: np.ndarray
    deps_p: np.ndarray
    plastic: np.ndarray


@lru_cache(maxsize=64)
def _compliance(E: float, nu: float, dim: int, comps: tuple[int, ...]) -> np.ndarray:
    """:func:`~skfem_npfem.materials.compliance_matrix`, kept per material.

    An explicit method calls the return mapping every substep; the matrices
    depend on the material only.
    """
    C = compliance_matrix(E, nu, dim, comps)
    C.flags.writeable = False
    return C


@lru_cache(maxsize=64)
def _stiffness(E: float, nu: float, dim: int) -> np.ndarray:
    D = np.linalg.inv(_compliance(E, nu, dim, tuple(range(full_voigt_size(dim)))))
    D.flags.writeable = False
    return D


def stiffness(mat: Material, dim: int) -> np.ndarray:
    """Elastic stiffness on the full Voigt components (plane strain in 2D)."""
    return _stiffness(float(mat.E), float(mat.nu), dim)


def elastic_trial(
    materials: list[Material],
    material: np.ndarray,
    dim: int,
    sigma_n: np.ndarray,
    deps: np.ndarray,
) -> np.ndarray:
    """Trial stresses ``s_n + D deps`` (full Voigt; ``deps_zz = 0`` in 2D)."""
    trial = np.array(sigma_n, dtype=float, copy=True)
    for m_id, mat in enumerate(materials):
        sel = material == m_id
        if np.any(sel):
            trial[sel] += deps[sel] @ stiffness(mat, dim).T
    return trial


def project_invariants(p, r, K, G, A, B, p_t):
    """Energy-norm projection of ``(p, r)`` onto ``{r <= A - B p, p <= p_t}``.

    Minimises ``(p' - p)^2 / K + (r' - r)^2 / G`` over the polygon bounded by
    the cone line ``r = A - B p`` (``B >= 0``), the cut-off ``p = p_t`` (``inf``:
    none) and ``r >= 0``.  All arguments are arrays of one shape (or scalars).

    Returns
    -------
    p_new, r_new : ndarray

    Examples
    --------
    >>> p, r = project_invariants(0.0, 3.0, 1.0, 1.0, 1.0, 0.0, np.inf)
    >>> float(p), float(r)
    (0.0, 1.0)
    """
    p, r, K, G, A, B, p_t = np.broadcast_arrays(
        *(np.asarray(v, dtype=float) for v in (p, r, K, G, A, B, p_t))
    )
    tol = 1e-12 * (np.abs(A) + np.abs(B * p) + np.abs(r) + 1e-300)
    inside = (r <= A - B * p + tol) & (p <= p_t)
    lam = (r + B * p - A) / (G + K * B**2)
    cut = np.isfinite(p_t)
    pc = np.where(cut, p_t, np.nan)  # cut-off candidates only where there is one
    apex = np.where(B > 0, A / np.where(B > 0, B, 1.0), np.minimum(p, p_t))
    cands = [
        (p - lam * K * B, r - lam * G),  # cone line
        (pc, r),  # cut-off line
        (pc, A - B * pc),  # corner cone/cut-off
        (apex, 0 * r),  # apex (B > 0) or the axis of a cylinder (B = 0)
    ]
    best_p, best_r = p.copy(), r.copy()
    best = np.full(p.shape, np.inf)
    with np.errstate(invalid="ignore"):
        for cp, cr in cands:  # four candidate families, each vectorised
            ok = np.isfinite(cp) & np.isfinite(cr) & (cr >= -tol) & (cp <= p_t + tol)
            ok &= cr <= A - B * np.where(ok, cp, 0.0) + tol
            dist = np.where(ok, (cp - p) ** 2 / K + (cr - r) ** 2 / G, np.inf)
            take = dist < best
            best = np.where(take, dist, best)
            best_p = np.where(take, cp, best_p)
            best_r = np.where(take, np.maximum(cr, 0.0), best_r)
    return np.where(inside, p, best_p), np.where(inside, r, best_r)


def _cone_invariants(mat: Material, dim: int, sigma_n: np.ndarray):
    """``(A, B, p_t)`` of the cone at stresses ``sigma_n`` and its kind."""
    inplane = isinstance(mat, MohrCoulomb)
    comps = (0, 1, 3) if inplane else tuple(range(full_voigt_size(dim)))
    rows = mat.cone(dim, comps, sigma_n)
    if inplane:  # a^T s = 2 a_xx p, ||M s|| = 2 r
        A, B = 0.5 * rows.k, rows.a[:, 0]
        n_norm = 2.0
    else:  # a^T s = 3 a_xx p, ||M s|| = r
        A, B = rows.k, 3.0 * rows.a[:, 0]
        n_norm = 3.0
    p_t = np.inf
    if rows.cutoff_a is not None and rows.cutoff_a[0] > 0:
        p_t = rows.cutoff_k / (n_norm * rows.cutoff_a[0])
    return inplane, A, B, p_t


def _split(sig: np.ndarray, inplane: bool):
    """Mean stress, deviator (Voigt) and radius of full-Voigt stresses."""
    if inplane:
        p = 0.5 * (sig[:, 0] + sig[:, 1])
        dev = np.zeros_like(sig)
        dev[:, 0] = 0.5 * (sig[:, 0] - sig[:, 1])
        dev[:, 1] = -dev[:, 0]
        dev[:, 3] = sig[:, 3]
        r = np.sqrt(dev[:, 0] ** 2 + dev[:, 3] ** 2)
        return p, dev, r
    p = sig[:, :3].mean(axis=1)
    dev = sig.copy()
    dev[:, :3] -= p[:, None]
    j2 = 0.5 * np.sum(dev[:, :3] ** 2, axis=1) + np.sum(dev[:, 3:] ** 2, axis=1)
    return p, dev, np.sqrt(j2)


def return_map(
    materials: list[Material],
    material: np.ndarray,
    dim: int,
    sigma_trial: np.ndarray,
    sigma_n: np.ndarray,
) -> ReturnResult:
    """Return trial stresses to the yield cones (closest point, energy norm).

    Parameters
    ----------
    materials : list of Material
    material : ndarray (n,) int
        Material index per point.
    dim : int
        2 (plane strain) or 3.
    sigma_trial : ndarray (n, n_full)
        Trial stresses (full Voigt).
    sigma_n : ndarray (n, n_full)
        Stresses at the start of the step: frozen-friction strengths, and the
        elastic ``s_zz`` rule of plane-strain Mohr-Coulomb.

    Returns
    -------
    ReturnResult
    """
    sigma = np.array(sigma_trial, dtype=float, copy=True)
    deps_p = np.zeros_like(sigma)
    plastic = np.zeros(sigma.shape[0], bool)
    for m_id, mat in enumerate(materials):
        idx = np.flatnonzero(material == m_id)
        if idx.size == 0 or not mat.plastic:
            continue
        inplane, A, B, p_t = _cone_invariants(mat, dim, sigma_n[idx])
        p, dev, r = _split(sigma_trial[idx], inplane)
        A, B, p_t = (np.broadcast_to(v, p.shape) for v in (A, B, p_t))
        # Points inside their cone keep the trial stress (the test of
        # project_invariants); only the others are projected.
        tol = 1e-12 * (np.abs(A) + np.abs(B * p) + np.abs(r) + 1e-300)
        out = ~((r <= A - B * p + tol) & (p <= p_t))
        if not np.any(out):
            continue
        idx, p, dev, r = idx[out], p[out], dev[out], r[out]
        new, moved = _returned(
            mat, dim, inplane, p, dev, r, A[out], B[out], p_t[out], sigma_n[idx]
        )
        tr = sigma_trial[idx]
        comps = (0, 1, 3) if inplane else tuple(range(sigma.shape[1]))
        C = _compliance(float(mat.E), float(mat.nu), dim, tuple(comps))
        d = (tr - new)[:, list(comps)] @ C.T
        deps_p[np.ix_(idx, list(comps))] = np.where(moved[:, None], d, 0.0)
        sigma[idx] = np.where(moved[:, None], new, tr)
        plastic[idx] = moved
    return ReturnResult(sigma, deps_p, plastic)


def _returned(mat, dim, inplane, p, dev, r, A, B, p_t, sigma_n):
    """Projected full-Voigt stresses of trial points and whether they moved."""
    G = mat.E / (2.0 * (1.0 + mat.nu))
    lam = mat.E * mat.nu / ((1.0 + mat.nu) * (1.0 - 2.0 * mat.nu))
    K = lam + G if inplane else lam + 2.0 * G / 3.0
    p2, r2 = project_invariants(p, r, K, G, A, B, p_t)
    scale = np.divide(r2, r, out=np.zeros_like(r), where=r > 0)
    new = dev * scale[:, None]
    if inplane:
        new[:, 0] += p2
        new[:, 1] += p2
        new[:, 2] = sigma_n[:, 2] + mat.nu * (
            new[:, 0] + new[:, 1] - sigma_n[:, 0] - sigma_n[:, 1]
        )
    else:
        new[:, :3] += p2[:, None]
    return new, (p2 != p) | (r2 != r)
