#!/usr/bin/env python
"""What does remapping cost?  Stress drift from remeshing, per method and transfer.

Two experiments, each for N-PFEM and FEM-remap P1/P2 x nearest/recovery:

1. **At rest** (remesh idempotence, docs/verification.md): the geostatic elastic
   column (W = 1 m, H = 4 m, E = 10 MPa, nu = 0.3, rho = 2000 kg/m^3, spacing
   0.25 m) is brought to equilibrium by one static step, then remeshed 100 times
   without motion (small-strain steps: ``update_geometry=False`` and no
   objective rotation; with geometry updates every static re-solve moves the
   settled particles a little, which flips lattice diagonals and changes the
   N-PFEM equilibrium too). N-PFEM goes through the library's ``advance`` with
   an ``AlphaShapeMesher`` every time (mesh rebuilt, cone program re-solved);
   FEM-remap's Gauss-point state is transferred to each new mesh.  An alpha
   shape of unmoved particles is the same mesh every time (and FEM-remap then
   skips the transfer), so each FEM remesh uses a different jitter seed: the
   lattice's Delaunay ties break differently and about half of the diagonals
   flip - the worst case of a mesh change, which a flowing body meets on a
   fraction of its elements every step.  Drift = change of the particles'
   (recovered) stresses, relative L2, after n remeshes; per transfer = drift/n.
2. **Rigid motion**: a pre-stressed block (21 x 21 lattice on the unit square,
   a smooth non-polynomial stress field sigma0(X) of order 1 kPa) is
   translated by (2, 1) m and rotated by 90 degrees in 100 equal steps,
   remeshed every step (new seed).  Kinematics are exact (positions moved
   rigidly, stresses rotated by the exact rotation increment) so that only
   the mapping can change the stress invariants p = I1/3 and q = sqrt(3 J2);
   their drift is measured against the exact values of each stress point's
   material point.  N-PFEM maps nothing: its drift is round-off by
   construction.
3. **A shear band with particle insertion**: the same pre-stressed block is
   sheared in a horizontal band (``v_x = V tanh((y - 1/2) / w)``, w = 2
   spacings, the two halves sliding 0.5 m past each other in 100 steps), so
   the edges across the band stretch to several spacings, as round a pushed
   body's shoulder.  The stress is a frozen material field (no rotation, no
   constitutive update): its exact value at a point is sigma0 at the point's
   material point, which the motion gives in closed form
   (``X = x - t V tanh((y - 1/2) / w)``).  N-PFEM adds particles where an edge
   exceeds 1.6 spacings (the library's :class:`~skfem_npfem.run.refining.Refiner`,
   the new particle's stress the mean of its edge's ends); FEM-remap transfers
   its Gauss points whenever the band's Delaunay triangulation changes.  The
   drift of q is measured as in experiment 2, over every stress point (for
   N-PFEM: only the added particles can differ).

Usage (from the repository root)::

    PYTHONPATH=. python demos/studies/compare_mapping.py            # full (~1 min)
    PYTHONPATH=. python demos/studies/compare_mapping.py --quick    # reduced

Writes ``docs/validation/comparison/mapping.json`` and ``mapping.png``
(``--out`` to change the folder).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from pathlib import Path

import numpy as np
from _common import ROOT, benchmark
from _reporting import save_png, write_result

from skfem_npfem.baseline import FemRemap
from skfem_npfem.baseline.fem_nodes import gauss_points
from skfem_npfem.baseline.transfer import recover_nodal
from skfem_npfem.materials import LinearElastic
from skfem_npfem.mesh.sources import AlphaShapeMesher
from skfem_npfem.scenes import get_scene
from skfem_npfem.step.kinematics import tensor_to_voigt, voigt_to_tensor
from skfem_npfem.step.model import Model
from skfem_npfem.step.stages import advance

OUT = ROOT / "docs" / "validation" / "comparison"
VARIANTS = [(e, t) for e in ("p1", "p2") for t in ("nearest", "recovery")]


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _column(spacing: float):
    """Particles and static model of the column; no motion."""
    scene = get_scene("elastic-column")
    sim = scene.build(scene.resolve({"spacing": spacing})).simulation
    return sim.particles, dataclasses.replace(
        sim.model, update_geometry=False, objective_rotation=False
    )


def _nodal(state) -> np.ndarray:
    """Recovered particle stresses of a FEM state (the user's output)."""
    gp = gauss_points(state.x, state.cells, "p1" if state.nq == 1 else "p2")
    return recover_nodal(state.x, state.cells, gp, state.gp_stress)


def at_rest(n_remesh: int = 100, spacing: float = 0.25) -> dict:
    """Experiment 1: drift of a column at rest under repeated remeshing."""
    p, model = _column(spacing)
    mesher = AlphaShapeMesher(h=spacing, alpha=1.3)
    p0, _ = advance(p, model, 1.0, mesher)
    q = p0
    for k in range(n_remesh):
        q, _ = advance(q, model, 1.0, mesher, step=k + 1)
    out = {
        "n_remesh": n_remesh,
        "n_particles": int(p.n),
        "npfem": {
            "drift": _rel(q.stress, p0.stress),
            "max_change": float(
                np.max(np.abs(q.stress - p0.stress)) / np.max(np.abs(p0.stress))
            ),
        },
    }
    first = AlphaShapeMesher(h=spacing, alpha=1.3, seed=0)(p.x)
    a0 = first[0][first[1]].T
    flips = []
    for e, t in VARIANTS:
        method = FemRemap(e, t)
        st = method.initial_state(p, mesher)
        st, _ = method.advance(st, model, 1.0, mesher)
        ref = _nodal(st)
        steps, last = [], ref
        for k in range(1, n_remesh + 1):
            act, loc = AlphaShapeMesher(h=spacing, alpha=1.3, seed=k)(st.x)
            cells = np.ascontiguousarray(act[loc].T)
            if e == "p1" and t == "nearest":
                flips.append(1.0 - _shared(cells, a0))
            sig, eps, _ = method.remap(st, cells, model)
            st = st.replace(cells=cells, gp_stress=sig, gp_eps_p=eps)
            now = _nodal(st)
            steps.append(_rel(now, ref))
            last = now
        out[f"fem-{e}-{t}"] = {
            "drift": _rel(last, ref),
            "drift_per_transfer": _rel(last, ref) / n_remesh,
            "history": steps,
        }
    out["changed_element_fraction"] = float(np.mean(flips))
    return out


def _shared(cells: np.ndarray, ref: np.ndarray) -> float:
    """Fraction of ``cells`` that are also elements of ``ref``."""
    a = {tuple(sorted(c)) for c in cells.tolist()}
    b = {tuple(sorted(c)) for c in ref.tolist()}
    return len(a & b) / len(a)


def prestress(X: np.ndarray, s0: float = 1.0e3) -> np.ndarray:
    """Smooth pre-stress field (full Voigt, plane strain) at reference points."""
    x, y = X[:, 0], X[:, 1]
    return s0 * np.stack(
        [
            -1.0 - 0.5 * np.sin(2.0 * x) * np.cos(1.5 * y),
            -0.6 + 0.4 * np.exp(-((x - 0.4) ** 2 + (y - 0.6) ** 2)),
            -0.8 + 0.3 * x * y,
            0.25 * np.cos(2.5 * x + y),
        ],
        axis=1,
    )


def invariants(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean stress p and von Mises stress q of full-Voigt stresses."""
    p = s[:, :3].mean(axis=1)
    dev = s[:, :3] - p[:, None]
    j2 = 0.5 * np.sum(dev**2, axis=1) + np.sum(s[:, 3:] ** 2, axis=1)
    return p, np.sqrt(3.0 * j2)


def _rotate(s: np.ndarray, angle: float) -> np.ndarray:
    c, si = math.cos(angle), math.sin(angle)
    R = np.array([[c, -si, 0.0], [si, c, 0.0], [0.0, 0.0, 1.0]])
    return tensor_to_voigt(R @ voigt_to_tensor(s) @ R.T, s.shape[1])


def rigid_motion(n_steps: int = 100, n: int = 20) -> dict:
    """Experiment 2: invariant drift of a pre-stressed block moved rigidly."""
    h = 1.0 / n
    g = np.linspace(0.0, 1.0, n + 1)
    X = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    c0 = X.mean(axis=0)
    model = Model(dim=2, materials=[LinearElastic(1.0e7, 0.3, 2000.0)], gravity=0.0)
    d_ang, d_pos = 0.5 * math.pi / n_steps, np.array([2.0, 1.0]) / n_steps

    def place(k: int) -> np.ndarray:
        a = k * d_ang
        R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        return (X - c0) @ R.T + c0 + k * d_pos

    def pull_back(x: np.ndarray, k: int) -> np.ndarray:
        a = k * d_ang
        R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        return (x - c0 - k * d_pos) @ R + c0

    out = {"n_steps": n_steps, "n_particles": int(X.shape[0])}
    # N-PFEM: the particles carry the stress; it is only rotated.
    s = prestress(X)
    for _ in range(n_steps):
        s = _rotate(s, d_ang)
    out["npfem"] = _drift(s, prestress(X))
    for e, t in VARIANTS:
        out[f"fem-{e}-{t}"] = _fem_rigid(
            e, t, X, h, model, d_ang, place, pull_back, n_steps
        )
    return out


def _drift(s: np.ndarray, exact: np.ndarray) -> dict:
    p, q = invariants(s)
    pe, qe = invariants(exact)
    scale = float(np.sqrt(np.mean(pe**2 + qe**2)))
    return {
        "p_drift": float(np.sqrt(np.mean((p - pe) ** 2)) / scale),
        "q_drift": float(np.sqrt(np.mean((q - qe) ** 2)) / scale),
        "max_drift": float(max(np.max(np.abs(p - pe)), np.max(np.abs(q - qe))) / scale),
    }


def _fem_rigid(e, t, X, h, model, d_ang, place, pull_back, n_steps) -> dict:
    from skfem_npfem.particles import Particles

    method = FemRemap(e, t)
    p = Particles.create(X, np.ones(X.shape[0]), stress=prestress(X))
    st = method.initial_state(p, AlphaShapeMesher(h=h, alpha=1.3, seed=0))

    def gp_of(state):
        return gauss_points(state.x, state.cells, e)

    # Start from the exact field at the Gauss points (not its interpolant).
    st = st.replace(gp_stress=prestress(gp_of(st)))
    history = []
    for k in range(1, n_steps + 1):
        st = st.replace(x=place(k), gp_stress=_rotate(st.gp_stress, d_ang))
        act, loc = AlphaShapeMesher(h=h, alpha=1.3, seed=k)(st.x)
        cells = np.ascontiguousarray(act[loc].T)
        sig, eps, _ = method.remap(st, cells, model)
        st = st.replace(cells=cells, gp_stress=sig, gp_eps_p=eps)
        exact = _rotate(prestress(pull_back(gp_of(st), k)), k * d_ang)
        history.append(_drift(st.gp_stress, exact)["q_drift"])
    res = _drift(st.gp_stress, exact)
    res["q_history"] = history
    return res


def _area(x: np.ndarray, cells: np.ndarray) -> float:
    """Total area of the triangles ``cells`` (ne, 3) over ``x``."""
    a, b, c = (x[cells[:, i]] for i in range(3))
    d1, d2 = b - a, c - a
    return float(0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]).sum())


def band(kind: str, n_steps: int = 100, n: int = 20, slide: float = 0.5) -> dict:
    """Experiment 3: q drift in a band that shears or opens, insertion vs transfer.

    ``kind="shear"``: ``v_x = V tanh((y - 1/2) / w)``; ``"opening"``:
    ``v_x = V tanh((x - 1/2) / w)``; w = 2 spacings, the two sides moving
    ``slide`` apart.  Both motions have closed forms, so every point's
    material point is exact.
    """
    from skfem_npfem.particles import Particles
    from skfem_npfem.run.refining import Refiner

    h = 1.0 / n
    g = np.linspace(0.0, 1.0, n + 1)
    X = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    model = Model(dim=2, materials=[LinearElastic(1.0e7, 0.3, 2000.0)], gravity=0.0)
    w, V, dt = 2.0 * h, 0.5 * slide, 1.0 / n_steps
    axis = 1 if kind == "shear" else 0

    def moved(x: np.ndarray, t: float) -> np.ndarray:
        """Points ``x`` carried by the flow for a time ``t`` (< 0: back)."""
        out = x.copy()
        if kind == "shear":  # y constant, so v_x constant along a path
            out[:, 0] += t * V * np.tanh((x[:, 1] - 0.5) / w)
        else:  # dx/dt = V tanh((x - 1/2)/w): sinh((x - 1/2)/w) grows as e^(Vt/w)
            s = np.sinh((x[:, 0] - 0.5) / w) * math.exp(V * t / w)
            out[:, 0] = 0.5 + w * np.arcsinh(s)
        return out

    out = {"kind": kind, "n_steps": n_steps, "n_particles": int(X.shape[0])}
    out["slide"], out["band_axis"] = slide, "xy"[axis]
    ends = moved(np.array([[0.0, 0.5], [1.0, 0.5]]), 1.0)
    exact_area = float(ends[1, 0] - ends[0, 0])  # the shear keeps the unit area
    # N-PFEM: the particles carry sigma0; the refiner adds particles, no rotation.
    p = Particles.create(X, np.full(X.shape[0], h * h), stress=prestress(X))
    mesher, refiner = AlphaShapeMesher(h=h, alpha=1.3, seed=0), Refiner(1.6)
    history = []
    for k in range(1, n_steps + 1):
        p = refiner(p.replace(x=moved(p.x, dt)), mesher)
        exact = prestress(moved(p.x, -k * dt))
        history.append(_drift(p.stress, exact)["q_drift"])
    res = _drift(p.stress, exact)
    added = slice(X.shape[0], None)
    res |= {"q_history": history, "inserted": refiner.inserted}
    act, loc = mesher(p.x)
    res["area_ratio"] = _area(p.x, act[loc].T) / exact_area
    res["added_q_drift"] = (
        _drift(p.stress[added], exact[added])["q_drift"] if refiner.inserted else None
    )
    out["npfem"] = res
    for e, t in VARIANTS:
        method, mesher = FemRemap(e, t), AlphaShapeMesher(h=h, alpha=1.3, seed=0)
        q = Particles.create(X, np.ones(X.shape[0]), stress=prestress(X))
        st = method.initial_state(q, mesher)
        st = st.replace(gp_stress=prestress(gauss_points(st.x, st.cells, e)))
        history, transfers = [], 0
        for k in range(1, n_steps + 1):
            st = st.replace(x=moved(st.x, dt))
            act, loc = mesher(st.x)
            cells = np.ascontiguousarray(act[loc].T)
            sig, eps, info = method.remap(st, cells, model)
            transfers += info["remapped"]
            st = st.replace(cells=cells, gp_stress=sig, gp_eps_p=eps)
            gp = gauss_points(st.x, st.cells, e)
            exact = prestress(moved(gp, -k * dt))
            history.append(_drift(st.gp_stress, exact)["q_drift"])
        res = _drift(st.gp_stress, exact)
        res |= {"q_history": history, "transfers": transfers}
        res["area_ratio"] = _area(st.x, st.cells) / exact_area
        out[f"fem-{e}-{t}"] = res | {"stress_points": int(gp.shape[0])}
    out["npfem"]["stress_points"] = int(p.n)
    return out


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.2))
    rest, rigid = result["at_rest"], result["rigid_motion"]
    opening = result["opening_band"]
    for key, name in MAPPING_NAMES.items():
        hist = np.maximum(np.array(opening[key]["q_history"]), 1e-17)
        style = "k-" if key == "npfem" else ("-" if "recovery" in key else "--")
        axes[2].semilogy(np.arange(1, hist.size + 1), hist, style, label=name)
    axes[2].set_xlabel("steps")
    axes[2].set_ylabel("RMS drift of q")
    axes[2].set_title("opening band: insertion (N-PFEM) vs transfer")
    axes[2].grid(True, which="both", alpha=0.3)
    for e, t in VARIANTS:
        key = f"fem-{e}-{t}"
        style = "-" if t == "recovery" else "--"
        hist = np.maximum(np.array(rest[key]["history"]), 1e-17)
        axes[0].semilogy(
            np.arange(1, hist.size + 1), hist, style, label=f"FEM {e.upper()} {t}"
        )
        hist = np.maximum(np.array(rigid[key]["q_history"]), 1e-17)
        axes[1].semilogy(
            np.arange(1, hist.size + 1), hist, style, label=f"FEM {e.upper()} {t}"
        )
    for ax, val in (
        (axes[0], rest["npfem"]["drift"]),
        (axes[1], rigid["npfem"]["q_drift"]),
    ):
        ax.axhline(max(val, 1e-17), color="k", lw=2, label="N-PFEM")
        ax.set_xlabel("remeshes")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("relative L2 change of particle stresses")
    axes[0].set_title("column at rest, remeshed")
    axes[1].set_ylabel("RMS drift of q = sqrt(3 J2)")
    axes[1].set_title("pre-stressed block moved rigidly")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    save_png(fig, path)


# ---------------------------------------------------------------------------
# The tables of the docs pages, rendered from the committed JSON (--tables).

docs_tables = benchmark("_tables")
TABLES: docs_tables.Tables = {}
docs_table = docs_tables.registry(TABLES)


MAPPING_NAMES = {
    "npfem": "N-PFEM",
    "fem-p1-nearest": "FEM-remap P1 nearest",
    "fem-p1-recovery": "FEM-remap P1 recovery",
    "fem-p2-nearest": "FEM-remap P2 nearest",
    "fem-p2-recovery": "FEM-remap P2 recovery",
}


@docs_table("docs/validation/comparison/mapping.json")
def mapping() -> str:
    """Stress drift from remeshing: at rest and under rigid motion."""
    data = docs_tables.load("docs/validation/comparison/mapping.json")
    rest, rigid = data["at_rest"], data["rigid_motion"]
    n = rest["n_remesh"]
    out = []
    for key, name in MAPPING_NAMES.items():
        a, b = rest.get(key, {}), rigid.get(key, {})
        per = a.get("drift_per_transfer", a.get("drift", math.nan) / n)
        out.append(
            [
                name,
                docs_tables.sci(a.get("drift")),
                docs_tables.sci(per),
                docs_tables.sci(b.get("p_drift")),
                docs_tables.sci(b.get("q_drift")),
                docs_tables.sci(b.get("max_drift")),
            ]
        )
    return docs_tables.md(
        [
            "method",
            f"at rest: drift after {n} remeshes",
            "per remesh",
            "rigid motion: p drift",
            "q drift",
            "max",
        ],
        out,
    )


@docs_table("docs/validation/comparison/mapping.json")
def mapping_band() -> str:
    """Insertion against transfer in a band that shears or opens."""
    return band_table(docs_tables.load("docs/validation/comparison/mapping.json"))


def band_table(data: dict) -> str:
    """The shear and opening bands: q drift after the last step, what was mapped."""
    rows = []
    for key, name in MAPPING_NAMES.items():
        row = [name]
        for kind in ("shear_band", "opening_band"):
            r = data[kind][key]
            if key == "npfem":
                done = f"{r['inserted']} particles added, each once"
            else:
                done = f"{r['stress_points']} points, {r['transfers']} transfers"
            row += [done, *map(docs_tables.sci, (r["q_drift"], r["max_drift"]))]
            row.append(f"{r['area_ratio']:.3f}")
        rows.append(row)
    head = ["method"]
    for kind in ("shear", "opening"):
        head += [f"{kind} band: what is mapped", "q drift", "max", "area"]
    return docs_tables.md(head, rows)


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument("--quick", action="store_true", help="reduced run (tests)")
    ap.add_argument("--out", type=Path, default=OUT, help="output folder")
    ap.add_argument("--no-plot", action="store_true")
    ap.add_argument("--tables", action="store_true", help=docs_tables.HELP)
    args = ap.parse_args(argv)
    if args.tables:
        docs_tables.write(TABLES)
        return {}
    start = time.perf_counter()
    n_remesh, n_steps, n = (100, 20, 10) if args.quick else (100, 100, 20)
    result = {
        "at_rest": at_rest(n_remesh),
        "rigid_motion": rigid_motion(n_steps, n),
        "shear_band": band("shear", n_steps, n),
        "opening_band": band("opening", n_steps, n),
        "quick": args.quick,
    }
    result["wall_time"] = time.perf_counter() - start
    if not args.quick:
        write_result(args.out / "mapping.json", result)
        if not args.no_plot:
            plot(result, args.out / "mapping.png")
    print(table(result))
    print(band_table(result))
    return result


def table(result: dict) -> str:
    """Markdown table of the drifts (the docs quote it)."""
    rest, rigid = result["at_rest"], result["rigid_motion"]
    lines = [
        f"| method | at rest: drift after {rest['n_remesh']} remeshes | per remesh "
        f"| rigid motion: p drift | q drift | max |",
        "|---|---|---|---|---|---|",
    ]
    n = rest["n_remesh"]
    for key in ["npfem"] + [f"fem-{e}-{t}" for e, t in VARIANTS]:
        r, m = rest[key], rigid[key]
        name = (
            "N-PFEM"
            if key == "npfem"
            else key.replace("fem-", "FEM-remap ").replace("-", " ")
        )
        lines.append(
            f"| {name} | {r['drift']:.2e} | {r['drift'] / n:.2e} | {m['p_drift']:.2e} "
            f"| {m['q_drift']:.2e} | {m['max_drift']:.2e} |"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    main()
