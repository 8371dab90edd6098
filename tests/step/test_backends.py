"""Linear-solver backends: automatic choice and the MKL Pardiso wiring."""

import ast
import functools
import importlib.metadata
import os
import subprocess
import sys

import numpy as np
import pytest

import skfem_npfem as npfem
from skfem_npfem.step import backends, solver


def _has_mkl_wheel() -> bool:
    try:
        importlib.metadata.version("mkl")
    except importlib.metadata.PackageNotFoundError:
        return False
    return sys.platform == "linux"


@functools.cache
def _footing(solver):
    return npfem.run_scene("strip-footing", {"linear_solver": solver, "steps": 3})


@pytest.mark.skipif(not _has_mkl_wheel(), reason="mkl extra not installed")
def test_mkl_is_found_without_user_setup():
    # The mkl extra is installed: Pardiso must be usable with no environment set-up.
    assert backends.mkl_available()


@pytest.mark.parametrize("solver", ["faer", "auto"])
def test_backends_agree(solver):
    # Same cone program, two different factorisations: q/c equal to 1e-7
    # relative.  The reference is qdldl, or faer when the requested backend
    # resolved to qdldl ("auto" on this small 2D program without MKL), so that
    # every case compares two different backends.
    run = _footing(solver)
    used = run["solver"]["linear_solvers"]
    ref = _footing("faer" if used == ["qdldl"] else "qdldl")
    assert len(used) == 1 and used != ref["solver"]["linear_solvers"]
    val, expected = (r["metrics"]["bearing_factor"] for r in (run, ref))
    assert abs(val / expected - 1) < 1e-7


@pytest.mark.skipif(not _has_mkl_wheel(), reason="mkl extra not installed")
def test_mkl_agrees_with_qdldl():
    ref = _footing("qdldl")["metrics"]["bearing_factor"]
    val = _footing("mkl")["metrics"]["bearing_factor"]
    assert abs(val / ref - 1) < 1e-7


def test_mkl_requested_but_missing_is_a_clear_error(monkeypatch):
    monkeypatch.setattr(solver, "mkl_available", lambda: False)
    with pytest.raises(npfem.ParameterError, match=r"linear_solver.*mkl"):
        npfem.SolverOptions(linear_solver="mkl").resolved_linear_solver(10, 2)


def test_auto_choice_by_size_and_dimension(monkeypatch):
    monkeypatch.setattr(backends, "mkl_available", lambda: False)
    assert backends.choose_linear_solver(1_000, 2) == "qdldl"
    assert backends.choose_linear_solver(10**6, 2) == "faer"
    assert backends.choose_linear_solver(1_000, 3) == "faer"
    monkeypatch.setattr(backends, "mkl_available", lambda: True)
    assert backends.choose_linear_solver(10**6, 3) == "mkl"
    assert backends.choose_linear_solver(100, 2) == "qdldl"


