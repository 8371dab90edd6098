"""Linear-solver backends: automatic choice and the MKL Pardiso wiring."""

import ast
import importlib.metadata
import os
import subprocess
import sys

import numpy as np
import pytest

import skfem_npfem as npfem
from skfem_npfem import backends


def _has_mkl_wheel() -> bool:
    try:
        importlib.metadata.version("mkl")
    except importlib.metadata.PackageNotFoundError:
        return False
    return sys.platform == "linux"


def _footing(solver):
    return npfem.run_scene("strip-footing", {"linear_solver": solver, "steps": 3})


@pytest.mark.skipif(not _has_mkl_wheel(), reason="mkl extra not installed")
def test_mkl_is_found_without_user_setup():
    # The mkl extra is installed: Pardiso must be usable with no environment set-up.
    assert backends.mkl_available()


@pytest.mark.parametrize("solver", ["qdldl", "faer", "auto"])
def test_backends_agree(solver):
    # Same cone program, different factorisations: q/c equal to 1e-7 relative.
    ref = _footing("qdldl")["metrics"]["bearing_factor"]
    val = _footing(solver)["metrics"]["bearing_factor"]
    assert abs(val / ref - 1) < 1e-7


@pytest.mark.skipif(not _has_mkl_wheel(), reason="mkl extra not installed")
def test_mkl_agrees_with_qdldl():
    ref = _footing("qdldl")["metrics"]["bearing_factor"]
    val = _footing("mkl")["metrics"]["bearing_factor"]
    assert abs(val / ref - 1) < 1e-7


def test_mkl_requested_but_missing_is_a_clear_error(monkeypatch):
    monkeypatch.setattr(npfem.conic, "mkl_available", lambda: False)
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
        "from pathlib import Path; from skfem_npfem import backends as b;"
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
