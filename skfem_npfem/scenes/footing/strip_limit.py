"""The strip footing's collapse load as one cone program (``analysis=limit``).

With a strength growing with depth (``su_gradient``) the particles carry the
profile's factors and the program scales each point's cohesion by its own;
the metric ``heterogeneity_factor`` is then Davis & Booker's (1973) factor
``F = q_ult / ((2 + pi) s_u0 + k B / 4)`` of a weightless Tresca clay.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from skfem import MeshTri

from ...limit.analysis import limit_analysis
from ...materials import Material
from ...mesh.regions import Region, mesh_regions
from ...mesh.smoothing import nodal_integration
from ...particles import Particles
from ..common import solver_from
from ..limit_mode import limit_metrics
from ..refinement import adapt, strategies
from ..soil_profile import has_profile
from .mesh import soil_particles, unit_weight
from .strip_water import footing_gamma, limit_soil, water_dead_load

__all__ = ["HETEROGENEITY_METRICS", "footing_limit", "heterogeneity_factor"]

#: The metric of a footing on a soil whose strength grows with depth.
HETEROGENEITY_METRICS = {
    "heterogeneity_factor": "Davis & Booker's (1973) F = q_ult / ((2 + pi) c + "
    "su_gradient B / 4) of a weightless tresca clay with su_gradient > 0 "
    "(null otherwise): the factor on the sum of the surface strength's "
    "Prandtl load and the gradient's",
}


def heterogeneity_factor(values: Mapping[str, Any], q: float) -> float | None:
    """Davis & Booker's ``F`` of a pressure ``q`` (None where it does not apply)."""
    if not has_profile(values) or values["layers"] is not None:
        return None
    if values["material"] != "tresca" or values["rho"]:
        return None
    k, B = values["su_gradient"], values["width"]
    return q / ((2.0 + math.pi) * values["c"] + k * B / 4.0)


def footing_limit(
    values: Mapping[str, Any],
    mesh: MeshTri,
    mat: Material,
    particles: Particles,
    foot: np.ndarray,
    ref: float | None,
    phi: float = 0.0,
    report: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """The footing's collapse load as one cone program (``analysis=limit``).

    The footing is rigid: the vertical velocities of its nodes are one unknown
    (and a rough footing's horizontal ones are zero), so the reference load --
    ``c b`` (``gamma b^2`` for c = 0) on the half model -- needs no
    distribution.  The soil's weight is the dead load.  The multiplier is then
    the bearing factor ``q / c`` (``q / (gamma b)``).  With ``refine=strain``
    the program is solved again on lattices refined where its mechanism
    dissipates (:func:`~skfem_npfem.scenes.refinement.adapt`; ``phi`` makes the
    particles of each lattice; the limit metrics count the programs of every
    cycle; ``report`` gets a progress line per cycle).
    """
    history, spent = None, []

    def solve(body: tuple) -> tuple[tuple[Any, Any, float], float, np.ndarray]:
        out = _program(values, mat, *body)
        spent.append(out[0][0])
        return out

    if "strain" in strategies(values):
        run = adapt(
            values,
            (mesh, particles, foot),
            solve,
            lambda body: (body[0].p.T, body[0].t),
            lambda pts: _lattice(values, pts, phi),
            report,
        )
        (res, ni, c), (mesh, particles, foot) = run.result, run.body
        history = run.history
    else:
        res, ni, c = solve((mesh, particles, foot))[0]
    factor = res.multiplier
    q = factor * (c if c > 0 else footing_gamma(values) * values["width"] / 2)
    return {
        "q_ult": q,
        "bearing_factor": factor,
        "bearing_factor_reference": ref,
        "relative_error": None if ref is None else factor / ref - 1.0,
        "n_particles": int(particles.n),
        "heterogeneity_factor": heterogeneity_factor(values, q),
        **limit_metrics(
            res,
            ni.volumes,
            len(spent),
            sum(r.wall_time for r in spent),
            sum(r.iterations for r in spent),
            [r.status for r in spent],
        ),
        "refine_history": history,
    }


def _lattice(
    values: Mapping[str, Any], pts: np.ndarray, phi: float
) -> tuple[MeshTri, Particles, np.ndarray]:
    """The footing's soil on the points ``pts`` (the square block, re-triangulated)."""
    L = values["domain_width"] * values["width"] / 2
    square = [Region("soil", np.array([[0.0, 0.0], [L, 0.0], [L, L], [0.0, L]]))]
    x, t, _ = mesh_regions(pts, square, values["spacing"])
    mesh = MeshTri(np.ascontiguousarray(x.T), np.ascontiguousarray(t))
    particles, foot = soil_particles(values, mesh, phi)
    return mesh, particles, foot


def _program(
    values: Mapping[str, Any],
    mat: Material,
    mesh: MeshTri,
    particles: Particles,
    foot: np.ndarray,
) -> tuple[tuple[Any, Any, float], float, np.ndarray]:
    """One limit program: (result, strain operator, c), the multiplier, the power."""
    b, gamma, g_ref = values["width"] / 2, unit_weight(values), footing_gamma(values)
    mat, c = limit_soil(values, mat, particles.stress)
    ni = nodal_integration(mesh, (0, 1, 2, 3) if mat.needs_zz(2) else (0, 1, 3))
    n = particles.n
    fixed = np.asarray(particles.fixed, bool).copy()
    foot = np.flatnonzero(foot)
    fixed[foot, 1] = False  # the footing's vertical dofs: one tied unknown
    load = np.zeros((n, 2))
    load[foot, 1] = -(c if c > 0 else g_ref * b) * b / foot.size
    dead = np.zeros((n, 2))
    dead[:, 1] = -gamma * ni.volumes
    dead += water_dead_load(values, ni, mesh.p.T)
    res = limit_analysis(
        ni,
        [mat],
        np.zeros(n, int),
        load,
        dead_load=dead,
        fixed=fixed,
        tied=[2 * foot + 1],
        options=solver_from(values),
        strength=particles.strength,
    )
    return (res, ni, c), res.multiplier, res.dissipation
