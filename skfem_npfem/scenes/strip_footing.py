"""Scene ``strip-footing``: rigid strip footing under displacement control.

Half model (symmetry at ``x = 0``), plane strain, quasi-static steps.  The soil
block is ``domain*b`` wide and deep with a mesh graded from ``spacing`` under the
footing; base fixed, far side on rollers.  The footing (half-width ``b``) pushes
the surface particles at ``x <= b`` down by ``settlement/steps`` per step; it is
smooth (horizontal motion free) or rough (horizontal motion fixed).  The
footing pressure is the sum of the vertical reactions over ``b``.

References (weightless soil): Prandtl ``q/c = 2 + pi``; Mohr-Coulomb
``N_c = (N_q - 1) cot(phi)``, ``N_q = exp(pi tan phi) tan^2(45 + phi/2)``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from skfem import MeshTri

from ..errors import ParameterError
from ..materials import DruckerPrager, MohrCoulomb, Tresca
from ..model import Model
from ..particles import Particles
from ..pfem import FixedMesh
from ..simulation import Simulation
from ..smoothing import nodal_integration
from .base import Param, Scene, SceneRun
from .common import elastic_params, make_writer, solver_from, solver_params

MATERIALS = ("tresca", "mohr-coulomb", "drucker-prager")

PARAMS = [
    Param("material", "tresca", "-", "yield criterion", str, MATERIALS),
    *elastic_params(1.0e8),
    Param("c", 1.0e4, "Pa", "cohesion", float, lo=0),
    Param(
        "phi",
        0.0,
        "deg",
        "friction angle (ignored by tresca)",
        float,
        lo=0,
        hi=90,
        hi_open=True,
    ),
    Param(
        "psi",
        None,
        "deg",
        "dilation angle (default: phi, associated)",
        float,
        lo=0,
        hi=90,
        hi_open=True,
    ),
    Param(
        "gamma", 0.0, "N/m^3", "unit weight of the soil (0: weightless)", float, lo=0
    ),
    Param(
        "K0",
        None,
        "-",
        "at-rest earth pressure coefficient (default 1-sin phi)",
        float,
        lo=0,
        lo_open=True,
    ),
    Param("footing", "smooth", "-", "footing-soil interface", str, ("smooth", "rough")),
    Param("half_width", 1.0, "m", "footing half-width b", float, lo=0, lo_open=True),
    Param(
        "spacing",
        0.125,
        "m",
        "element size under the footing",
        float,
        lo=0,
        lo_open=True,
    ),
    Param(
        "grading",
        1.15,
        "-",
        "element growth ratio away from the footing",
        float,
        lo=1.0,
        hi=2.0,
    ),
    Param(
        "domain",
        5.0,
        "-",
        "soil block size / b (width and depth)",
        float,
        lo=2.0,
        hi=50.0,
    ),
    Param(
        "settlement", 0.01, "m", "total footing settlement", float, lo=0, lo_open=True
    ),
    Param("steps", 8, "-", "number of (equal) settlement steps", int, lo=1),
    Param(
        "large_deformation",
        False,
        "-",
        "move the particles with the soil (updated Lagrangian); false: "
        "small-strain limit analysis",
        bool,
    ),
    *solver_params(),
]

METRICS = {
    "q_ult": "footing pressure at the last step (= collapse load on the plateau), Pa",
    "bearing_factor": "q_ult / c (c > 0), else q_ult / (gamma b) = N_gamma (B = 2b)",
    "bearing_factor_reference": "Prandtl-Reissner N_c for weightless soil (else null)",
    "relative_error": "bearing_factor / reference - 1 (weightless soil)",
    "load_curve": "list of [settlement (m), pressure (Pa)] per step",
    "n_particles": "number of particles",
}


def graded_coordinates(b: float, h: float, length: float, ratio: float) -> np.ndarray:
    """Coordinates 0..length: uniform ``h`` up to ``1.5 b``, then growing by ratio."""
    n_fine = max(2, round(1.5 * b / h))
    xs = list(np.linspace(0.0, n_fine * h, n_fine + 1))
    step = h
    while xs[-1] < length - 1e-12:
        step *= ratio
        xs.append(min(xs[-1] + step, length))
    if len(xs) > 3 and xs[-1] - xs[-2] < 0.3 * (xs[-2] - xs[-3]):
        xs.pop(-2)
    return np.array(xs)


def n_c(phi_deg: float) -> float:
    """Prandtl-Reissner bearing factor N_c (2 + pi for phi = 0)."""
    if phi_deg == 0.0:
        return 2.0 + math.pi
    f = math.radians(phi_deg)
    nq = math.exp(math.pi * math.tan(f)) * math.tan(math.pi / 4 + f / 2) ** 2
    return (nq - 1.0) / math.tan(f)


def build(
    values: dict[str, Any], out: Path | None = None, progress=None, resume: bool = False
) -> SceneRun:
    """Build the strip-footing simulation."""
    b, h = values["half_width"], values["spacing"]
    if h > b / 2:
        raise ParameterError("spacing", h, f"at most half_width/2 = {b / 2:g} m")
    L = values["domain"] * b
    xs = graded_coordinates(b, h, L, values["grading"])
    ys = L - graded_coordinates(b, h, L, values["grading"])[::-1]
    mesh = MeshTri.init_tensor(xs, ys)
    name = values["material"]
    c, phi = values["c"], values["phi"]
    psi = phi if values["psi"] is None else values["psi"]
    gamma = values["gamma"]
    rho = gamma / 9.81
    E, nu = values["E"], values["nu"]
    if name == "tresca":
        if c <= 0:
            raise ParameterError("c", c, "tresca needs c > 0")
        mat = Tresca(E, nu, rho, c=c)
        phi = 0.0
    elif name == "mohr-coulomb":
        mat = MohrCoulomb(E, nu, rho, c=c, phi=phi, psi=psi)
    else:
        mat = DruckerPrager(E, nu, rho, c=c, phi=phi, psi=psi)
    if c == 0 and gamma == 0:
        raise ParameterError("gamma", gamma, "must be > 0 when c = 0 (no strength)")
    ni = nodal_integration(mesh)
    x = mesh.p.T.copy()
    fixed = np.zeros_like(x, dtype=bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    fixed[np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], L), 0] = True
    foot = np.isclose(x[:, 1], L) & (x[:, 0] <= b * (1 + 1e-9))
    fixed[foot, 1] = True
    if values["footing"] == "rough":
        fixed[foot, 0] = True
    K0 = values["K0"] if values["K0"] is not None else 1.0 - math.sin(math.radians(phi))
    stress = np.zeros((x.shape[0], 4))
    sv = -gamma * (L - x[:, 1])
    stress[:, 1] = sv
    stress[:, 0] = stress[:, 2] = K0 * sv
    particles = Particles.create(
        x, np.maximum(rho, 1e-12) * ni.volumes, stress=stress, fixed=fixed
    )
    n_steps = values["steps"]
    dt = 1.0
    vp = np.zeros_like(x)
    vp[foot, 1] = -values["settlement"] / n_steps / dt
    particles = particles.replace(v_prescribed=vp)
    model = Model(
        dim=2,
        materials=[mat],
        gravity=9.81 if gamma > 0 else 0.0,
        mode="static",
        objective_rotation=values["large_deformation"],
        update_geometry=values["large_deformation"],
        solver=solver_from(values),
    )
    sim = Simulation(
        particles,
        model,
        FixedMesh(mesh.t),
        dt,
        writer=make_writer(out, resume),
        progress=progress,
        meta={"scene": "strip-footing", "parameters": values},
    )

    def record(sim_, p, res) -> bool:
        # Stored on the step record so that it survives checkpoints (--resume).
        res.record.extra["settlement"] = float(-p.u[foot, 1].mean())
        res.record.extra["pressure"] = -float(res.solution.reaction[foot, 1].sum()) / b
        return False

    sim.callbacks.append(record)
    ref = n_c(phi) if gamma == 0 and c > 0 else None

    def metrics(sim_: Simulation) -> dict[str, Any]:
        curve = [
            [r.extra["settlement"], r.extra["pressure"]]
            for r in sim_.records
            if "pressure" in r.extra
        ]
        q = curve[-1][1] if curve else float("nan")
        factor = q / c if c > 0 else q / (gamma * b)
        return {
            "q_ult": q,
            "bearing_factor": factor,
            "bearing_factor_reference": ref,
            "relative_error": None if ref is None else factor / ref - 1.0,
            "load_curve": curve,
            "n_particles": int(x.shape[0]),
        }

    return SceneRun(sim, {"steps": n_steps}, metrics)


SCENE = Scene(
    name="strip-footing",
    description=__doc__.strip().splitlines()[0].split(": ", 1)[1],
    params=PARAMS,
    build=build,
    metrics_doc=METRICS,
)
