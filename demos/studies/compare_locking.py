#!/usr/bin/env python
"""Volumetric locking: Cook's membrane in plane strain, N-PFEM vs FEM P1 vs FEM P2.

Cook's membrane (docs/verification.md, "The reference cases"): the trapezoid
(0,0), (48,44), (48,60), (0,44), clamped at x = 0, with a uniform vertical shear
of total force F = 100 on the edge x = 48; plane strain, E = 250, nu = 0.3,
0.49, 0.4999 (the near-incompressible case at 0.4999). Compared: the vertical
displacement of the corner C = (48, 60) on n x n meshes (a tensor triangulation
of the unit square mapped onto the trapezoid), n = 4, 8, 16, 32, for

* N-PFEM: the library's static step (``conic.solve_step``) with nodal
  integration, loads from the consistent P1 edge traction;
* FEM P1 and FEM P2: the FEM baseline's Gauss-point cone program (elastic:
  one KKT solve), consistent P1/P2 edge loads.

Reference: our own converged mixed solution, Taylor-Hood P2-P1 with the
penalty coupling ``- p q / lambda`` (valid for every nu), assembled with
scikit-fem on n = 32, 64, 128 and extrapolated (Richardson with the observed
order).  The published value for nu = 0.4999 is 7.77 +- 0.01
(Taylor-Hood 7.7286 / 7.7510 / 7.7616 at n = 32 / 64 / 128).

Usage (from the repository root)::

    PYTHONPATH=. python demos/studies/compare_locking.py            # full (~1 min)
    PYTHONPATH=. python demos/studies/compare_locking.py --quick  # nu 0.4999, n 8, 16

Writes ``docs/validation/comparison/locking.json`` and ``locking.png``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as sla
from _common import ROOT, benchmark
from _reporting import save_png, write_result
from skfem import (
    Basis,
    BilinearForm,
    ElementTriP1,
    ElementTriP2,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshTri,
    asm,
    bmat,
    condense,
)
from skfem.helpers import ddot, div, sym_grad

from skfem_npfem import ConeInput, Contacts, solve_step
from skfem_npfem.baseline import gauss_mesh
from skfem_npfem.materials import LinearElastic
from skfem_npfem.mesh.smoothing import nodal_integration

OUT = ROOT / "docs" / "validation" / "comparison"
E, F = 250.0, 100.0
CORNER = np.array([48.0, 60.0])
COMPS = (0, 1, 3)


def cook_mesh(n: int) -> MeshTri:
    """n x n tensor triangulation of the unit square mapped onto Cook's trapezoid."""
    m = MeshTri.init_tensor(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    xi, eta = m.p
    p = np.stack([48.0 * xi, 44.0 * xi + eta * (44.0 - 28.0 * xi)])
    return MeshTri(p, m.t)


def edge_load(mesh: MeshTri, element) -> np.ndarray:
    """Consistent nodal loads (n_dofs_scalar,) of the traction F/16 on x = 48."""
    fb = FacetBasis(
        mesh, element, facets=mesh.facets_satisfying(lambda x: np.isclose(x[0], 48.0))
    )

    @LinearForm
    def traction(v, w):
        return (F / 16.0) * v

    return asm(traction, fb)


def clamped(x: np.ndarray) -> np.ndarray:
    """(n, 2) fixity of nodes at positions x: clamped on x = 0."""
    return np.repeat(np.isclose(x[:, 0], 0.0)[:, None], 2, axis=1)


def npfem(n: int, nu: float) -> float:
    mesh = cook_mesh(n)
    x = mesh.p.T
    N = x.shape[0]
    force = np.zeros((N, 2))
    force[:, 1] = edge_load(mesh, ElementTriP1())
    data = ConeInput(
        operator=nodal_integration(mesh, COMPS),
        materials=[LinearElastic(E, nu)],
        material=np.zeros(N, int),
        sigma_n=np.zeros((N, 4)),
        force=force,
        fixed=clamped(x),
        du_prescribed=np.zeros((N, 2)),
        contacts=Contacts.empty(2),
    )
    du = solve_step(data).du
    return float(du[np.argmin(np.linalg.norm(x - CORNER, axis=1)), 1])


def fem(n: int, nu: float, element: str) -> float:
    mesh = cook_mesh(n)
    gm = gauss_mesh(mesh.p.T, mesh.t, element, COMPS)
    N = gm.node_x.shape[0]
    force = np.zeros((N, 2))
    force[:, 1] = edge_load(mesh, ElementTriP1() if element == "p1" else ElementTriP2())
    data = ConeInput(
        operator=gm.points,
        materials=[LinearElastic(E, nu)],
        material=np.zeros(gm.points.n_points, int),
        sigma_n=np.zeros((gm.points.n_points, 4)),
        force=force,
        fixed=clamped(gm.node_x),
        du_prescribed=np.zeros((N, 2)),
        contacts=Contacts.empty(2),
    )
    du = solve_step(data).du
    return float(du[np.argmin(np.linalg.norm(gm.node_x - CORNER, axis=1)), 1])


def taylor_hood(n: int, nu: float) -> float:
    """u_y(C) of the Taylor-Hood P2-P1 solution with penalty -p q / lambda."""
    mesh = cook_mesh(n)
    ub = Basis(mesh, ElementVector(ElementTriP2()))
    pb = ub.with_element(ElementTriP1())
    mu = E / (2 * (1 + nu))
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))

    @BilinearForm
    def stiff(u, v, w):
        return 2 * mu * ddot(sym_grad(u), sym_grad(v))

    @BilinearForm
    def coupling(u, q, w):
        return div(u) * q

    @BilinearForm
    def penalty(p, q, w):
        return p * q / lam

    B = asm(coupling, ub, pb)
    K = bmat([[asm(stiff, ub), B.T], [B, -asm(penalty, pb)]], "csr")
    f = np.zeros(K.shape[0])
    fb = FacetBasis(
        mesh, ub.elem, facets=mesh.facets_satisfying(lambda x: np.isclose(x[0], 48.0))
    )

    @LinearForm
    def traction(v, w):
        return (F / 16.0) * v[1]

    f[: ub.N] = asm(traction, fb)
    fixed = ub.get_dofs(lambda x: np.isclose(x[0], 0.0)).all()
    sol = np.zeros(K.shape[0])
    A, b, _, free = condense(K, f, D=fixed, x=sol)
    sol[free] = sla.spsolve(A.tocsc(), b)
    corner = int(np.argmin(np.linalg.norm(mesh.p.T - CORNER, axis=1)))
    return float(sol[ub.nodal_dofs[1, corner]])


