"""Extremes matrix, ``strip-footing`` cases: nu, E, phi, c and length scale.

References (docs/verification.md, "The reference cases"): the Prandtl footing
``q/c = 2 + pi``; the N_c footing ``N_c(phi)`` (``bearing_factor_reference``); the
N_gamma footing (Martin 2005: 7.653 smooth and 14.75 rough at 30 deg).  Measured
numbers are at the default mesh (spacing 0.125 m: 576 particles).
"""

from __future__ import annotations

import numpy as np
from skfem import MeshTri

from skfem_npfem.materials import compliance_matrix
from skfem_npfem.mesh.smoothing import nodal_integration

from .framework import C_FOOT, N_GAMMA_30, PRANDTL, Outcome, case, run_built, within


def footing(overrides: dict):
    """Run the footing: (simulation, metrics, pressures per step, iterations)."""
    sim, m, its = run_built("strip-footing", overrides)
    q = [v for _, v in m["load_curve"]]
    return sim, m, q, its


def plateau(q) -> float:
    """Relative change of the last two footing pressures (NaN for one step)."""
    return abs(q[-1] / q[-2] - 1) if len(q) > 1 else float("nan")


for _nu in (0.0, 0.4999):

    @case(
        f"footing-nu-{_nu:g}",
        "nu",
        "strip-footing",
        {"material": "tresca", "nu": _nu, "steps": 6},
        "incompressible limit, no locking: q/c within [0, +1 %] of 2 + pi, plateau "
        "(last two "
        "loads within 0.2 %)",
    )
    def _foot_nu(nu=_nu):
        # Measured +0.36 % (nu = 0), +0.42 % (nu = 0.4999).
        _sim, m, q, its = footing({"nu": nu, "steps": 6})
        err = m["bearing_factor"] / PRANDTL - 1
        return Outcome(
            within(err, 0.0, 1e-2) and plateau(q) <= 2e-3,
            f"q/c = {m['bearing_factor']:.4f} ({err:+.2%})",
            err,
            its,
            plastic=True,
            yielding=True,
        )


_FOOT_E = {  # E -> cohesion (E/c = 1e2, 1e2, 1e6); settlement 100 c/E b
    1.0e3: 10.0,
    1.0e6: C_FOOT,
    1.0e10: C_FOOT,
}
for _E, _c in _FOOT_E.items():

    @case(
        f"footing-E-{_E:.0e}",
        "E",
        "strip-footing",
        {"material": "tresca", "E": _E, "c": _c, "settlement": 100 * _c / _E},
        "soft and stiff extremes, rigid-plastic limit: q/c of 2 + pi within 1 % for "
        "E/c from 1e2 to 1e6 (settlement "
        "100 c b/E), equal to the E = 1e8 run within 1e-6",
    )
    def _foot_E(E=_E, c=_c):
        # Measured: the three runs agree to 1e-10 (q/c = 5.1614, +0.39 %).
        o = {"E": E, "c": c, "settlement": 100 * c / E, "steps": 6}
        _, m, q, its = footing(o)
        _, m0, _, _ = footing({**o, "E": 1e8, "c": C_FOOT, "settlement": 0.01})
        err = m["bearing_factor"] / PRANDTL - 1
        dev = abs(m["bearing_factor"] / m0["bearing_factor"] - 1)
        return Outcome(
            within(err, 0.0, 1e-2) and dev <= 1e-6 and plateau(q) <= 2e-3,
            f"q/c = {m['bearing_factor']:.4f} ({err:+.2%}); vs E/c = 1e4: {dev:.0e}",
            err,
            its,
            plastic=True,
            yielding=True,
        )


@case(
    "footing-rigid-plastic-one-step",
    "E",
    "strip-footing",
    {"material": "tresca", "E": 1e10, "settlement": 0.01, "steps": 1},
    "rigid-plastic limit: E/c = 1e6, the whole settlement (100x the elastic range) in "
    "one step: "
    "the first solve succeeds and q/c is within 1 % of 2 + pi",
)
def _foot_rigid():
    _, m, _, its = footing({"E": 1e10, "settlement": 0.01, "steps": 1})
    err = m["bearing_factor"] / PRANDTL - 1
    return Outcome(
        within(err, 0.0, 1e-2),
        f"q/c = {m['bearing_factor']:.4f} ({err:+.2%})",
        err,
        its,
        plastic=True,
        yielding=True,
    )


