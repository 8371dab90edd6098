"""The closed-form 2D stress rotation equals the general Cayley rotation.

Reference: ``rotate_stress`` in 3D (``R = (I - W/2)^-1 (I + W/2)`` by a 3x3
solve) of the same stresses and gradients embedded in 3D (no out-of-plane
gradient, zero out-of-plane shear): the in-plane result must agree to
round-off (1e-14 of the stress), ``zz`` must be untouched, and the rotation
must keep the in-plane invariants.
"""

from __future__ import annotations

import numpy as np

from skfem_npfem.step.kinematics import rotate_stress


def test_plane_rotation_equals_the_3d_cayley_rotation():
    rng = np.random.default_rng(3)
    n = 200
    grad = rng.normal(scale=0.3, size=(n, 2, 2))
    stress = rng.normal(scale=1e4, size=(n, 4))
    ours = rotate_stress(stress, grad)
    g3 = np.zeros((n, 3, 3))
    g3[:, :2, :2] = grad
    s6 = np.zeros((n, 6))
    s6[:, :4] = stress
    ref = rotate_stress(s6, g3)
    scale = np.abs(stress).max()
    np.testing.assert_allclose(ours, ref[:, :4], rtol=0, atol=1e-14 * scale)
    np.testing.assert_array_equal(ours[:, 2], stress[:, 2])
    assert np.allclose(ref[:, 4:], 0.0, atol=1e-14 * scale)
    tr = ours[:, 0] + ours[:, 1]
    det = ours[:, 0] * ours[:, 1] - ours[:, 3] ** 2
    np.testing.assert_allclose(tr, stress[:, 0] + stress[:, 1], atol=1e-11 * scale)
    det0 = stress[:, 0] * stress[:, 1] - stress[:, 3] ** 2
    np.testing.assert_allclose(det, det0, atol=1e-11 * scale**2)
