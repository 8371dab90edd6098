#!/usr/bin/env python
"""Why the stabilisation costs what it costs: the factor of the step's KKT.

One state of the column collapse (stabilised, ``--skip`` steps from rest) is
stepped once more three times, each time capturing the scaled cone program and
solving it again in a child process with MKL Pardiso's statistics
(:func:`cylinder_profile.pardiso_split`):

* ``beta=30``: the library's stabilised step (element-residual penalty, all
  stress components of neighbouring particles coupled);
* ``beta=0``: the same state without the stabilisation;
* ``one-scalar``: the ``beta=0`` program with one extra variable per particle,
  ``p_i = (trace of its scaled stress) / d`` (zero-cone rows), and a graph
  Laplacian over the mesh edges on the ``p_i`` in the objective.  This is the
  sparsity of the cheapest stress coupling there is -- one scalar per particle,
  as in a pressure-projection stabilisation (Dohrmann & Bochev 2004) -- so its
  factor bounds from below what any stabilisation that couples the stresses of
  neighbouring particles adds.  The values (a unit Laplacian scaled to the
  stress block's diagonal) are not a method: only the symbolic numbers
  (factor non-zeros, GFLOP) of this row are meant to be read.

With ``--modes`` the state is also stepped with the reduced stabilisation
modes (``stabilisation_mode``: ``vertical``, ``sigma_v``, ``mean``;
:mod:`skfem_npfem.step.stabilisation`), at ``beta=30`` and at the ``--betas``
given, one row ``mode=<mode>,beta=<beta>`` each (the ``mean`` mode is the
library's version of the ``one-scalar`` sparsity).

The factor's non-zeros and GFLOP per factorisation come from Pardiso's
symbolic phase and do not depend on the machine's load; the solve times do.

Usage (repository root)::

    python benchmarks/stabilisation_fill.py --case plane_strain --skip 20
    python benchmarks/stabilisation_fill.py --case quarter_cylinder \
        --divisions 18 --skip 2

Writes ``benchmarks/results/stabilisation_fill_plane_strain.json`` or
``stabilisation_fill_quarter_cylinder_<divisions>.json`` (or ``--out``).  Needs
MKL Pardiso (``pip install -e ".[mkl]"``).
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
from pathlib import Path
from typing import Any

import _harness as harness
import clarabel
import numpy as np
import scipy.sparse as sp
from cylinder_profile import capture_step, pardiso_split, save_program

from skfem_npfem.io import write_json
from skfem_npfem.scenes import get_scene

RESULTS = Path(__file__).resolve().parent / "results"
R0 = 0.039


def case_params(case: str, divisions: float) -> dict[str, Any]:
    """Scene parameters of a case (plane strain: 48 particles across L0).

    The quarter cylinder is pinned to the settings its committed results were
    measured with (the paper's bare method apart from the stabilisation this
    benchmark sets, and the full element residual, the one mode there was),
    not to the geometry's defaults of today.
    """
    if case == "plane_strain":
        return {"spacing": 0.2 / 48}
    geo = "quarter-cylinder"
    return {
        "geometry": geo,
        "spacing": R0 / divisions,
        **harness.method_overrides(geo, "bare"),
        "stabilisation_mode": "full",
    }


def node_edges(P30: sp.spmatrix, n: int, ns: int) -> np.ndarray:
    """Pairs ``i < j`` of particles whose stresses the stabilised ``P`` couples."""
    block = sp.coo_matrix(P30.tocsc()[: n * ns, : n * ns])
    i, j = block.row // ns, block.col // ns
    keep = i < j
    return np.unique(np.stack([i[keep], j[keep]], axis=1), axis=0)


def one_scalar(prog: dict[str, Any], edges: np.ndarray, n: int, ns: int, d: int):
    """The ``beta=0`` program plus one coupled scalar per particle (see above)."""
    P0, A0 = sp.csc_matrix(prog["P"]), sp.csc_matrix(prog["A"])
    nx = P0.shape[0]
    diag = P0.diagonal()[: n * ns]
    scale = float(np.median(diag[diag > 0]))
    m = len(edges)
    incidence = sp.csc_matrix(
        (np.tile([1.0, -1.0], m), (np.repeat(np.arange(m), 2), edges.ravel())),
        shape=(m, n),
    )
    L = incidence.T @ incidence  # graph Laplacian: sum over edges of (p_i - p_j)^2
    P = sp.triu(sp.block_diag([P0, scale * L]), format="csc")
    rows = np.repeat(np.arange(n), d)
    cols = (np.arange(n)[:, None] * ns + np.arange(d)[None, :]).ravel()
    trace = sp.csc_matrix((np.full(n * d, -1.0 / d), (rows, cols)), shape=(n, nx))
    A = sp.vstack(
        [
            sp.hstack([trace, sp.identity(n, format="csc")]),
            sp.hstack([A0, sp.csc_matrix((A0.shape[0], n))]),
        ],
        format="csc",
    )
    q = np.concatenate([prog["q"], np.zeros(n)])
    b = np.concatenate([np.zeros(n), prog["b"]])
    cones = [clarabel.ZeroConeT(n), *prog["cones"]]
    return {"P": P, "q": q, "A": A, "b": b, "cones": cones, "options": prog["options"]}


def measure(prog: dict[str, Any]) -> dict[str, Any]:
    """Pardiso's statistics of one captured program (in a child process)."""
    path = save_program(prog)
    try:
        rec = pardiso_split(path)
    finally:
        Path(path).unlink()
    rec["P_nnz"] = int(sp.csc_matrix(prog["P"]).nnz)
    rec["A_shape"] = list(prog["A"].shape)
    return rec


