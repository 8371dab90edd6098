"""Axisymmetric nodal integration: the N-PFEM operators of a body of revolution.

A body of revolution about the ``z`` axis is modelled on its half-section
``r >= 0`` in the ``(r, z)`` plane (mesh coordinates ``x = r``, ``y = z``; gravity
along ``-z``).  Displacements are ``(u_r, u_z)`` and the four stress components
map onto the library's 2D full-Voigt order ``(xx, yy, zz, xy)`` as

    (sigma_rr, sigma_zz, sigma_thetatheta, sigma_rz),

so the "zz" slot of plane strain holds the *hoop* component.  Its strain is no
longer zero but ``eps_thetatheta = u_r / r``.

Weights: everything is integrated over the full ring, with the weight
``2 pi r``.  Cell volumes are in m^3 (they sum to the volume of the body of
revolution) and particle masses ``rho V_i`` are in kg of the full ring; forces
(gravity, contact, reactions) are those on the whole ring.

Smoothing (docs/theory.md, "Axisymmetric N-PFEM"): with ``phi_i`` the P1 hat
function of node ``i``,

    V_i          = int phi_i 2 pi r dA
    eps_bar_i    = (1 / V_i) int phi_i eps(u_h) 2 pi r dA
    eps_bar_tt,i = (2 pi / V_i) int phi_i u_r dA          (no 1/r left)
    G            : sigma^T G^T v = int tau_h : eps(v_h) 2 pi r dA,

``tau_h`` being the P1 interpolant of the nodal stresses.  In the plane
(weight 1 instead of ``2 pi r``) these are exactly the cells of
:func:`skfem_npfem.mesh.smoothing.nodal_integration`.  The integrals are polynomials
of degree 2 on each triangle and are evaluated exactly with scikit-fem's
``ElementTriP1`` basis and a degree-2 quadrature.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import CellBasis, ElementTriP1, Mesh

from ..materials import ConeRows, MohrCoulomb, strength_factors
from .smoothing import FULL_VOIGT, NodalIntegration, check_p1_mesh, connectivity

__all__ = [
    "MASS_BASIS",
    "AxisymmetricIntegration",
    "AxisymmetricMohrCoulomb",
    "axisymmetric_integration",
    "mohr_coulomb_cones",
]

#: How volumes and masses of an axisymmetric model are counted (for summaries).
MASS_BASIS = "full ring (2 pi r weight): volumes in m^3, masses in kg"

#: Index of the hoop component in the 2D full-Voigt order (the "zz" slot).
HOOP = 2

# In-plane strain rows (voigt row, displacement component k, gradient direction
# j): B[row, (node, k)] = dN/dx_j, as in plane strain; the hoop row is separate.
_IN_PLANE = ((0, 0, 0), (1, 1, 1), (3, 0, 1), (3, 1, 0))


@dataclass(frozen=True)
class AxisymmetricIntegration(NodalIntegration):
    """Smoothing-cell operators of an axisymmetric mesh.

    Same interface as :class:`~skfem_npfem.mesh.smoothing.NodalIntegration` (so the
    cone program and the particle update use it unchanged): ``volumes`` are the
    ``2 pi r``-weighted cell volumes, ``G`` has the hoop row in the ``zz`` slot,
    :meth:`strain` returns ``(eps_rr, eps_zz, eps_tt, gamma_rz)`` and
    :meth:`gradient` the smoothed in-plane gradient ``d u_k / d x_j`` with
    ``(x_0, x_1) = (r, z)`` (the spin of the objective rotation lies in the
    ``r-z`` plane; the hoop direction does not rotate).

    Attributes
    ----------
    areas : ndarray (N,)
        Planar cell areas ``int phi_i dA`` of the half-section, m^2.
    radii : ndarray (N,)
        Cell radius ``V_i / (2 pi areas_i)``: the ``phi_i``-weighted mean radius
        (positive on the axis too).
    element_areas : ndarray (ne,)
        Planar element areas of the half-section, m^2 (``element_volumes`` are
        their ``2 pi r``-weighted rings, so the centroid radius is
        ``element_volumes / (2 pi element_areas)``).
    """

    areas: np.ndarray
    radii: np.ndarray
    element_areas: np.ndarray

    @property
    def length_scale(self) -> float:
        """Particle spacing ``sqrt(mean(areas))``, m (of the half-section)."""
        return float(np.mean(self.areas)) ** 0.5


def axisymmetric_integration(
    mesh: Mesh, components: tuple[int, ...] | None = None
) -> AxisymmetricIntegration:
    """Assemble the axisymmetric smoothing cells and internal-force operator.

    Parameters
    ----------
    mesh : skfem.MeshTri1
        Mesh of the half-section, coordinates ``(r, z)`` with ``r >= 0``.  Every
        node must belong to an element.
    components : tuple of int, optional
        Full-Voigt components kept as stress variables; must contain the hoop
        component 2 (default: all four).

    Returns
    -------
    AxisymmetricIntegration

    Raises
    ------
    ValueError
        For a 3D mesh, a node at ``r < 0``, components without the hoop slot, or
        nodes outside every element.

    Examples
    --------
    >>> from skfem import MeshTri
    >>> ni = axisymmetric_integration(MeshTri().refined(2))  # r, z in [0, 1]
    >>> round(float(ni.volumes.sum() / np.pi), 12)  # pi r^2 h with r = h = 1
    1.0
    """
    check_p1_mesh(mesh)
    if mesh.dim() != 2:
        raise ValueError("an axisymmetric mesh is the 2D (r, z) half-section")
    components = tuple(range(4)) if components is None else tuple(components)
    if HOOP not in components:
        raise ValueError(
            "axisymmetric stresses need the hoop component (index 2, the 'zz' "
            f"slot) as a variable; got components {components}"
        )
    t, n = connectivity(mesh)
    r_nodes = mesh.p[0]
    extent = float(np.ptp(mesh.p, axis=1).max())
    if r_nodes.min() < -1e-9 * extent:
        raise ValueError(
            f"axisymmetric mesh has nodes at r < 0 (min r = {r_nodes.min():g}); "
            "keep particles at r >= 0 (a frictionless wall at r = 0)"
        )
    grads, w, hoop, area = _element_integrals(mesh)
    ne = t.shape[1]
    volumes = np.bincount(t.ravel(), weights=w.ravel(), minlength=n)
    areas = np.bincount(t.ravel(), weights=np.tile(area / 3.0, 3), minlength=n)
    if np.any(volumes <= 0.0):
        raise ValueError("mesh has nodes with zero smoothing-cell volume")
    G = _assemble_G(t, grads, w, hoop, components, n)
    averaging = sp.csr_matrix(
        (w.ravel() / volumes[t.ravel()], (t.ravel(), np.tile(np.arange(ne), 3))),
        shape=(n, ne),
    )
    return AxisymmetricIntegration(
        dim=2,
        components=components,
        volumes=volumes,
        G=G,
        averaging=averaging,
        grads=grads,
        t=t,
        element_volumes=w.sum(axis=0),  # 2 pi r-weighted, like ``volumes``
        areas=areas,
        radii=volumes / (2.0 * math.pi * areas),
        element_areas=area,
    )


def _element_integrals(mesh: Mesh):
    """Element P1 gradients and the exact weighted integrals of one triangle.

    Returns
    -------
    grads : (ne, 3, 2)
        ``d phi_a / d x_j`` (constant on a P1 triangle).
    w : (3, ne)
        ``int_e phi_a 2 pi r dA``: the part of cell ``t[a, e]`` in element ``e``.
    hoop : (3, 3, ne)
        ``int_e phi_a phi_c 2 pi dA``: the hoop coupling of stress node
        ``t[a, e]`` and radial displacement of node ``t[c, e]``.
    area : (ne,)
        Element areas.
    """
    # Degree-2 integrands (phi * r, phi * phi): intorder=2 is exact.
    basis = CellBasis(mesh, ElementTriP1(), intorder=2)
    phi = np.stack([np.asarray(basis.basis[a][0]) for a in range(3)])  # (3, ne, nq)
    grads = np.stack([basis.basis[a][0].grad[:, :, 0].T for a in range(3)], axis=1)
    dx = basis.dx  # (ne, nq)
    r = np.asarray(basis.global_coordinates())[0]  # (ne, nq)
    two_pi = 2.0 * math.pi
    w = two_pi * np.einsum("aeq,eq,eq->ae", phi, r, dx)
    hoop = two_pi * np.einsum("aeq,ceq,eq->ace", phi, phi, dx)
    return grads, w, hoop, dx.sum(axis=1)


def _assemble_G(
    t: np.ndarray,
    grads: np.ndarray,
    w: np.ndarray,
    hoop: np.ndarray,
    components: tuple[int, ...],
    n: int,
) -> sp.csc_matrix:
    """``G[(c, k), (a, s)]``: in-plane ``w[a] dphi_c/dx_j``, hoop ``hoop[a, c]``."""
    nfull = len(FULL_VOIGT[2])
    pos = -np.ones(nfull, dtype=int)
    pos[list(components)] = np.arange(len(components))
    ns = len(components)
    a_idx, c_idx = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    a_idx, c_idx = a_idx.ravel(), c_idx.ravel()
    rows, cols, vals = [], [], []
    for s, k, j in _IN_PLANE:  # 4 pattern entries: not a loop over elements
        if pos[s] < 0:
            continue
        rows.append(2 * t[c_idx] + k)
        cols.append(ns * t[a_idx] + pos[s])
        vals.append(w[a_idx] * grads[:, c_idx, j].T)
    # Hoop row: eps_tt = u_r / r, weighted by 2 pi r -> int phi_a phi_c 2 pi u_r.
    rows.append(2 * t[c_idx])
    cols.append(ns * t[a_idx] + pos[HOOP])
    vals.append(hoop[a_idx, c_idx])
    return sp.csc_matrix(
        (
            np.concatenate(vals).ravel(),
            (np.concatenate(rows).ravel(), np.concatenate(cols).ravel()),
        ),
        shape=(2 * n, ns * n),
    )


def mohr_coulomb_cones(
    phi: float, c: float
) -> list[tuple[np.ndarray, float, np.ndarray]]:
    """Axisymmetric Mohr-Coulomb as three second-order cones ``k - a.s >= |M s|``.

    With ``sigma_tt`` principal, the in-plane principal stresses ``p +- R``
    (``p = (s_rr + s_zz)/2``, ``R = |((s_rr - s_zz)/2, s_rz)|``) and
    ``N = (1 + sin phi)/(1 - sin phi)``, Mohr-Coulomb (``max_{i != j} s_i (1 + sin
    phi) - s_j (1 - sin phi) <= 2 c cos phi``, tension positive) is exactly

    * ``R + p sin phi <= c cos phi`` (the plane-strain cone, in-plane pair),
    * ``R + p - s_tt / N <= 2 c / sqrt(N)`` (in-plane major, hoop minor),
    * ``R - p + N s_tt <= 2 c sqrt(N)`` (hoop major, in-plane minor).

    :class:`AxisymmetricMohrCoulomb` returns these three cones per point; the
    program stacks each as its own SOC(3) (docs/theory.md).

    Parameters
    ----------
    phi : float
        Friction angle, degrees.
    c : float
        Cohesion, Pa.

    Returns
    -------
    list of (a (4,), k, M (2, 4))
        In the order ``(rr, zz, tt, rz)``.
    """
    s = math.sin(math.radians(phi))
    cos = math.cos(math.radians(phi))
    n = (1.0 + s) / (1.0 - s)
    M = np.array([[0.5, -0.5, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    return [
        (np.array([0.5 * s, 0.5 * s, 0.0, 0.0]), c * cos, M),
        (np.array([0.5, 0.5, -1.0 / n, 0.0]), 2.0 * c / math.sqrt(n), M),
        (np.array([-0.5, -0.5, n, 0.0]), 2.0 * c * math.sqrt(n), M),
    ]


class AxisymmetricMohrCoulomb(MohrCoulomb):
    """Mohr-Coulomb with the hoop stress as a variable: three SOC(3) per node.

    Exact Mohr-Coulomb whenever the ``zz`` slot is a principal stress: the hoop
    stress in axisymmetry (``Model(axisymmetric=True)``), and equally
    ``sigma_zz`` of plane strain.  The cones are :func:`mohr_coulomb_cones`;
    ``psi < phi`` uses frozen friction cone by cone (each cone is linear in its
    friction coefficient once the coefficient of ``R`` is 1), and the tension
    cut-off bounds the mean stress by the apex, ``I1 / 3 <= c cot(phi)``.

    Parameters
    ----------
    E, nu, rho, c, phi, psi, tension_cutoff
        As :class:`~skfem_npfem.materials.MohrCoulomb`.

    Examples
    --------
    >>> mc = AxisymmetricMohrCoulomb(1e7, 0.3, c=1e3, phi=30.0)
    >>> [round(float(r.k[0]), 3) for r in mc.cone(2, (0, 1, 2, 3), np.zeros((1, 4)))]
    [866.025, 1154.701, 3464.102]
    """

    def needs_zz(self, dim: int) -> bool:  # noqa: D102
        return True

    def cone(  # type: ignore[override]
        self,
        dim: int,
        components: tuple[int, ...],
        sigma_n: np.ndarray,
        strength: np.ndarray | None = None,
    ) -> list[ConeRows]:
        """Three cone rows per node, with the frozen-friction strengths."""
        sigma_n = np.atleast_2d(sigma_n)[:, :4]
        comp = list(components)
        n = sigma_n.shape[0]
        f = 1.0 if strength is None else strength_factors(strength, n)
        out = []
        cones = zip(
            mohr_coulomb_cones(self.phi, self.c),
            mohr_coulomb_cones(self.psi, self.c),
            strict=True,
        )
        for j, ((a_phi, k0, M), (a_psi, _, _)) in enumerate(cones):
            cut_a = cut_k = None
            if j == 0 and self.tension_cutoff and self.phi > 0.0:
                cut_a = np.array([1.0, 1.0, 1.0, 0.0])[comp] / 3.0
                cut_k = f * self.c / math.tan(math.radians(self.phi))
            out.append(
                ConeRows(
                    a=np.broadcast_to(a_psi[comp], (n, len(comp))).copy(),
                    k=np.maximum(f * k0 - sigma_n @ (a_phi - a_psi), 0.0),
                    M=M[:, comp],
                    cutoff_a=cut_a,
                    cutoff_k=cut_k,
                )
            )
        return out
