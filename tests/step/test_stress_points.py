"""The cone step with more stress points than displacement nodes.

Reference: splitting every stress point of nodal integration into two points
with half its volume (``G`` columns halved, the same strain) describes the same
discrete problem: the program's optimum has equal stresses in both halves,
equal to the unsplit step's stress, and the same displacement increment.  Any
place of the program that sized stress points by nodes (or nodes by stress
points) breaks this.  The scaling length ``h`` is per displacement node and
must not change when points are split.  Case: a dynamic step (theta1 = 0.8) of
a Mohr-Coulomb block with frozen friction and tension cut-off, floor contacts
with friction and prescribed top dofs, solved to tolerance 1e-10; the two
solutions agree to 1e-6 of the largest value (measured 1.3e-7 for ``du``),
plastic strains to 1e-5 (measured 1.6e-6: they are differences of strains).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import MeshTri

from skfem_npfem.boundary import Contacts
from skfem_npfem.materials import MohrCoulomb
from skfem_npfem.mesh.smoothing import NodalIntegration, nodal_integration
from skfem_npfem.step.conic import build_program, cell_size, solve_step
from skfem_npfem.step.program import ConeInput
from skfem_npfem.step.solver import SolverOptions


@dataclass
class SplitPoints:
    """Each stress point of ``base`` as two points of half the volume."""

    base: NodalIntegration

    def __post_init__(self) -> None:
        b, ns = self.base, len(self.base.components)
        self.dim, self.components = b.dim, b.components
        self.volumes = np.repeat(0.5 * b.volumes, 2)
        # Point p -> points 2p, 2p+1; each column block of G taken half.
        cols = np.arange(b.n_points * ns).reshape(-1, ns)
        pick = sp.csr_matrix(
            (
                np.full(2 * cols.size, 0.5),
                (np.repeat(cols, 2, axis=0).ravel(), np.arange(2 * cols.size)),
            ),
            shape=(cols.size, 2 * cols.size),
        )
        self.G = (b.G @ pick).tocsc()

    @property
    def n_nodes(self) -> int:
        return self.base.n_nodes

    @property
    def n_points(self) -> int:
        return 2 * self.base.n_points

    def strain(self, u):
        return np.repeat(self.base.strain(u), 2, axis=0)

    def gradient(self, u):
        return np.repeat(self.base.gradient(u), 2, axis=0)

    def check(self) -> None:
        self.base.check()


def block_step(operator, repeat: int) -> ConeInput:
    m = MeshTri.init_tensor(np.linspace(0, 1, 7), np.linspace(0, 2, 13))
    x, n = m.p.T, m.p.shape[1]
    ni = nodal_integration(m, (0, 1, 3))
    mat = MohrCoulomb(1e7, 0.3, 2000, c=5e3, phi=30, psi=5, tension_cutoff=True)
    fixed = np.zeros((n, 2), bool)
    fixed[x[:, 0] < 1e-9, 0] = True
    fixed[x[:, 1] > 2 - 1e-9, 1] = True
    base = np.flatnonzero(x[:, 1] < 1e-9)
    contacts = Contacts(
        base,
        np.tile([0.0, 1.0], (base.size, 1)),
        np.zeros(base.size),
        np.full(base.size, 50.0),
    )
    sig = np.zeros((n, 4))
    sig[:, 1] = -2000 * 9.81 * (2 - x[:, 1])
    sig[:, 0] = sig[:, 2] = 0.5 * sig[:, 1]
    force = np.zeros((n, 2))
    force[:, 1] = -1.5 * 2000 * 9.81 * ni.volumes
    v = 0.01 * np.random.default_rng(5).normal(size=(n, 2))
    return ConeInput(
        operator=operator(ni),
        materials=[mat],
        material=np.zeros(repeat * n, int),
        sigma_n=np.repeat(sig, repeat, axis=0),
        force=force,
        fixed=fixed,
        du_prescribed=np.where(fixed, -1e-4, 0.0),
        contacts=contacts,
        dt=0.01,
        mass=2000 * ni.volumes,
        v_n=v,
        theta1=0.8,
        theta2=1.0,
        dynamic=True,
    )


def test_split_stress_points_give_the_same_step():
    whole = block_step(lambda ni: ni, 1)
    split = block_step(SplitPoints, 2)
    assert cell_size(build_program(split)[0]) == cell_size(build_program(whole)[0])
    options = SolverOptions(tol=1e-10)
    ref, ours = solve_step(whole, options), solve_step(split, options)
    assert ref.status == ours.status == "Solved"
    assert np.max(ref.deps_p) > 1e-6  # the step is plastic
    for key in ("du", "reaction", "lambda_n", "lambda_t"):
        a, b = getattr(ours, key), getattr(ref, key)
        assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(b)), key
    for key, tol in (("sigma", 1e-6), ("deps_p", 1e-5)):
        a, b = getattr(ours, key), getattr(ref, key)
        for half in (a[0::2], a[1::2]):
            assert np.max(np.abs(half - b)) <= tol * np.max(np.abs(b)), key
