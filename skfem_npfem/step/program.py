"""The data of one step's cone program: inputs, variable layout and blocks.

:class:`ConeInput` is everything one cone step needs; :class:`Program` derives
from it what the row families and objective terms of
:mod:`skfem_npfem.step.families` share (free and prescribed dofs, the generalised
force ``f~``, compliances, yield cones, the variable layout), and
:func:`assemble` stacks their finished blocks into one Clarabel program.

Stress points and nodes
-----------------------
The program never assumes that stresses live at the nodes.  It sees the strain
operator ``data.operator`` only through this interface (:class:`StrainOperator`):

``dim``, ``components``
    Spatial dimension and the full-Voigt indices of the stress components
    carried as variables (``n_s`` of them).
``n_nodes``, ``n_points``
    Displacement nodes ``N`` and stress points ``n_p``.
``volumes`` : (n_p,)
    Integration weight of each stress point (a smoothing-cell area/volume; an
    axisymmetric operator would weight by ``2 pi r`` or work per radian).
``G`` : sparse (d*N, n_p*n_s)
    Internal force ``f_int = G @ sigma`` (node-major dofs, point-major stresses).
``strain(du)`` -> (n_p, n_s), ``gradient(du)`` -> (n_p, d, d)
    Strain and displacement-gradient recovery at the stress points.
``check()``
    Raise :class:`~skfem_npfem.errors.ParameterError` for a degenerate mesh.

Per-point arrays of :class:`ConeInput` (``material``, ``sigma_n``) have ``n_p``
rows; nodal ones (``force``, ``fixed``, ``du_prescribed``, ``mass``, ``v_n``,
``contacts``) have ``N``.  :class:`~skfem_npfem.mesh.smoothing.NodalIntegration`
(N-PFEM: one stress point per node, ``n_p = N``) is one implementation; an
axisymmetric variant adds the hoop row to ``G``/``strain`` and carries
``sigma_thetatheta`` in ``components``; a Gauss-point operator (standard FEM)
has its own ``n_p``.

Variables and blocks
--------------------
``x = [ds (n_p*n_s) | r (n_free, dynamic) | lambda_n (n_c) | lambda_t (n_t)
| p (n_p, mean-stress stabilisation only) | dp_w (n_p, undrained water only)]``
(:class:`Layout`).  A row family returns a :class:`Block` ``A x + s = b, s in
cones`` with the unit of its rows (force or stress, for scaling); an objective
term returns a :class:`Term` ``(P, q)``.  New physics is one more function of
either kind (see :mod:`skfem_npfem.step.families`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Protocol

import clarabel
import numpy as np
import scipy.sparse as sp

from ..boundary import Contacts
from ..materials import ConeRows, Material
from ..water.forces import coupling_matrix

__all__ = [
    "Assembled",
    "Block",
    "ConeInput",
    "Layout",
    "PoreInput",
    "Program",
    "StrainOperator",
    "Term",
    "assemble",
]


class StrainOperator(Protocol):
    """What the cone program needs from a strain operator (see module notes)."""

    dim: int
    components: tuple[int, ...]
    volumes: np.ndarray
    G: sp.spmatrix

    @property
    def n_nodes(self) -> int:  # noqa: D102
        ...

    @property
    def n_points(self) -> int:  # noqa: D102
        ...

    def strain(self, u: np.ndarray) -> np.ndarray:  # noqa: D102
        ...

    def gradient(self, u: np.ndarray) -> np.ndarray:  # noqa: D102
        ...

    def check(self) -> None:  # noqa: D102
        ...


@dataclass
class PoreInput:
    """The pore water of one step (:mod:`skfem_npfem.water`).

    The static pore pressure's force is already part of
    :attr:`ConeInput.force`; what the program needs besides is the excess
    pore pressure and, in undrained steps, its variables.

    Attributes
    ----------
    excess : ndarray (n_p,)
        Excess pore pressure at the start of the step, Pa (compression
        positive); its force ``Q p_ex`` enters equilibrium.
    undrained : bool
        The excess pore-pressure increments are variables of the step
        (undrained and coupled steps): the multipliers of the cells' volume
        constraint, or the pressures of their mass balance.
    projection : scipy.sparse matrix (n_p, n_p) or None
        Upper triangle of the pressure-projection term ``tau / (2G) L`` on the
        increments (None: none).
    static : ndarray (n_p,) or None
        The static pore pressure of the step, Pa (reported, not used by the
        program).
    darcy : scipy.sparse matrix (n_p, n_p) or None
        ``dt H``: the step's Darcy term on the excess pore pressure (coupled
        steps; full symmetric matrix), m^3 / Pa per unit thickness in 2D.
    storage : ndarray (n_p,) or None
        ``V_j n / K_w``: the fluid's storage of each cell (None: none).
    drained : ndarray (n_d,) int or None
        Points on a drained boundary: their excess pore pressure is zero at
        the end of the step (coupled steps).
    diffusion_number : float or None
        ``c_v dt / h^2`` of a coupled step (smallest over its nodes, ``h``
        the mean node spacing): reported in the step record's ``extra``.
    """

    excess: np.ndarray
    undrained: bool = False
    projection: sp.spmatrix | None = None
    static: np.ndarray | None = None
    darcy: sp.spmatrix | None = None
    storage: np.ndarray | None = None
    drained: np.ndarray | None = None
    diffusion_number: float | None = None


@dataclass
class ConeInput:
    """The input of one step's cone program, on the active nodes of one mesh.

    What :func:`~skfem_npfem.solve_step` solves; :func:`~skfem_npfem.advance`
    builds it from the particles (fill it by hand only to study one program).

    Attributes
    ----------
    operator : StrainOperator
        Strain operator (e.g. :class:`~skfem_npfem.mesh.smoothing.NodalIntegration`);
        ``operator.components`` selects the stress variables.
    materials : list of Material
        Materials referenced by ``material``.
    material : ndarray (n_p,) int
        Material index per stress point.
    sigma_n : ndarray (n_p, n_full)
        Stress at the start of the step (full Voigt), Pa.
    force : ndarray (N, d)
        External nodal force over the step (gravity ``m g`` plus tractions), N.
    fixed : ndarray (N, d) bool
        Prescribed degrees of freedom.
    du_prescribed : ndarray (N, d)
        Displacement increment on prescribed dofs (ignored elsewhere), m.
    contacts : Contacts
        Contact candidates (node indices).
    dt : float
        Time step, s (dynamic only).
    mass : ndarray (N,) or None
        Nodal masses, kg (dynamic only).
    v_n : ndarray (N, d) or None
        Velocity at the start of the step, m/s (dynamic only).
    theta1 : float
        Time-integration parameter of the velocity rule (dynamic only).
    theta2 : float
        Time-integration parameter of the displacement rule (dynamic only).
    dynamic : bool
        Include inertia (otherwise quasi-static).
    stress_scale : float or None
        Stress scale ``s*`` for non-dimensionalisation (None: automatic).
    stabilisation : float
        Factor ``beta`` of the element-residual stabilisation of the stresses
        (:mod:`skfem_npfem.step.stabilisation`); 0: none.
    a_n : ndarray (N, d) or None
        Nodal accelerations at the start of the step, m/s^2 (the inertia of the
        stabilisation's residual; None: zero).
    eigenstrain : ndarray (n_p, n_full) or None
        Stress-free strain prescribed over the step (full Voigt), e.g. the
        volume correction of :mod:`skfem_npfem.step.volume`; None: none.
    stabilisation_mode : {"full", "vertical", "sigma_v", "mean"}
        Which stress increments the stabilisation's residual couples
        (:data:`~skfem_npfem.step.stabilisation.STABILISATION_MODES`).
    pore : PoreInput or None
        The pore water (None: a dry step).  With it, ``sigma_n`` and the
        stress variables are effective stresses.
    tied : list of ndarray or None
        Groups of tied free dofs (node-major indices ``d * node + axis``):
        each group's equilibrium rows are summed into one row, so its dofs
        share one displacement (:attr:`~skfem_npfem.Model.tied`).  None: none.
    strength : ndarray (n_p,) or None
        Per-point factor on each material's cohesive strength (``c``,
        ``sigma_y``; :attr:`~skfem_npfem.Particles.strength`).  None: 1.
    stiffness : ndarray (n_p,) or None
        Per-point factor on each material's elastic moduli (the compliance
        is divided by it; :attr:`~skfem_npfem.Particles.stiffness`).  None: 1.
    body_force : ndarray (N, d) or None
        The part of ``force`` that acts in the volume (the weight, ``k_h`` and
        the water's force), N: the stabilisation's residual takes it as a
        body-force density; a traction or point load (``Model.loads``) is no
        body force.  None: all of ``force``.
    """

    operator: StrainOperator
    materials: list[Material]
    material: np.ndarray
    sigma_n: np.ndarray
    force: np.ndarray
    fixed: np.ndarray
    du_prescribed: np.ndarray
    contacts: Contacts
    dt: float = 1.0
    mass: np.ndarray | None = None
    v_n: np.ndarray | None = None
    theta1: float = 1.0
    theta2: float = 1.0
    dynamic: bool = False
    stress_scale: float | None = None
    stabilisation: float = 0.0
    a_n: np.ndarray | None = None
    eigenstrain: np.ndarray | None = None
    stabilisation_mode: str = "full"
    pore: PoreInput | None = None
    tied: list[np.ndarray] | None = None
    strength: np.ndarray | None = None
    stiffness: np.ndarray | None = None
    body_force: np.ndarray | None = None


@dataclass
class Block:
    """Rows ``A x + s = b`` with ``s`` in ``cones`` (one constraint family).

    Attributes
    ----------
    A : scipy.sparse.csc_matrix (m, n_x)
    b : ndarray (m,)
    cones : list of Clarabel cones
        Covering the ``m`` rows in order.
    unit : {"force", "stress"}
        Physical unit of the rows: they are divided by ``F*`` or ``s*``.
    """

    A: sp.csc_matrix
    b: np.ndarray
    cones: list
    unit: str

    @property
    def rows(self) -> int:
        """Number of rows ``m``."""
        return int(self.b.size)


@dataclass
class Term:
    """An objective contribution ``1/2 x^T P x + q^T x`` (P upper, n_x square)."""

    P: sp.coo_matrix | None = None
    q: np.ndarray | None = None


class Layout:
    """Named blocks of the variable vector, in order, each with its unit."""

    def __init__(self) -> None:
        self.slices: dict[str, slice] = {}
        self.units: dict[str, str] = {}
        self.size = 0

    def add(self, name: str, size: int, unit: str) -> slice:
        """Append a block of ``size`` variables; return its slice."""
        sl = slice(self.size, self.size + int(size))
        self.slices[name], self.units[name] = sl, unit
        self.size = sl.stop
        return sl

    def column_scale(self, scale: dict[str, float]) -> np.ndarray:
        """Scale of every variable (``scale[unit]`` of its block)."""
        return np.concatenate(
            [
                np.full(sl.stop - sl.start, scale[self.units[name]])
                for name, sl in self.slices.items()
            ]
        )


class Program:
    """What the row families and objective terms of one step share.

    Attributes
    ----------
    data : ConeInput
    dim, n_nodes, n_points, comp, ns
        Dimension, nodes, stress points, stress components and their number.
    free, pres : ndarray
        Free and prescribed dof indices (node-major); ``ubar`` the prescribed
        increments.
    sig_n : ndarray (n_p, n_s)
        Start-of-step stresses on the variable components.
    mt, ftilde : ndarray (d*N,)
        Modified nodal masses ``m / (theta1 theta2)`` (dynamic) and the
        generalised external force ``f~`` (docs/theory.md, "Time discretisation
        and the min–max principle").
    fric : ndarray
        Contacts with friction (``mu_lambda > 0``).
    layout : Layout
        ``sigma`` (stress), ``r``, ``lambda_n``, ``lambda_t`` (force).
    compliance : ndarray (n_p, n_s, n_s)
    yield_cones : list of (points, ConeRows)
        Yield cones of the plastic materials (one entry per cone: a material
        may return a list of cones per point).  With ``strength_floor > 0``
        the strengths of each cone below that fraction of its largest are
        raised to it (:class:`~skfem_npfem.step.solver.SolverOptions`).
    """

    def __init__(self, data: ConeInput, strength_floor: float = 0.0) -> None:
        op = data.operator
        self.data = data
        self.dim = d = op.dim
        self.n_nodes, self.n_points = op.n_nodes, op.n_points
        self.comp = tuple(op.components)
        self.ns = len(self.comp)
        dofs_fixed = np.asarray(data.fixed, bool).reshape(-1)
        self.free = np.flatnonzero(~dofs_fixed)
        self.pres = np.flatnonzero(dofs_fixed)
        self.ubar = np.asarray(data.du_prescribed, float).reshape(-1)[self.pres]
        self.tie = tie_matrix(self.free, data.tied)
        self.sig_n = np.asarray(data.sigma_n, float)[:, list(self.comp)]
        self.mt = np.zeros(0)
        if data.dynamic:
            m = np.repeat(np.asarray(data.mass, float), d)
            self.mt = m / (data.theta1 * data.theta2)
        self.ftilde = self._generalised_force()
        c = data.contacts
        self.fric = np.flatnonzero(c.mu_lambda > 0.0)
        self.layout = Layout()
        self.layout.add("sigma", self.n_points * self.ns, "stress")
        self.layout.add("r", self.free.size if data.dynamic else 0, "force")
        self.layout.add("lambda_n", c.size, "force")
        self.layout.add("lambda_t", self.fric.size * (d - 1), "force")
        # The mean-stress stabilisation couples one auxiliary scalar per point
        # (skfem_npfem.step.stabilisation); zero-size otherwise.
        mean = data.stabilisation and data.stabilisation_mode == "mean"
        self.layout.add("mean_stress", self.n_points if mean else 0, "stress")
        # Undrained water: one excess pore-pressure increment per point.
        pore = data.pore
        self.Q = None if pore is None else coupling_matrix(op)
        undrained = pore is not None and pore.undrained
        self.layout.add("pore", self.n_points if undrained else 0, "stress")
        self.compliance = np.empty((self.n_points, self.ns, self.ns))
        self.yield_cones: list[tuple[np.ndarray, ConeRows]] = []
        for m_id, mat in enumerate(data.materials):
            points = np.flatnonzero(data.material == m_id)
            if points.size == 0:
                continue
            self.compliance[points] = mat.compliance(d, self.comp)
            if data.stiffness is not None:
                self.compliance[points] /= data.stiffness[points, None, None]
            if mat.plastic:
                # A material may return several cones per point (axisymmetric
                # Mohr-Coulomb: three SOC(3), skfem_npfem.mesh.axisymmetric).
                if data.strength is None:
                    rows = mat.cone(d, self.comp, data.sigma_n[points])
                else:
                    rows = mat.cone(
                        d, self.comp, data.sigma_n[points], data.strength[points]
                    )
                for cone in rows if isinstance(rows, list | tuple) else [rows]:
                    if strength_floor > 0.0 and cone.k.size:
                        k = np.maximum(cone.k, strength_floor * cone.k.max())
                        cone = replace(cone, k=k)
                    self.yield_cones.append((points, cone))

    def _generalised_force(self) -> np.ndarray:
        """``f~``: the external force plus inertia of the theta scheme."""
        data = self.data
        f = np.asarray(data.force, float).reshape(-1)
        if data.dynamic:
            th1 = data.theta1
            f = f / th1 + self.mt * np.asarray(data.v_n, float).reshape(-1) / data.dt
            if th1 != 1.0:
                G = data.operator.G
                f = f - (1 - th1) / th1 * (G @ self.sig_n.reshape(-1))
        return f

    @property
    def nx(self) -> int:
        """Number of variables."""
        return self.layout.size

    def slice(self, name: str) -> slice:
        """Slice of a variable block (``sigma``, ``r``, ``lambda_n``, ...)."""
        return self.layout.slices[name]

    def size(self, name: str) -> int:
        """Number of variables in a block."""
        sl = self.layout.slices[name]
        return sl.stop - sl.start


def tie_matrix(free: np.ndarray, tied: list[np.ndarray] | None) -> sp.csr_matrix | None:
    """Rows summing the equilibrium rows of each tied group (None: no group).

    ``T`` (n_eq, n_free) maps the free dofs' rows to the program's: one row
    per untied free dof and one per group; a dof's displacement is then
    ``-(T^T z)`` of the rows' multipliers ``z``.  Tied dofs that are
    prescribed are left to their prescription.
    """
    if not tied:
        return None
    row = np.arange(free.size)
    position = np.full(int(free.max(initial=-1)) + 1, -1)
    position[free] = row
    for group in tied:
        group = np.asarray(group, int)
        at = position[group[group < position.size]]
        at = at[at >= 0]
        if at.size > 1:
            row[at] = row[at].min()
    _, row = np.unique(row, return_inverse=True)
    ones = np.ones(free.size)
    return sp.csr_matrix(
        (ones, (row, np.arange(free.size))), (row.max() + 1, free.size)
    )


@dataclass
class Assembled:
    """The stacked program ``min 1/2 x^T P x + q^T x``, ``A x + s = b``, cones."""

    P: sp.csc_matrix
    q: np.ndarray
    A: sp.csc_matrix
    b: np.ndarray
    cones: list
    blocks: list[Block]


def assemble(prog: Program, terms: list[Term], blocks: list[Block]) -> Assembled:
    """Sum the objective terms and stack the blocks: zero, nonnegative, then SOC.

    Blocks keep their order within each cone kind; adjacent zero and
    nonnegative cones merge into one.
    """
    nx = prog.nx
    parts = [t.P.tocoo() for t in terms if t.P is not None]
    P = sp.csc_matrix(
        (
            np.concatenate([p.data for p in parts] or [np.zeros(0)]),
            (
                np.concatenate([p.row for p in parts] or [np.zeros(0, int)]),
                np.concatenate([p.col for p in parts] or [np.zeros(0, int)]),
            ),
        ),
        shape=(nx, nx),
    )
    q = np.zeros(nx)
    for t in terms:
        if t.q is not None:
            q += t.q
    blocks = sorted((blk for blk in blocks if blk.rows or blk.cones), key=_rank)
    cones: list = []
    for blk in blocks:
        for cone in blk.cones:
            merge = type(cone) in (clarabel.ZeroConeT, clarabel.NonnegativeConeT)
            if merge and cones and type(cones[-1]) is type(cone):
                cones[-1] = type(cone)(cones[-1].dim + cone.dim)
            else:
                cones.append(cone)
    A = sp.vstack([blk.A for blk in blocks], format="csc")
    b = np.concatenate([blk.b for blk in blocks])
    return Assembled(P, q, A, b, cones, blocks)


def _rank(block: Block) -> int:
    """Stacking rank of a block: zero cones, nonnegative cones, then the rest."""
    if not block.cones:
        return 1
    kinds = {clarabel.ZeroConeT: 0, clarabel.NonnegativeConeT: 1}
    return kinds.get(type(block.cones[0]), 2)
