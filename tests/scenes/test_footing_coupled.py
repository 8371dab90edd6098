"""The strip footing loaded fast, then held: consolidation under a rigid footing.

A weightless saturated soil, elastic in effect (Tresca with ``c`` 50 times
the collapse pressure ``(2 + pi) c`` over the load), under a rigid smooth
footing carrying ``q`` from the first step.  References:

* the first (loading) step is undrained: its settlement is that of the same
  scene with ``drainage=undrained`` (the coupled step differs by the drained
  surface beside the footing, a one-element boundary layer of the excess pore
  pressure), and an undrained step without the pressure projection is, to
  round-off, the elastic step of nu -> 1/2 with the same shear modulus (it
  keeps every cell's volume);
* held long enough, the soil is drained: the final settlement is that of the
  dry scene with the skeleton's nu;
* in between the settlement grows monotonically (Terzaghi's principle under
  a constant load: the effective stress takes over as the excess pore
  pressure drains; no Mandel-Cryer rise of the settlement);
* independently of the library, the elastic settlements of the same rigid
  footing on the same block by scikit-fem's Taylor-Hood P2/P1 (undrained,
  exactly incompressible) and P2 (drained) elements on the once-refined mesh:
  nodal integration converges to them from above (3 % and 2 % at this
  spacing, docs/verification.md).  The coupled first step adds the pressure
  projection's compliance (0.5 %) and the drained boundary layer (1.5 %) to
  the undrained step's 3 %.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from skfem import (
    Basis,
    BilinearForm,
    ElementTriP1,
    ElementTriP2,
    ElementVector,
    MeshTri,
    asm,
    condense,
    solve,
)
from skfem.helpers import ddot, div, sym_grad

from skfem_npfem import ParameterError, get_scene
from skfem_npfem.scenes.footing.mesh import soil_mesh

E, NU, Q, B = 1.0e7, 0.3, 2.0e4, 2.0
SHEAR = E / (2 * (1 + NU))
BASE = {
    "material": "tresca",
    "c": 1.0e6,
    "E": E,
    "nu": NU,
    "load": Q,
    "width": B,
    "spacing": 0.125,
    "domain_width": 5.0,
}


def run(projection: float | None = None, **extra):
    """Run the loaded footing; its metrics and resolved values."""
    scene = get_scene("strip-footing")
    values = scene.resolve({**BASE, **extra})
    srun = scene.build(values)
    if projection is not None:
        srun.simulation.model.water.projection = projection
    srun.simulation.run(**srun.run_kwargs)
    return srun.metrics(srun.simulation), values


def taylor_hood(mesh: MeshTri, nu: float) -> float:
    """The rigid smooth footing's settlement by P2 (nu < 1/2) or P2/P1 (1/2), m.

    Half model: symmetry face and far side on rollers, base fixed; the
    footing's vertical dofs are one unknown (a column of ones in the map from
    the reduced dofs) loaded by ``Q B / 2``.
    """
    ub = Basis(mesh, ElementVector(ElementTriP2()), intorder=4)
    lam = 2 * SHEAR * nu / (1 - 2 * nu) if nu < 0.5 else 0.0

    @BilinearForm
    def elastic(u, v, w):
        return 2 * SHEAR * ddot(sym_grad(u), sym_grad(v)) + lam * div(u) * div(v)

    K = asm(elastic, ub)
    if nu == 0.5:
        pb = Basis(mesh, ElementTriP1(), intorder=4)

        @BilinearForm
        def volume(u, p, w):
            return -p * div(u)

        C = asm(volume, ub, pb)
        K = sp.bmat([[K, C.T], [C, None]], "csr")
    side, top = mesh.p[0].max(), mesh.p[1].max()
    tol = 1e-9 * side
    foot = ub.get_dofs(lambda x: (x[1] > top - tol) & (x[0] < B / 2 + tol)).all("u^2")
    rollers = ub.get_dofs(lambda x: (x[0] < tol) | (x[0] > side - tol)).all("u^1")
    base = ub.get_dofs(lambda x: x[1] < tol).all()
    n = K.shape[0]
    keep = np.setdiff1d(np.arange(n), foot)
    column = np.empty(n, int)
    column[keep] = np.arange(keep.size)
    column[foot] = keep.size
    T = sp.csr_matrix((np.ones(n), (np.arange(n), column)), shape=(n, keep.size + 1))
    f = np.zeros(keep.size + 1)
    f[-1] = -Q * B / 2
    held = np.unique(column[np.concatenate([rollers, base])])
    x = solve(*condense((T.T @ K @ T).tocsr(), f, D=held))
    return -float(x[-1])


@pytest.fixture(scope="module")
def coupled():
    return run(drainage="coupled", k=1.0e-6)


def test_held_footing_settles_from_undrained_to_drained(coupled):
    m, values = coupled
    undrained, _ = run(drainage="undrained")
    drained, _ = run(drainage="dry")
    s = np.array(m["settlement_time"])[:, 1]
    assert m["settlement_immediate"] == s[0]
    assert m["settlement_final"] == s[-1]
    assert m["settlement_immediate"] == pytest.approx(
        undrained["settlement_final"], rel=0.02
    )
    assert m["settlement_final"] == pytest.approx(drained["settlement_final"], rel=0.02)
    assert np.all(np.diff(s) >= -1e-9 * s[-1])
    # The time factors are those of c_v = k M / gamma_w and B.
    M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))
    cv = values["k"] * M / (values["rho_w"] * values["gravity"])
    assert m["consolidation_coefficient"] == pytest.approx(cv, rel=1e-12)
    assert m["time_factor_50"] == pytest.approx(m["time_50"] * cv / B**2, rel=1e-12)
    assert 0 < m["time_factor_50"] < m["time_factor_90"] < values["hold"]


def test_undrained_and_drained_steps_against_taylor_hood(coupled):
    m, values = coupled
    undrained, _ = run(projection=0.0, drainage="undrained")
    incompressible, _ = run(drainage="dry", nu=0.4999999, E=3 * SHEAR)
    assert undrained["settlement_final"] == pytest.approx(
        incompressible["settlement_final"], rel=1e-5
    )
    mesh = soil_mesh(values).refined()
    for settlement, nu in (
        (undrained["settlement_final"], 0.5),
        (m["settlement_final"], NU),
    ):
        error = settlement / taylor_hood(mesh, nu) - 1
        assert 0 < error < 0.04


def test_held_load_refuses_the_limit_analysis():
    scene = get_scene("strip-footing")
    values = scene.resolve({"load": Q, "analysis": "limit"})
    with pytest.raises(ParameterError, match="analysis"):
        scene.build(values)
