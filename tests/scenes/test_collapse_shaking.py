"""A column shaken pseudo-statically: ``kh`` on the collapse scene.

Reference: Newton's second law.  A column too strong to fail (c = 1 MPa)
against the smooth wall ``x = 0``, on a frictionless floor, under ``k_h``
times its weight along ``+x`` slides away from the wall as a rigid block with
acceleration ``a = k_h g``: its mass-weighted mean velocity is ``a t``, and
its displacement that of the scheme's velocity update (theta2 = 1:
``v_n = a t_n`` exactly, ``u_n = sum v_k dt = a t^2 (1 + dt / t) / 2``).
"""

from __future__ import annotations

import meshio
import numpy as np
import pytest

import skfem_npfem as npfem
from skfem_npfem import ParameterError
from skfem_npfem.scenes import get_scene

BLOCK = {
    "c": 1.0e6,
    "E": 1.0e8,
    "t_end": 0.3,
    "rest_fraction": 0.0,
    "floor_friction": 0.0,
    "spacing": 0.05,
}
G = 9.81


def mean_state(out) -> tuple[float, float]:
    """Mass-weighted mean x displacement and x velocity of the last VTU."""
    m = meshio.read(sorted(out.glob("result_*.vtu"))[-1])
    w = m.point_data["mass"]
    u, v = m.point_data["displacement"], m.point_data["velocity"]
    return float(w @ u[:, 0] / w.sum()), float(w @ v[:, 0] / w.sum())


def test_a_rigid_column_slides_at_kh_g(tmp_path):
    res = npfem.run_scene("column-collapse", {**BLOCK, "kh": 0.2}, out=tmp_path)
    t, dt = res["history"][-1]["time"], res["history"][-1]["dt"]
    a = 0.2 * G
    ux, vx = mean_state(tmp_path)
    # Measured: v within 1e-4, u within 1e-3 (an elastic ripple of the block).
    assert vx == pytest.approx(a * t, rel=2e-3)
    assert ux == pytest.approx(0.5 * a * t * t * (1 + dt / t), rel=5e-3)


def test_a_recorded_pulse_leaves_the_block_at_its_velocity(tmp_path):
    # k_h = 0.2 for 0.1 s, ramped over 0.02 s each way: the velocity gained is
    # g times the area under the pulse, 0.2 g (0.08 + 0.02) s, then it coasts.
    pulse = tmp_path / "pulse.csv"
    pulse.write_text("# t, kh\n0, 0\n0.02, 0.2\n0.1, 0.2\n0.12, 0\n")
    out = tmp_path / "run"
    npfem.run_scene("column-collapse", {**BLOCK, "kh": str(pulse)}, out=out)
    _, vx = mean_state(out)
    assert vx == pytest.approx(0.2 * G * 0.1, rel=5e-3)


@pytest.mark.parametrize("geometry", ["axisymmetric", "quarter-cylinder"])
def test_kh_is_refused_where_it_breaks_a_symmetry(geometry):
    sc = get_scene("column-collapse")
    with pytest.raises(ParameterError, match="kh"):
        sc.resolve({"geometry": geometry, "kh": 0.1})


def test_a_bad_kh_file_is_refused_when_resolved(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("0, 0\n0.1, 0.2\n0.05, 0\n")
    sc = get_scene("column-collapse")
    with pytest.raises(ParameterError, match="increasing t"):
        sc.resolve({"kh": str(bad)})
    assert np.isfinite(sc.resolve({"kh": 0.1})["kh"])