@pytest.mark.skipif(not _has_mkl_wheel(), reason="mkl extra not installed")
def test_private_cache_folder_works(tmp_path):
    # When the wheel's folder is read-only, a cache folder with a copy of the
    # runtime and links to its siblings must work in a fresh process.
    folder = backends.mkl_library_dir()
    runtime = sorted(folder.glob("libmkl_rt.so.*"))[-1]
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path))
    code = (
        "from pathlib import Path; from skfem_npfem.step import backends as b;"
        f"print(b._private_copy(Path({str(folder)!r}), Path({str(runtime)!r})))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    assert out.startswith(str(tmp_path))
    env["MKL_PARDISO_PATH"] = out
    check = (
        "import numpy as np, scipy.sparse as sp, clarabel;"
        "s = clarabel.DefaultSettings(); s.verbose = False;"
        "s.direct_solve_method = 'mkl';"
        "sol = clarabel.DefaultSolver(sp.csc_matrix(np.eye(2)), np.array([1.0, -1]),"
        " sp.csc_matrix(np.eye(2)), np.ones(2), [clarabel.NonnegativeConeT(2)],"
        " s).solve(); print(sol.status, np.round(sol.x, 6).tolist())"
    )
    res = subprocess.run(
        [sys.executable, "-c", check],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    # min 1/2|x|^2 + x0 - x1 s.t. x <= 1 elementwise: x = (-1, 1) (to 1e-4, the
    # interior-point tolerance on an active bound).
    status, values = res.split(" ", 1)
    assert status == "Solved"
    assert np.allclose(ast.literal_eval(values), [-1.0, 1.0], atol=1e-4)


# A gravity-loaded Drucker-Prager block (8 x 4 x 4 tets, 225 nodes) whose face
# x = W is free: one dynamic step with many active yield cones.  Run in a child
# process because a crash inside MKL would take pytest down with it.
_BLOCK3D_CHILD = """
import sys
import numpy as np
from skfem import MeshTet
import skfem_npfem as npfem
from skfem_npfem.step import backends
from skfem_npfem import FixedMesh, Model, Simulation
from skfem_npfem.mesh.smoothing import nodal_integration

W, D, H, rho, g = 2.0, 1.0, 1.0, 1800.0, 9.81
mesh = MeshTet.init_tensor(
    np.linspace(0, W, 9), np.linspace(0, D, 5), np.linspace(0, H, 5)
)
x = mesh.p.T.copy()
sv = -rho * g * (H - x[:, 2])
stress = np.zeros((x.shape[0], 6))
stress[:, :3] = 0.5 * sv[:, None]
stress[:, 2] = sv
fixed = np.zeros((x.shape[0], 3), bool)
fixed[np.isclose(x[:, 2], 0.0)] = True
for k, ext in ((0, W), (1, D)):
    fixed[np.isclose(x[:, k], 0.0) | np.isclose(x[:, k], ext), k] = True
fixed[np.isclose(x[:, 0], W) & ~np.isclose(x[:, 2], 0.0), 0] = False
mat = npfem.DruckerPrager(10e6, 0.3, rho, c=1e3, phi=30.0, psi=0.0,
                          match="compression")
out = {}
for solver, threads in (("faer", 0), ("mkl", 1), ("mkl", 2)):
    p = npfem.Particles.create(
        x, rho * nodal_integration(mesh).volumes, stress=stress, fixed=fixed
    )
    model = Model(dim=3, materials=[mat], gravity=g, mode="dynamic",
                  theta1=1.0, theta2=1.0,
                  solver=npfem.SolverOptions(linear_solver=solver,
                                             max_threads=threads))
    sim = Simulation(p, model, FixedMesh(mesh.t), 5e-3)
    sim.run(steps=1)
    out[(solver, threads)] = sim.particles.x - x
    assert sim.records[-1].iterations > 5  # the yield cones are active
ref = out[("faer", 0)]
for key in (("mkl", 1), ("mkl", 2)):
    print(key[1], np.abs(out[key] - ref).max() / np.abs(ref).max())
print("restored", backends.pardiso_thread_count(0))
"""


@pytest.mark.skipif(not _has_mkl_wheel(), reason="mkl extra not installed")
def test_mkl_thread_count_is_honoured_in_3d():
    # Clarabel 0.11 sets Pardiso's threads after the symbolic analysis, and MKL
    # crashed (SIGSEGV) on this 225-node 3D step with max_threads = 1; the
    # library now sets the thread count first.  Same displacement as faer to
    # 1e-6 of the largest one, and MKL's own thread setting is restored.
    before = subprocess.run(
        [
            sys.executable,
            "-c",
            "from skfem_npfem.step import backends; "
            "print(backends.pardiso_thread_count(0))",
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    res = subprocess.run(
        [sys.executable, "-c", _BLOCK3D_CHILD], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr[-2000:]
    lines = res.stdout.split("\n")
    rel = {ln.split()[0]: float(ln.split()[1]) for ln in lines if ln[:1].isdigit()}
    assert set(rel) == {"1", "2"}
    assert max(rel.values()) < 1e-6, rel
    assert f"restored {before}" in res.stdout


@pytest.mark.skipif(not _has_mkl_wheel(), reason="mkl extra not installed")
def test_mkl_reruns_are_bit_identical():
    # Pardiso runs in MKL's conditional-reproducibility mode by default: the same
    # collapse run twice (remeshing every step) ends with identical positions.
    # Also with one Pardiso thread instead of all cores: resuming with another
    # ``threads`` value is allowed and must not change the result.
    def run(threads=0):
        scene = npfem.get_scene("column-collapse")
        values = scene.resolve({"linear_solver": "mkl", "threads": threads})
        sim = scene.build(values, out=None, progress=False).simulation
        sim.run(steps=10)
        return sim.particles.x

    a, b, c = run(), run(), run(threads=1)
    assert np.array_equal(a, b)
    assert np.array_equal(a, c)


def test_faer_thread_default_follows_the_core_count(monkeypatch):
    # 0 = automatic: one faer thread on <= 2 cores (measured faster there),
    # Clarabel's own choice on bigger machines; an explicit count always wins.
    opts = npfem.SolverOptions(linear_solver="faer")
    monkeypatch.setattr(backends, "available_cores", lambda: 2)
    assert opts.clarabel_settings("faer").max_threads == 1
    assert opts.clarabel_settings("qdldl").max_threads == 0
    monkeypatch.setattr(backends, "available_cores", lambda: 16)
    assert opts.clarabel_settings("faer").max_threads == 0
    explicit = npfem.SolverOptions(linear_solver="faer", max_threads=3)
    assert explicit.clarabel_settings("faer").max_threads == 3


@pytest.mark.parametrize(
    ("requested", "expected"), [("auto", "qdldl"), ("faer", "faer")]
)
def test_stalled_automatic_backend_falls_back_to_qdldl(
    monkeypatch, requested, expected
):
    # A backend chosen automatically that stalls (InsufficientProgress even with
    # iterative refinement) is replaced by qdldl for one more solve, whose
    # answer is the same program's optimum; a backend the user asked for is
    # kept and its failure reported.
    import clarabel
    import scipy.sparse as sp

    real = clarabel.DefaultSolver

    class Stalling:
        def __init__(self, P, q, A, b, cones, settings):
            self.method = settings.direct_solve_method
            self.inner = real(P, q, A, b, cones, settings)

        def solve(self):
            sol = self.inner.solve()
            if self.method == "faer":
                return type("Stalled", (), {
                    "status": "InsufficientProgress", "iterations": 7,
                    "x": sol.x, "z": sol.z,
                })()  # fmt: skip
            return sol

    monkeypatch.setattr(clarabel, "DefaultSolver", Stalling)
    monkeypatch.setattr(solver, "choose_linear_solver", lambda *a, **k: "faer")
    # min (x - 1)^2 / 2 subject to x <= 0.25: x = 0.25
    P = sp.csc_matrix([[1.0]])
    A = sp.csc_matrix([[1.0]])
    res = solver.solve_clarabel(
        P,
        np.array([-1.0]),
        A,
        np.array([0.25]),
        [clarabel.NonnegativeConeT(1)],
        solver.SolverOptions(linear_solver=requested),
        1,
    )
    assert res.linear_solver == expected
    if expected == "qdldl":
        assert res.status == "Solved"
        assert res.x[0] == pytest.approx(0.25, abs=1e-7)
        assert res.iterations > 7  # the stalled solve's 7 are counted
    else:
        assert res.status == "InsufficientProgress"
