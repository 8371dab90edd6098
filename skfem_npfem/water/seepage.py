"""Steady seepage: the drained pore pressure of a flow through the soil.

The total head ``h = z + p / (rho_w g)`` (m) of a steady flow through a
rigid, saturated soil solves Darcy's problem

    div(k grad h) = 0    in the soil,
    h = h_b              on the water boundaries (:class:`HeadBoundary`),
    k grad h . n = 0     on every other boundary (impermeable),

with ``k`` the hydraulic conductivity (m/s).  It is solved with scikit-fem's
P1 triangles on the step's mesh (the particles are its nodes), and the pore
pressure is ``p = rho_w g (h - z)``, clamped at ``p >= 0`` where the head is
below the point: there is no suction, and no free-surface iteration for an
unconfined flow (a phreatic surface inside the soil is not searched for; the
head boundaries must describe a confined flow, or the clamp stands in for
the unsaturated zone).  Plane sections only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from skfem import Basis, BilinearForm, ElementTriP1, MeshTri, asm, condense, solve
from skfem.helpers import dot, grad

from ..errors import ParameterError

__all__ = ["HeadBoundary", "Seepage", "SeepageField", "solve_heads"]


@dataclass(frozen=True)
class HeadBoundary:
    """A water boundary of a plane section: a polyline with a total head.

    Parameters
    ----------
    line : array_like (k, 2)
        Polyline ``[[x, z], ...]`` (at least two points), m.
    head : float
        Total head ``z + p / (rho_w g)`` on it, m (the elevation of the free
        water's surface when the boundary is under free water).
    name : str
        What errors and flow reports call it.

    Notes
    -----
    A boundary facet of the mesh lies on the head boundary when both its
    ends and its midpoint are within ``1e-6 D + |f| / 4`` of the polyline
    (``D`` the diagonal of the mesh's bounding box, ``|f|`` the facet's
    length): a facet along the line, or a node drifted by less than a
    quarter of the spacing, is on it; a facet that only touches the line
    with one end (the side of a corner) is not.  The nodes of those facets
    take the head; a node on two head boundaries takes the first one's.

    Examples
    --------
    >>> HeadBoundary([[0.0, 1.0], [2.0, 1.0]], head=3.0, name="reservoir").head
    3.0
    """

    line: np.ndarray
    head: float
    name: str = ""

    def __post_init__(self) -> None:
        label = self.label
        try:
            line = np.array(self.line, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(
                f"{label} line", self.line, "a polyline [[x, z], ...] of numbers"
            ) from None
        if line.ndim != 2 or line.shape[1] != 2 or line.shape[0] < 2:
            raise ParameterError(
                f"{label} line",
                f"shape {line.shape}",
                "at least two points [[x, z], ...]",
            )
        if not np.all(np.isfinite(line)):
            raise ParameterError(
                f"{label} line", "NaN or inf", "finite coordinates (m)"
            )
        h = self.head
        if isinstance(h, bool) or not (isinstance(h, int | float) and math.isfinite(h)):
            raise ParameterError(f"{label} head", h, "a finite total head (m)")
        object.__setattr__(self, "line", line)
        object.__setattr__(self, "head", float(h))

    @property
    def label(self) -> str:
        """``head boundary 'name'`` (or without a name)."""
        return f"head boundary {self.name!r}" if self.name else "head boundary"

    def distance(self, x: np.ndarray) -> np.ndarray:
        """Distance of every point ``x`` (n, 2) to the polyline, m."""
        a, b = self.line[:-1], self.line[1:]  # (s, 2)
        ab = b - a
        length2 = np.maximum(np.einsum("sk,sk->s", ab, ab), np.finfo(float).tiny)
        ap = x[:, None, :] - a[None, :, :]  # (n, s, 2)
        s = np.clip(np.einsum("nsk,sk->ns", ap, ab) / length2, 0.0, 1.0)
        gap = ap - s[:, :, None] * ab[None, :, :]
        return np.sqrt(np.einsum("nsk,nsk->ns", gap, gap).min(axis=1))


def _positive(name: str, v: object) -> float:
    ok = isinstance(v, int | float) and not isinstance(v, bool)
    if not (ok and math.isfinite(v) and v > 0):
        raise ParameterError(name, v, "a finite hydraulic conductivity > 0 (m/s)")
    return float(v)


@dataclass(frozen=True)
class SeepageField:
    """The solution of one steady-seepage problem on a mesh.

    Attributes
    ----------
    head : ndarray (N,)
        Total head at the nodes, m.
    inflow : dict[str, float]
        Flow rate into the soil through each head boundary (by its name, or
        ``"boundary <i>"``), m^3/s per metre of section: the consistent nodal
        flux ``K h`` summed over the boundary's nodes; the values sum to zero
        up to the solver's round-off.
    """

    head: np.ndarray
    inflow: dict[str, float]


@dataclass(frozen=True)
class Seepage:
    """A steady flow through the soil: what a :class:`Water` is told.

    Parameters
    ----------
    heads : list of HeadBoundary
        The water boundaries (at least one); every other boundary is
        impermeable.
    k : float or sequence of float
        Hydraulic conductivity, m/s: one for all the soil, or one per
        material (indexed by the particles' material id).  An element takes
        the mean of its vertices' ``k``.

    Examples
    --------
    >>> s = Seepage([HeadBoundary([[0.0, 1.0], [1.0, 1.0]], head=2.0)], k=1e-5)
    >>> s.conductivity(np.array([0, 0]))
    array([1.e-05, 1.e-05])
    """

    heads: Sequence[HeadBoundary]
    k: float | Sequence[float] = 1.0

    def __post_init__(self) -> None:
        heads = list(self.heads) if isinstance(self.heads, list | tuple) else None
        if not heads:
            raise ParameterError(
                "heads", self.heads, "a list of at least one HeadBoundary"
            )
        for b in heads:
            if not isinstance(b, HeadBoundary):
                raise ParameterError("heads", b, "HeadBoundary objects")
        object.__setattr__(self, "heads", tuple(heads))
        if isinstance(self.k, int | float) and not isinstance(self.k, bool):
            object.__setattr__(self, "k", _positive("k", self.k))
            return
        try:
            ks = list(self.k)
        except TypeError:
            raise ParameterError(
                "k", self.k, "a hydraulic conductivity > 0 (m/s) or one per material"
            ) from None
        if not ks:
            raise ParameterError("k", self.k, "at least one conductivity (m/s)")
        ks = tuple(_positive(f"k[{i}]", v) for i, v in enumerate(ks))
        object.__setattr__(self, "k", ks)

    def conductivity(self, material: np.ndarray) -> np.ndarray:
        """The hydraulic conductivity at nodes of the given material ids, m/s."""
        material = np.asarray(material, int)
        if isinstance(self.k, float):
            return np.full(material.shape, self.k)
        ks = np.asarray(self.k)
        if material.size and material.max() >= ks.size:
            raise ParameterError(
                "k",
                list(self.k),
                f"one conductivity per material ({int(material.max()) + 1} or more)",
            )
        return ks[material]

    def solve(
        self, x: np.ndarray, t: np.ndarray, material: np.ndarray | None = None
    ) -> SeepageField:
        """The heads and flows on the mesh ``(x, t)``.

        Parameters
        ----------
        x : ndarray (N, 2)
            Node positions ``(x, z)``, m.
        t : ndarray (3, ne) int
            Triangles.
        material : ndarray (N,) int, optional
            Material id of every node (default 0).
        """
        x = np.asarray(x, float)
        t = np.asarray(t)
        if x.ndim != 2 or x.shape[1] != 2:
            raise ParameterError(
                "seepage", f"a mesh in {x.shape[-1]}D", "a plane section (2D)"
            )
        material = np.zeros(x.shape[0], int) if material is None else material
        k_e = self.conductivity(material)[t].mean(axis=0)
        mesh = MeshTri(np.ascontiguousarray(x.T), np.ascontiguousarray(t))
        facets = mesh.facets[:, mesh.boundary_facets()]  # (2, nb)
        fixed = np.full(x.shape[0], -1)
        for i, b in reversed(list(enumerate(self.heads))):
            fixed[_facet_nodes(b, x, facets)] = i
        nodes = np.flatnonzero(fixed >= 0)
        heads = np.array([b.head for b in self.heads])
        head = solve_heads(x, t, nodes, heads[fixed[nodes]], k_e, mesh=mesh)
        flux = _stiffness(mesh, k_e) @ head
        names = [b.name or f"boundary {i}" for i, b in enumerate(self.heads)]
        inflow = {n: float(flux[fixed == i].sum()) for i, n in enumerate(names)}
        return SeepageField(head, inflow)

    def pressure(
        self,
        x: np.ndarray,
        t: np.ndarray,
        material: np.ndarray | None,
        rho_w: float,
        gravity: float,
    ) -> np.ndarray:
        """Pore pressure ``rho_w g max(h - z, 0)`` at the nodes of ``(x, t)``, Pa."""
        head = self.solve(x, t, material).head
        x = np.asarray(x, float)
        return rho_w * gravity * np.maximum(head - x[:, -1], 0.0)


def _facet_nodes(b: HeadBoundary, x: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Nodes of the boundary facets that lie on ``b`` (see :class:`HeadBoundary`)."""
    a, c = x[facets[0]], x[facets[1]]
    size = float(np.linalg.norm(x.max(axis=0) - x.min(axis=0)))
    tol = 1e-6 * size + 0.25 * np.linalg.norm(c - a, axis=1)
    near = (
        (b.distance(a) <= tol)
        & (b.distance(c) <= tol)
        & (b.distance(0.5 * (a + c)) <= tol)
    )
    if not np.any(near):
        lo, hi = x.min(axis=0), x.max(axis=0)
        raise ParameterError(
            b.label,
            b.line.tolist(),
            "a polyline along the boundary of the soil (it touches no boundary "
            f"facet of the mesh, which spans x in [{lo[0]:g}, {hi[0]:g}], "
            f"z in [{lo[1]:g}, {hi[1]:g}])",
        )
    return np.unique(facets[:, near])


@BilinearForm
def _darcy(u, v, w):
    return w.k * dot(grad(u), grad(v))


def _stiffness(mesh: MeshTri, k_e: np.ndarray):
    """``K_ij = integral k grad phi_i . grad phi_j`` (P1, element-constant k).

    N x N for all the mesh's points, those of no triangle included (their
    rows are empty; scikit-fem numbers only the vertices up to the last
    one used).
    """
    basis = Basis(mesh, ElementTriP1())
    k_q = np.repeat(np.asarray(k_e, float)[:, None], basis.X.shape[1], axis=1)
    K = asm(_darcy, basis, k=k_q).tocsr()
    n = mesh.p.shape[1]
    if K.shape[0] < n:
        K.resize((n, n))
    return K


def solve_heads(
    x: np.ndarray,
    t: np.ndarray,
    fixed_nodes: np.ndarray,
    fixed_heads: np.ndarray,
    k_per_element: np.ndarray,
    mesh: MeshTri | None = None,
) -> np.ndarray:
    """Solve ``div(k grad h) = 0`` with P1 triangles and the heads of some nodes.

    Parameters
    ----------
    x : ndarray (N, 2)
        Node positions, m.
    t : ndarray (3, ne) int
        Triangles.
    fixed_nodes : ndarray (n_f,) int
        Nodes with a prescribed head (at least one).
    fixed_heads : ndarray (n_f,)
        Their heads, m (finite).
    k_per_element : ndarray (ne,)
        Hydraulic conductivity of every triangle, m/s (> 0).
    mesh : MeshTri, optional
        The scikit-fem mesh of ``(x, t)`` when the caller has it.

    Returns
    -------
    ndarray (N,)
        The total head at every node, m; the other boundaries are
        impermeable (the natural condition).  A node of no triangle (a
        particle outside the step's mesh) takes its own elevation as head:
        no pore pressure.
    """
    fixed_nodes = np.asarray(fixed_nodes, int)
    fixed_heads = np.asarray(fixed_heads, float)
    k_e = np.asarray(k_per_element, float)
    if fixed_nodes.size == 0:
        raise ParameterError(
            "heads", "no node with a head", "at least one head boundary on the mesh"
        )
    if not np.all(np.isfinite(fixed_heads)):
        raise ParameterError("heads", "NaN or inf", "finite heads (m)")
    if not (np.all(np.isfinite(k_e)) and np.all(k_e > 0)):
        raise ParameterError("k", float(k_e.min()), "conductivities > 0 (m/s)")
    x = np.asarray(x, float)
    if mesh is None:
        mesh = MeshTri(np.ascontiguousarray(x.T), np.ascontiguousarray(t))
    K = _stiffness(mesh, k_e)
    head = x[:, -1].copy()
    head[fixed_nodes] = fixed_heads
    orphan = np.ones(head.size, bool)
    orphan[np.asarray(t).ravel()] = False
    orphan[fixed_nodes] = False
    D = np.union1d(fixed_nodes, np.flatnonzero(orphan))
    if D.size == head.size:
        return head
    return solve(*condense(K, x=head, D=D))
