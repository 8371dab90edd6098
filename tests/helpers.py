"""Helpers shared by several test modules (on ``sys.path`` through pyproject's
``pythonpath = ["tests"]``), so that no test module imports another one.

* the command line run in-process and its one-line error (``run_cli``,
  ``check_cli_error``);
* a structured section mesh with jittered interior nodes (``jittered_section``);
* the exactness check of a geostatic step (``assert_exact_geostatic_step``,
  with the density ``RHO`` and gravity ``GRAV`` of its blocks).
"""

from __future__ import annotations

import io
from contextlib import redirect_stderr, redirect_stdout

import numpy as np
from skfem import MeshTri

from skfem_npfem import ConeInput, solve_step
from skfem_npfem.cli import main
from skfem_npfem.step.conic import build_program
from skfem_npfem.step.stabilisation import element_residual

#: Density (kg/m^3) and gravity (m/s^2) of the geostatic blocks.
RHO, GRAV = 2000.0, 9.81


def run_cli(argv: list[str]) -> tuple[int, str]:
    """``main(argv)`` with captured stdout/stderr; returns (exit code, stderr)."""
    err, out = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(out):
        code = main(argv)
    return code, err.getvalue()


def check_cli_error(code: int, err: str, *needles: str) -> str:
    assert code == 2, (code, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: "), err
    assert "Traceback" not in err
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    return lines[0]


def jittered_section(r0, r1, h, nr, nz, amount=0.25, seed=0):
    """Structured mesh of [r0, r1] x [0, h] with interior nodes jittered."""
    rng = np.random.default_rng(seed)
    m = MeshTri.init_tensor(np.linspace(r0, r1, nr + 1), np.linspace(0, h, nz + 1))
    p = m.p.copy()
    step = min((r1 - r0) / nr, h / nz)
    inner = np.setdiff1d(np.arange(p.shape[1]), m.boundary_nodes())
    p[:, inner] += amount * step * rng.uniform(-1, 1, (2, inner.size))
    return MeshTri(p, m.t)


def assert_exact_geostatic_step(data: ConeInput) -> None:
    """Zero element residual (1e-9 rho g) and a step that keeps the state.

    ``du`` below 1e-8 of the settlement scale rho g H^2 / E = 2e-3 m (H = 1),
    stresses to 1e-6 rho g H.
    """
    prog, _ = build_program(data)
    _, c, w = element_residual(prog)
    assert np.abs(c).max() < 1e-9 * RHO * GRAV
    assert w.min() > 0
    sol = solve_step(data)
    assert np.abs(sol.du).max() < 1e-8 * 2e-3
    assert np.abs(sol.sigma - data.sigma_n).max() < 1e-6 * RHO * GRAV


def assert_resume_repeats(build, folder, steps: int = 2):
    """A run resumed from its checkpoint after ``steps`` repeats the clean one.

    ``build(folder)`` returns a fresh simulation, checkpointing every
    ``steps`` steps into ``folder`` (``build(None)``: none).  The first run
    stops after ``steps``; a second, restored from that checkpoint, runs
    ``steps`` more; a third runs ``2 steps`` uninterrupted.  Every record's
    ``extra`` and every particle array must agree to the bit.  Returns the
    uninterrupted simulation.
    """
    from skfem_npfem.io import checkpoint_path

    first = build(folder)
    first.run(steps=steps)
    resumed = build(None)
    resumed.restore(checkpoint_path(folder, steps))
    resumed.run(steps=steps)
    clean = build(None)
    clean.run(steps=2 * steps)
    assert [r.extra for r in resumed.records] == [r.extra for r in clean.records]
    for name, arr in clean.particles.arrays().items():
        np.testing.assert_array_equal(resumed.particles.arrays()[name], arr, name)
    return clean
