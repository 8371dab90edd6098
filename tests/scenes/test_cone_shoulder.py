"""The cone's rounded shoulder (``shoulder_round``).

The corner where the 60-degree face meets the shaft turns the soil's flow by
30 degrees; ``shoulder_round = k`` replaces it by an arc of radius ``k``
spacings tangent to both, a regularisation that vanishes with the spacing.
"""

import math

import numpy as np
import pytest

from skfem_npfem import ParameterError
from skfem_npfem.scenes import get_scene, run_scene
from skfem_npfem.scenes.footing.cone import cone_body
from skfem_npfem.scenes.footing.cone_geometry import sizes, soil_points
from skfem_npfem.scenes.footing.cone_ground import soil_volume

SCENE = "cone-penetration"
D = 0.0357
R = D / 2
TAN15 = math.tan(math.radians(15.0))


def _values(**extra):
    return get_scene(SCENE).resolve({"spacing": D / 4, **extra})


def test_a_sharp_shoulder_is_the_standard_cones_four_corners():
    body = cone_body(_values())
    z_tip = sizes(_values())["z_tip"]
    np.testing.assert_allclose(
        body.vertices[:2], [[0.0, z_tip], [R, z_tip + R * math.sqrt(3.0)]]
    )
    assert body.vertices.shape == (4, 2)


def test_the_rounded_shoulder_is_an_arc_tangent_to_the_face_and_the_shaft():
    values = _values(shoulder_round=2.0, interface="rough")
    g = sizes(values)
    r = 2.0 * D / 4
    body = cone_body(values)
    corner = np.array([R, g["z_tip"] + R * math.sqrt(3.0)])
    arc = body.vertices[1:-2]
    # The tangent points: r tan(15 deg) from the corner along the face (30
    # degrees off the vertical) and up the shaft.
    face = np.array([0.5, math.sqrt(3.0) / 2])
    np.testing.assert_allclose(arc[0], corner - r * TAN15 * face, atol=1e-15)
    np.testing.assert_allclose(arc[-1], corner + np.array([0.0, r * TAN15]), atol=1e-15)
    # All on one circle of radius r whose centre is r from both lines.
    centre = arc[-1] - np.array([r, 0.0])
    np.testing.assert_allclose(np.linalg.norm(arc - centre, axis=1), r, rtol=1e-12)
    # Four chords of 7.5 degrees: the outline turns by half a chord's angle at
    # the tangent points and a whole one between, 30 degrees in all.
    t = np.diff(body.vertices[[0, *range(1, arc.shape[0] + 2)]], axis=0)
    ang = np.degrees(np.arctan2(t[:, 0], t[:, 1]))
    np.testing.assert_allclose(-np.diff(ang), [3.75, 7.5, 7.5, 7.5, 3.75], atol=1e-9)
    # The face's adhesion covers the arc; the shaft stays smooth.
    assert body.adhesion.tolist() == [1.0e4] * 5 + [0.0] * 3


def test_the_rounded_cone_starts_in_contact_and_its_soil_volume_gains_the_ring():
    values = _values(shoulder_round=3.0)
    g = sizes(values)
    body = cone_body(values)
    x, _ = soil_points(values, body)
    d, _, _ = body.signed_distance(x, 0.0)
    assert d.min() > -1e-12 * D
    assert np.sum(np.abs(d) < 1e-12 * D) >= 10  # the face, the arc, the shaft
    # The ring between the arc and the sharp corner, revolved: a fan of
    # triangles from the corner, each by Pappus (area x 2 pi x centroid's r).
    corner = np.array([R, g["z_tip"] + R * math.sqrt(3.0)])
    arc = body.vertices[1:-2]
    a, b = arc[:-1] - corner, arc[1:] - corner
    area = 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    centroid_r = (corner[0] + arc[:-1, 0] + arc[1:, 0]) / 3
    ring = float(np.sum(2 * math.pi * centroid_r * area))
    sharp = soil_volume(sizes(_values()))
    assert soil_volume(g) - sharp == pytest.approx(ring, rel=1e-6)
    # The fan's area: the exact arc's r^2 (tan 15 - pi/12) plus the four
    # circular segments its chords cut off, r^2 (t - sin t) / 2 each (t = pi/24).
    r, t = 3.0 * D / 4, math.pi / 24
    exact = r**2 * (TAN15 - math.pi / 12) + 2 * r**2 * (t - math.sin(t))
    assert area.sum() == pytest.approx(exact, rel=1e-9)


@pytest.mark.parametrize("value", [-1.0, 4.5])
def test_a_radius_out_of_range_is_refused(value):
    with pytest.raises(ParameterError, match="shoulder_round"):
        run_scene(SCENE, {"spacing": D / 4, "shoulder_round": value})


@pytest.mark.slow  # 5 min: 96 steps of a 4 000-particle cone
def test_a_rounded_shoulder_brings_the_steady_cones_mean_to_its_median():
    # At D/8, pushed 6 D, with steps of 0.45, 0.5 and 0.55 spacings, the
    # sharp cone's mean over the last diameter was 1.1-1.3 % off its median
    # and rounded to two spacings 0.03-0.62 %; the largest one-step fall in
    # the last two diameters 19-26 % of their mean sharp, 8-20 % rounded
    # (docs/validation/cone_penetration.md): no fall of a third, no collapse
    # of the tip resistance for a step.  Teh & Houlsby's 9.72 and Lu et al.'s
    # 10.77 bracket N_c at I_r = 100.
    m = run_scene(SCENE, {"spacing": D / 8, "shoulder_round": 2.0})["metrics"]
    c = np.asarray(m["curve"])
    last = c[:, 0] > c[-1, 0] - 2.0
    falls = np.maximum(c[:-1, 1] - c[1:, 1], 0.0)[last[1:]]
    mean = float(np.mean(c[last, 1]))
    assert falls.max() < 0.3 * mean
    assert m["cone_factor_mean"] == pytest.approx(m["cone_factor"], rel=0.01)
    assert 0.97 * 9.72 < m["cone_factor"] < 1.03 * 10.77


def test_the_pictures_draw_the_rounded_cone_and_a_sharp_run_records_as_before():
    from skfem_npfem.scenes.footing.cone import cone_scenery
    from skfem_npfem.scenes.footing.penetration_soil import penetration_parameters

    values = _values(shoulder_round=2.0)
    recorded = penetration_parameters(values)
    outline, _, name = cone_scenery(recorded).bodies[0]
    assert name == "cone"
    np.testing.assert_allclose(outline, cone_body(values).vertices, rtol=1e-12)
    assert recorded["shoulder_round"] == 2.0
    assert "shoulder_round" not in penetration_parameters(_values())