def reference(nu: float, levels=(32, 64, 128)) -> dict:
    """Taylor-Hood values and their Richardson extrapolation."""
    vals = [taylor_hood(n, nu) for n in levels]
    out = {"levels": list(levels), "values": vals, "value": vals[-1]}
    if len(vals) == 3:
        d1, d2 = vals[1] - vals[0], vals[2] - vals[1]
        if d1 * d2 > 0 and abs(d2) < abs(d1):
            order = float(np.log2(d1 / d2))
            out["order"] = order
            out["value"] = vals[2] + d2 / (2**order - 1)
    return out


def run(nus, meshes, ref_levels) -> dict:
    result = {"E": E, "F": F, "meshes": list(meshes), "cases": []}
    for nu in nus:
        ref = reference(nu, ref_levels)
        case = {"nu": nu, "reference": ref, "methods": {}}
        for name, element in (("N-PFEM", None), ("FEM P1", "p1"), ("FEM P2", "p2")):
            vals = [
                npfem(n, nu) if element is None else fem(n, nu, element) for n in meshes
            ]
            case["methods"][name] = {
                "u_C": vals,
                "ratio": [v / ref["value"] for v in vals],
            }
        result["cases"].append(case)
    return result


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = result["cases"]
    fig, axes = plt.subplots(1, len(cases), figsize=(4 * len(cases), 3.8), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, case in zip(axes, cases, strict=True):
        for name, style in (("N-PFEM", "o-"), ("FEM P1", "s--"), ("FEM P2", "^-")):
            ax.semilogx(
                result["meshes"],
                case["methods"][name]["ratio"],
                style,
                label=name,
                base=2,
            )
        ax.axhline(1.0, color="k", lw=1)
        ax.set_title(f"nu = {case['nu']}  (u_ref = {case['reference']['value']:.4g})")
        ax.set_xlabel("elements per side n")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("u_y(C) / reference")
    axes[0].legend()
    fig.tight_layout()
    save_png(fig, path)


def table(result: dict) -> str:
    """Markdown table: u_y(C)/reference per method, nu and mesh."""
    ns = result["meshes"]
    head = (
        "| nu | reference u_y(C) | method | "
        + " | ".join(f"n = {n}" for n in ns)
        + " |"
    )
    lines = [head, "|" + "---|" * (3 + len(ns))]
    for case in result["cases"]:
        ref = case["reference"]["value"]
        for name, m in case["methods"].items():
            cells = " | ".join(f"{r:.4f}" for r in m["ratio"])
            lines.append(f"| {case['nu']} | {ref:.4f} | {name} | {cells} |")
    return "\n".join(lines)


# ---------------------------------------------------------------------------
# The tables of the docs pages, rendered from the committed JSON (--tables).

docs_tables = benchmark("_tables")
TABLES: docs_tables.Tables = {}
docs_table = docs_tables.registry(TABLES)


@docs_table("docs/validation/comparison/locking.json")
def locking() -> str:
    """Cook's membrane: u_y(C) over the reference, per nu, method and mesh."""
    data = docs_tables.load("docs/validation/comparison/locking.json")
    out = []
    for case in data["cases"]:
        for method, res in case["methods"].items():
            out.append(
                [f"{case['nu']:g}", f"{case['reference']['value']:.4f}", method]
                + [f"{x:.4f}" for x in res["ratio"]]
            )
    return docs_tables.md(
        ["ν", "reference u_y(C)", "method"] + [f"n = {n}" for n in data["meshes"]], out
    )


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--quick", action="store_true", help="nu = 0.4999, n = 8, 16")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--no-plot", action="store_true")
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    args = ap.parse_args(argv)
    if args.tables:
        docs_tables.write(TABLES)
        return {}
    start = time.perf_counter()
    if args.quick:
        result = run([0.4999], [8, 16], (32,))
    else:
        result = run([0.3, 0.49, 0.4999], [4, 8, 16, 32], (32, 64, 128))
    result["quick"] = args.quick
    result["wall_time"] = time.perf_counter() - start
    if not args.quick:
        write_result(args.out / "locking.json", result)
        if not args.no_plot:
            plot(result, args.out / "locking.png")
    print(table(result))
    return result


if __name__ == "__main__":
    main()