# phi -> (extra parameters, lower and upper bound of N / N_c - 1).  Measured at
# spacing 0.125: -0.19 % (10), -3.37 % (30), -8.7 % (50); frictional cases
# approach N_c from below here and converge under refinement (slow cases:
# -1.5 % at 30 deg with spacing 0.0625, -6.9 % at 50 deg with grading 1.2).
# 50 deg: the Prandtl mechanism reaches 36 b from the footing edge, so the
# block is 45 b with a coarser grading (900 particles).
_PHI = {
    0.0: ({}, 0.0, 1e-2),
    10.0: ({"settlement": 0.1, "steps": 4}, -1e-2, 1e-2),
    30.0: ({"settlement": 0.1, "steps": 4}, -5e-2, 0.0),
    50.0: (
        {
            "settlement": 0.5,
            "steps": 5,
            "domain_width": 45.0,
            "grading": 1.3,
            "E": 1e10,
        },
        -0.12,
        0.0,
    ),
}
for _phi, (_extra, _lo, _hi) in _PHI.items():

    @case(
        f"footing-phi-{_phi:g}",
        "phi",
        "strip-footing",
        {"material": "mohr-coulomb", "phi": _phi, **_extra},
        f"N_c footing: weightless Mohr-Coulomb, N = q/c vs N_c(phi) (bearing_factor_"
        f"reference) within [{_lo:+.0%}, {_hi:+.0%}] (measured band), plateau "
        "within 0.2 %",
    )
    def _foot_phi(phi=_phi, extra=_extra, lo=_lo, hi=_hi):
        _, m, q, its = footing({"material": "mohr-coulomb", "phi": phi, **extra})
        ref = m["bearing_factor_reference"]
        err = m["bearing_factor"] / ref - 1
        return Outcome(
            within(err, lo, hi) and plateau(q) <= 2e-3,
            f"N = {m['bearing_factor']:.3f} vs N_c = {ref:.3f} ({err:+.2%})",
            err,
            its,
            plastic=True,
            yielding=True,
        )


@case(
    "footing-phi-30-refined",
    "phi",
    "strip-footing",
    {"material": "mohr-coulomb", "phi": 30, "spacing": 0.0625, "domain_width": 10},
    "N_c footing convergence: N_c(30) error shrinks under refinement, within [-3 %, 0]",
    slow=True,
)
def _foot_phi30_fine():
    # Measured -2.93 % (spacing 0.125) -> -1.52 % (0.0625), domain 10 b.
    o = {"material": "mohr-coulomb", "phi": 30.0, "settlement": 0.1, "steps": 4}
    _, m1, _, _ = footing({**o, "domain_width": 10.0})
    _, m2, _q, its = footing({**o, "domain_width": 10.0, "spacing": 0.0625})
    e1, e2 = (m["bearing_factor"] / m["bearing_factor_reference"] - 1 for m in (m1, m2))
    return Outcome(
        within(e2, -3e-2, 0.0) and abs(e2) < abs(e1),
        f"{e1:+.2%} (h = 0.125) -> {e2:+.2%} (h = 0.0625)",
        e2,
        its,
        plastic=True,
        yielding=True,
    )


@case(
    "footing-phi-50-graded",
    "phi",
    "strip-footing",
    {"material": "mohr-coulomb", "phi": 50, "domain_width": 45, "grading": 1.2},
    "N_c footing convergence: N_c(50) error shrinks with a finer far field, within "
    "[-9 %, 0]",
    slow=True,
)
def _foot_phi50_fine():
    o = {"material": "mohr-coulomb", "phi": 50.0, "settlement": 0.5, "steps": 5}
    o |= {"domain_width": 45.0, "E": 1e10}
    _, m1, _, _ = footing({**o, "grading": 1.3})
    _, m2, _q, its = footing({**o, "grading": 1.2})
    e1, e2 = (m["bearing_factor"] / m["bearing_factor_reference"] - 1 for m in (m1, m2))
    return Outcome(
        within(e2, -9e-2, 0.0) and abs(e2) < abs(e1),
        f"{e1:+.2%} (grading 1.3) -> {e2:+.2%} (grading 1.2)",
        e2,
        its,
        plastic=True,
        yielding=True,
    )


