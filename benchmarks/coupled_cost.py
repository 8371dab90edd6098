#!/usr/bin/env python
"""What a coupled (consolidating) step costs against a dry and a drained one.

One process, every variant built on the same lattice and stepped alternately
(round robin), so that all see the same machine load; per variant the median
over the steps of the step's wall and process CPU time, of its phases
(``assembly``, Clarabel's ``setup`` and ``solve``) and of the IPM iterations,
the program's sizes (``step.solution.sizes``) and a proxy of the KKT
factor: the fill of a SuperLU factorisation (``scipy.sparse.linalg.splu``,
COLAMD column order) of the scaled program's KKT matrix
``[P A^T; A -eps I]`` (Clarabel does not expose its own factor).

Problems, each plane strain and axisymmetric, on a 51 x 27 lattice (1 377
particles, spacing 0.04 m):

* ``elastic``: a linear-elastic column (E = 10 MPa, nu = 0.3, rho = 2000
  kg/m^3), base fixed, rollers on the sides, 20 kPa on top: no cone, zero IPM
  iterations, one factorisation a step;
* ``plastic``: a Mohr-Coulomb block (plane strain; Drucker-Prager in
  axisymmetry: Mohr-Coulomb is plane-strain only), c = 10 kPa, phi = 20 deg,
  psi = 0, weightless, pushed by a rigid smooth footing of a quarter of its
  width (prescribed settlement 2 mm a step): yield cones, IPM iterations.

Variants: ``dry``, ``drained`` (water table at the top), ``undrained`` with
the pressure projection tau = 1 and 0, ``coupled`` tau = 1 and 0 (k such that
c_v dt / h^2 = 1 with dt = 1 s).

Usage (repository root)::

    python benchmarks/coupled_cost.py --steps 9 --before
    python benchmarks/coupled_cost.py --tables

Writes ``benchmarks/results/coupled_cost.json`` (or ``--out``) and the docs
table ``benchmarks/results/coupled-cost.inc``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import _harness as harness
import _tables as docs_tables
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from skfem import MeshTri

import skfem_npfem as npfem
from skfem_npfem.io import write_json
from skfem_npfem.step import conic
from skfem_npfem.water import forces

OUT = Path(__file__).resolve().parent / "results" / "coupled_cost.json"
NX, NY, H = 50, 26, 0.04
E, NU, RHO, RHO_W, G = 1e7, 0.3, 2000.0, 1000.0, 9.81
M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))
DT = 1.0
K = RHO_W * G * H**2 / (M * DT)  # c_v dt / h^2 = 1
VARIANTS = {
    "dry": None,
    "drained": ("drained", 1.0),
    "undrained tau=1": ("undrained", 1.0),
    "undrained tau=0": ("undrained", 0.0),
    "coupled tau=1": ("coupled", 1.0),
    "coupled tau=0": ("coupled", 0.0),
}
#: Variants stepped as the library did before (``--before``): the facet finder
#: below, and qdldl for pore pressures coupled in P (the automatic backend).
BEFORE = {"drained (before)": "drained", "coupled tau=1 (before)": "coupled tau=1"}
PROBLEMS = ("elastic", "plastic")
GEOMETRIES = ("plane strain", "axisymmetric")


def boundary_facets_before(t: np.ndarray):
    """The boundary facets as ``skfem_npfem.water.forces`` found them before.

    A row-wise ``np.unique(axis=0)`` of the sorted facets (it is now one int64
    key per facet); the same facets in the same order, slower.
    """
    nv, ne = t.shape
    local = np.array([[j for j in range(nv) if j != k] for k in range(nv)])
    faces = t[local].transpose(2, 0, 1).reshape(ne * nv, nv - 1)
    key = np.sort(faces, axis=1)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    once = np.flatnonzero(count[inv.reshape(-1)] == 1)
    return faces[once], once // nv, once % nv


def water(variant: str, top: float) -> npfem.Water | None:
    """The pore water of a variant (None: dry); the table at the top."""
    spec = VARIANTS[BEFORE.get(variant, variant)]
    if spec is None:
        return None
    drainage, tau = spec
    kwargs = {"permeability": K} if drainage == "coupled" else {}
    table = npfem.WaterTable(level=top)
    return npfem.Water(drainage, table, rho_w=RHO_W, projection=tau, **kwargs)


def build(problem: str, geometry: str, variant: str):
    """Particles, model and mesh of one case."""
    mesh = MeshTri.init_tensor(
        np.linspace(0, NX * H, NX + 1), np.linspace(0, NY * H, NY + 1)
    )
    x = mesh.p.T
    width, top = x[:, 0].max(), x[:, 1].max()
    axi = geometry == "axisymmetric"
    fixed = np.zeros_like(x, bool)
    fixed[:, 1] = x[:, 1] < 1e-12
    fixed[:, 0] = (x[:, 0] < 1e-12) | (x[:, 0] > width - 1e-12) | fixed[:, 1]
    at_top = x[:, 1] > top - 1e-12
    loads = None
    if problem == "elastic":
        soil = npfem.LinearElastic(E=E, nu=NU, rho=RHO)
        loads = npfem.surface_load(x, at_top, 2e4, axisymmetric=axi)
    else:
        cls = npfem.DruckerPrager if axi else npfem.MohrCoulomb
        soil = cls(E=E, nu=NU, rho=1e-9, c=1e4, phi=20.0, psi=0.0)
        fixed[:, 1] |= at_top & (x[:, 0] < 0.25 * width + 1e-12)
    model = npfem.Model(
        dim=2,
        materials=[soil],
        mode="static",
        gravity=G,
        loads=loads,
        water=water(variant, top),
        update_geometry=False,
        axisymmetric=axi,
    )
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    if problem == "plastic":
        footing = at_top & (x[:, 0] < 0.25 * width + 1e-12)
        p.v_prescribed[footing, 1] = -2e-3 / DT
    return p, model, mesh


class KKTProbe:
    """Wrap Clarabel's call in :mod:`skfem_npfem.step.conic` to keep the program."""

    def __init__(self) -> None:
        self.last: tuple | None = None
        self._inner = conic.solve_clarabel

        def wrapped(P, q, A, b, cones, *args, **kwargs):
            self.last = (P, A)
            return self._inner(P, q, A, b, cones, *args, **kwargs)

        conic.solve_clarabel = wrapped

    def fill(self) -> dict[str, int]:
        """nnz of the KKT matrix and of SuperLU's L + U (COLAMD order)."""
        P, A = self.last
        n, m = P.shape[0], A.shape[0]
        Pf = P + sp.triu(P, 1).T
        kkt = sp.bmat([[Pf, A.T], [A, -1e-8 * sp.identity(m)]], format="csc")
        lu = spla.splu(kkt, permc_spec="COLAMD")
        return {
            "kkt_dim": int(n + m),
            "kkt_nnz": int(kkt.nnz),
            "lu_nnz": int(lu.L.nnz + lu.U.nnz),
        }


