"""The cone in a heavy clay whose strength grows with depth (``rho``, ``su_gradient``).

Site investigation reads a cone with ``q_net = q_c - sigma_v0(z)`` and
``N_kt = q_net / s_u(z)`` at the tip's depth, assuming ``N_kt`` is the
weightless uniform cone factor at the same rigidity index.  With ``E``
proportional to ``s_u`` (the default ``stiffness_profile``) the rigidity
index is the same at every depth, and the weight is a hydrostatic-like field
that an isochoric Tresca mechanism does no work against.
"""

import math

import numpy as np
import pytest

from skfem_npfem import ParameterError
from skfem_npfem.constants import GRAVITY
from skfem_npfem.scenes import get_scene, run_scene
from skfem_npfem.scenes.footing.cone import cone_body
from skfem_npfem.scenes.footing.cone_geometry import sizes, soil_points
from skfem_npfem.scenes.footing.cone_ground import soil_volume, start_state

SCENE = "cone-penetration"
D = 0.0357
GROUND = {"rho": 1800.0, "su_gradient": 2.0e4}


def test_heavy_ground_starts_at_its_geostatic_state():
    # The particles carry the mass rho V of the soil round the embedded cone
    # (V: the cylinder less the shaft and the cone, 1e-12 relative), start
    # under sigma0 + rho g z, and their strength and stiffness factors are
    # s_u(z) / s_u0 (a uniform rigidity index).
    sc = get_scene(SCENE)
    values = sc.resolve({"spacing": D / 4, **GROUND})
    x, _ = soil_points(values, cone_body(values))
    p, _ = start_state(values, x)
    g = sizes(values)
    R = D / 2
    tall = R / math.tan(math.radians(30.0))
    V = math.pi * (
        g["radius"] ** 2 * g["top"]
        - R**2 * (g["top"] - g["z_tip"] - tall)
        - R**2 * tall / 3
    )
    assert soil_volume(g) == pytest.approx(V, rel=1e-12)
    assert p.mass.sum() == pytest.approx(1800.0 * V, rel=1e-12)
    z = g["top"] - p.x[:, 1]
    np.testing.assert_allclose(p.stress[:, 1], -(5e4 + 1800.0 * GRAVITY * z))
    np.testing.assert_allclose(p.strength, 1.0 + 2.0e4 * z / 1.0e4)
    np.testing.assert_array_equal(p.stiffness, p.strength)


def test_uniform_ground_reads_as_before():
    # No weight, no profile: N_kt is the cone factor (q_c - sigma0) / s_u and
    # q_net = N s_u at the tip's depth, step by step.
    m = run_scene(SCENE, {"spacing": D / 4, "penetration": D / 2})["metrics"]
    assert m["cone_factor_nkt"] == m["cone_factor"]
    depth0 = sizes(get_scene(SCENE).resolve({}))["depth"]
    for (w, n), (z, q_net, s_z) in zip(m["curve"], m["q_net"], strict=True):
        assert z == pytest.approx(depth0 + w * D, rel=1e-12)
        assert q_net == pytest.approx(n * 1.0e4, rel=1e-12)
        assert s_z == 1.0e4


@pytest.mark.parametrize(
    ("over", "name"),
    [
        ({"material": "mohr-coulomb", "rho": 1800.0}, "rho"),
        ({"drainage": "undrained", "su_gradient": 1e3}, "su_gradient"),
        ({"interface": "rough", "su_gradient": 1e3}, "interface"),
        ({"material": "mohr-coulomb", "sensitivity": 2.0}, "sensitivity"),
    ],
)
def test_ground_it_cannot_model_is_refused(over, name):
    sc = get_scene(SCENE)
    with pytest.raises(ParameterError, match=name):
        sc.build(sc.resolve({"spacing": D / 4, **over}))


@pytest.mark.slow
def test_nkt_in_heavy_ground_is_the_uniform_cone_factor():
    # D/8, half a spacing a step, 5 D; about 3 minutes each on a core of its
    # own.  s_u from 17.2 to 20.8 kPa over the push (su = 10 kPa at the
    # surface, k = 20 kPa/m), gamma = 17.7 kN/m^3.  Measured: N_kt 9.95
    # against the uniform N_c 9.92 (+0.3 %; 10.04 in a run whose factors
    # differed in the last bit); over w = 2..5 D the local q_net / s_u(z) is
    # within 2.6 % of the uniform curve's mean, while q_net / s_u0 is 2.0
    # times it (the strength ratio).
    over = {"spacing": D / 8, "dt": D / 16 / 0.02, "penetration": 5 * D}
    over["steady_window"] = 2.0
    uniform = run_scene(SCENE, over)["metrics"]
    ground = run_scene(SCENE, {**over, **GROUND})["metrics"]
    assert ground["cone_factor_nkt"] == pytest.approx(uniform["cone_factor"], rel=0.05)
    cu, cg = np.array(uniform["curve"]), np.array(ground["curve"])
    q = np.array(ground["q_net"])
    late_u, late_g = cu[:, 0] >= 2.0, cg[:, 0] >= 2.0
    n_uniform = cu[late_u, 1].mean()
    assert cg[late_g, 1].mean() == pytest.approx(n_uniform, rel=0.05)
    ratio = q[late_g, 1].mean() / 1.0e4 / n_uniform
    assert ratio == pytest.approx(q[late_g, 2].mean() / 1.0e4, rel=0.05)