MODES = ("vertical", "sigma_v", "mean")


def run(
    case: str,
    divisions: float,
    skip: int,
    modes: bool = False,
    betas: tuple[float, ...] = (),
) -> dict[str, Any]:
    """Measure the programs on one state of ``case`` (see the module notes)."""
    scene = get_scene("column-collapse")
    params = {**case_params(case, divisions), "linear_solver": "mkl"}
    values = scene.resolve({**params, "stabilisation": 30.0})
    sim = scene.build(values, out=None, progress=False).simulation
    sim.run(steps=skip)
    progs = {}
    for beta in (30.0, 0.0):
        twin = copy.deepcopy(sim)
        twin.model = dataclasses.replace(twin.model, stabilisation=beta)
        progs[f"beta={beta:g}"] = capture_step(twin)
    variants = [("full", b) for b in betas if b != 30.0]
    if modes:
        variants += [(m, b) for m in MODES for b in (30.0, *betas) if b]
    for mode, beta in variants:
        twin = copy.deepcopy(sim)
        twin.model = dataclasses.replace(
            twin.model, stabilisation=beta, stabilisation_mode=mode
        )
        progs[f"mode={mode},beta={beta:g}"] = capture_step(twin)
    n = int(sim.particles.n)
    d = int(sim.particles.x.shape[1])
    ns = progs["beta=0"]["ns"]
    if progs["beta=0"]["sigma"] != slice(0, n * ns):
        raise RuntimeError("the stresses are not the program's first variables")
    edges = node_edges(progs["beta=30"]["P"], n, ns)
    progs["one-scalar"] = one_scalar(progs["beta=0"], edges, n, ns, d)
    out: dict[str, Any] = {
        "case": case,
        "params": params,
        "skip": skip,
        "particles": n,
        "stress_components": ns,
        "mesh_edges": len(edges),
    }
    for name, prog in progs.items():
        out[name] = measure(prog)
        keys = ("factor_nnz", "gflop_per_factorisation")
        print(name, {k: out[name][k] for k in keys})
    base = out["beta=0"]
    for name in [k for k in progs if k != "beta=0"]:
        out[name]["factor_nnz_ratio"] = out[name]["factor_nnz"] / base["factor_nnz"]
        out[name]["gflop_ratio"] = (
            out[name]["gflop_per_factorisation"] / base["gflop_per_factorisation"]
        )
    out["machine"] = harness.machine_info()
    return out


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Run one case and write its JSON (returned)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", choices=("plane_strain", "quarter_cylinder"))
    ap.add_argument("--divisions", type=float, default=12.0, help="3D: r0 / spacing")
    ap.add_argument("--skip", type=int, default=2, help="steps before the measured one")
    ap.add_argument("--modes", action="store_true", help="the reduced modes too")
    ap.add_argument(
        "--betas", type=float, nargs="*", default=[], help="more beta values"
    )
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    result = run(args.case, args.divisions, args.skip, args.modes, tuple(args.betas))
    tag = args.case
    if args.case == "quarter_cylinder":
        tag += f"_{args.divisions:g}"
    write_json(args.out or RESULTS / f"stabilisation_fill_{tag}.json", result)
    return result


if __name__ == "__main__":
    main()