def run_case(
    problem: str, geometry: str, steps: int, probe: KKTProbe, before: bool = False
) -> dict:
    """Step every variant of a case alternately; their medians."""
    names = [*VARIANTS, *(BEFORE if before else ())]
    sims = {v: [*build(problem, geometry, v), None] for v in names}
    rows: dict[str, dict[str, list]] = {v: {} for v in names}
    now = forces._boundary_facets, conic.couples_pore_pressures
    for _ in range(steps):
        for v, sim in sims.items():
            p, model, mesh, state = sim
            if v in BEFORE:
                forces._boundary_facets = boundary_facets_before
                conic.couples_pore_pressures = lambda data: False
            t0, c0 = time.perf_counter(), time.process_time()
            p, step = npfem.advance(p, model, DT, mesh, start=state)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            forces._boundary_facets, conic.couples_pore_pressures = now
            sim[0], sim[3] = p, step.state
            r = rows[v]
            t = step.solution.timings
            for key, val in (
                ("step_s", wall),
                ("cpu_s", cpu),
                ("assembly_s", t["assembly"]),
                ("setup_s", t["setup"]),
                ("solve_s", t["solve"]),
                ("iterations", step.solution.iterations),
            ):
                r.setdefault(key, []).append(val)
            if "sizes" not in r:
                r["sizes"] = {**step.solution.sizes, **probe.fill()}
    out = {}
    for v, r in rows.items():
        med = {k: float(np.median(r[k])) for k in r if k != "sizes"}
        out[v] = {**med, "iterations_max": int(max(r["iterations"])), **r["sizes"]}
    for v in names:
        out[v]["vs_drained"] = out[v]["step_s"] / out["drained"]["step_s"]
        out[v]["cpu_vs_drained"] = out[v]["cpu_s"] / out["drained"]["cpu_s"]
        if v in BEFORE:  # against the drained step of before
            ref = out["drained (before)"]
            out[v]["vs_drained"] = out[v]["step_s"] / ref["step_s"]
            out[v]["cpu_vs_drained"] = out[v]["cpu_s"] / ref["cpu_s"]
    return {"problem": problem, "geometry": geometry, "variants": out}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=7)
    ap.add_argument("--problems", default=",".join(PROBLEMS))
    ap.add_argument("--out", default=str(OUT))
    ap.add_argument(
        "--before",
        action="store_true",
        help="also step the drained and coupled (tau = 1) variants as before "
        "(boundary-facet finder, backend choice), in the same run",
    )
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    args = ap.parse_args(argv)
    if args.tables:
        return docs_tables.write(TABLES)
    probe = KKTProbe()
    cases = []
    for problem in args.problems.split(","):
        for geometry in GEOMETRIES:
            cases.append(run_case(problem, geometry, args.steps, probe, args.before))
            for v, r in cases[-1]["variants"].items():
                print(
                    f"{problem:8s} {geometry:13s} {v:16s} {r['step_s']:.4f} s "
                    f"(x{r['vs_drained']:.2f}, cpu x{r['cpu_vs_drained']:.2f}) "
                    f"setup {r['setup_s']:.4f} solve "
                    f"{r['solve_s']:.4f} it {r['iterations']:.0f} "
                    f"n {r['kkt_dim']} LU {r['lu_nnz']} {r['linear_solver']}",
                    flush=True,
                )
    report: dict[str, Any] = {
        "machine": harness.machine_info(),
        "particles": (NX + 1) * (NY + 1),
        "steps": args.steps,
        "k": K,
        "cases": cases,
    }
    write_json(Path(args.out), report)
    return docs_tables.write(TABLES) if Path(args.out) == OUT else 0