for _foot in ("smooth", "rough"):

    @case(
        f"footing-c-0-Ngamma-{_foot}",
        "c",
        "strip-footing",
        {
            "material": "mohr-coulomb",
            "c": 0,
            "phi": 30,
            "rho": 2e4 / 9.81,
            "interface": _foot,
            "settlement": 0.1,
            "steps": 5,
        },
        "N_gamma footing: heavy cohesionless soil, N_gamma = q/(gamma b) above the "
        "exact "
        "7.653 (smooth) / 14.75 (rough) within the N_gamma gates, +7 % / +5 %",
    )
    def _foot_ngamma(footing_=_foot):
        # Measured 8.139 (+6.4 %, smooth) and 14.874 (+0.8 %, rough).
        o = {"material": "mohr-coulomb", "c": 0.0, "phi": 30.0, "rho": 2e4 / 9.81}
        o |= {"interface": footing_, "settlement": 0.1, "steps": 5}
        _, m, q, its = footing(o)
        ref = N_GAMMA_30[footing_]
        err = m["bearing_factor"] / ref - 1
        hi = 0.07 if footing_ == "smooth" else 0.05
        return Outcome(
            within(err, 0.0, hi) and plateau(q) <= 2e-3,
            f"N_gamma = {m['bearing_factor']:.3f} vs {ref} ({err:+.2%})",
            err,
            its,
            plastic=True,
            yielding=True,
        )


def elastic_footing_pressure(sim, settlement: float, b: float = 1.0) -> float:
    """Footing pressure on the same mesh by a direct NS-FEM displacement solve.

    ``K = G (V^-1 (x) D) G^T``, condensed on the free dofs with the footing
    pushed down by ``settlement``; independent of conic.py.
    """
    p = sim.particles
    mat = sim.model.materials[0]
    comps = sim.model.components
    mesh = MeshTri(p.x.T.copy(), sim.mesh_source.t, sort_t=False)
    ni = nodal_integration(mesh, comps)
    D = np.linalg.inv(compliance_matrix(mat.E, mat.nu, 2, comps))
    Gd = ni.G.toarray()
    K = Gd @ np.kron(np.diag(1.0 / ni.volumes), D) @ Gd.T
    foot = p.v_prescribed[:, 1] < 0
    ubar = np.zeros_like(p.x)
    ubar[foot, 1] = -settlement
    fix = p.fixed.ravel()
    F, P = np.flatnonzero(~fix), np.flatnonzero(fix)
    u = ubar.ravel()
    u[F] = np.linalg.solve(K[np.ix_(F, F)], -K[np.ix_(F, P)] @ u[P])
    R = (K @ u).reshape(-1, 2)
    return float(-R[foot, 1].sum()) / b


@case(
    "footing-c-1e12-elastic",
    "c",
    "strip-footing",
    {
        "material": "tresca",
        "c": 1e12,
        "settlement": 0.003,
        "steps": 3,
        "plateau_tol": 0,
    },
    "rigid-plastic limit, converse: a strength that is never reached gives the "
    "elastic answer: "
    "q proportional to the settlement (1e-9) and equal to a direct NS-FEM "
    "solve (1e-6)",
)
def _foot_elastic():
    # No plateau exists: plateau_tol = 0 runs exactly the 3 steps.
    sim, m, q, its = footing(
        {"c": 1e12, "settlement": 0.003, "steps": 3, "plateau_tol": 0}
    )
    s = [v for v, _ in m["load_curve"]]
    lin = max(abs(q[k] / s[k] / (q[0] / s[0]) - 1) for k in range(len(q)))
    direct = elastic_footing_pressure(sim, s[-1])
    err = abs(q[-1] / direct - 1)
    return Outcome(
        lin <= 1e-9 and err <= 1e-6,
        f"q/s constant to {lin:.0e}; q vs direct solve {err:.1e}",
        err,
        its,
        plastic=True,
    )


for _b in (1.0e-3, 100.0):

    @case(
        f"footing-scale-{_b:g}m",
        "length",
        "strip-footing",
        {"material": "tresca", "width": 2 * _b, "spacing": _b / 8},
        "same dimensionless footing as b = 1 m (settlement/b fixed): q/c equal "
        "to 1e-8 relative",
    )
    def _foot_scale(b=_b):
        o = {"steps": 4}
        _, m, _, its = footing(
            {**o, "width": 2 * b, "spacing": b / 8, "settlement": 0.01 * b}
        )
        _, m0, _, _ = footing(o | {"settlement": 0.01})
        dev = abs(m["bearing_factor"] / m0["bearing_factor"] - 1)
        return Outcome(
            dev <= 1e-8,
            f"q/c = {m['bearing_factor']:.6f}, vs b = 1 m: {dev:.1e}",
            dev,
            its,
            plastic=True,
            yielding=True,
        )