TABLES: docs_tables.Tables = {}
docs_table = docs_tables.registry(TABLES)


@docs_table(f"{docs_tables.RESULTS}/coupled_cost.json")
def coupled_cost() -> str:
    """Median step time and KKT size per variant, against the drained step."""
    rows = []
    for c in docs_tables.load(f"{docs_tables.RESULTS}/coupled_cost.json")["cases"]:
        for v, r in c["variants"].items():
            rows.append(
                [
                    f"{c['problem']}, {c['geometry']}",
                    f"{v} ({r['linear_solver']})",
                    docs_tables.sig(r["step_s"]),
                    f"{r['vs_drained']:.2f} / {r['cpu_vs_drained']:.2f}",
                    " / ".join(
                        docs_tables.sig(r[k])
                        for k in ("assembly_s", "setup_s", "solve_s")
                    ),
                    f"{r['iterations']:.0f}",
                    docs_tables.count(r["kkt_dim"]),
                    docs_tables.count(r["lu_nnz"]),
                ]
            )
    return docs_tables.md(
        [
            "problem",
            "variant (backend)",
            "step (s)",
            "/ drained (wall / CPU)",
            "assembly / setup / solve (s)",
            "IPM iterations",
            "KKT size",
            "LU fill (nnz)",
        ],
        rows,
    )


if __name__ == "__main__":
    raise SystemExit(main())
