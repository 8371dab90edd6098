"""Moving rigid bodies in 3D: planes and bodies of revolution.

Known answers:

* the distance to a plane, a cylinder and a sphere (closed form);
* a smooth rigid plane pushed down on a block with rollers on its sides puts
  it in uniaxial strain: the force is ``M eps A`` with the constrained
  modulus ``M = E (1 - nu) / ((1 + nu) (1 - 2 nu))``;
* a sphere pressed into a quarter block with two symmetry planes takes four
  times less force than the whole block, which the axisymmetric 2D model
  computes on its own code path (polygon outline, ring integration);
* a block on a rough plane moving under it slides at ``mu g`` (as the 2D
  belt of test_bodies.py);
* a run resumed from a checkpoint repeats the uninterrupted one bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import assert_resume_repeats
from skfem import MeshTet, MeshTri

import skfem_npfem as npfem
from skfem_npfem import BodyOfRevolution, ParameterError, RigidPlane
from skfem_npfem.boundary import boundary_faces, face_tributary, spanning_tetrahedra

E, NU, RHO, G = 1e6, 0.3, 1800.0, 9.81


# --- geometry ----------------------------------------------------------------
def test_distances_to_a_cylinder_and_a_sphere():
    # A punch of radius 0.2, its axis along (1, 1, 0) through (1, 0, 0).
    e = np.array([1.0, 1.0, 0.0]) / math.sqrt(2.0)
    punch = BodyOfRevolution.cylinder([1.0, 0.0, 0.0], 0.2, 1.0, axis=[2.0, 2.0, 0.0])
    side = np.array([0.0, 0.0, 1.0])
    x = np.array(
        [
            [1.0, 0.0, 0.0] + 0.5 * e + 0.5 * side,  # 0.3 outside the side
            [1.0, 0.0, 0.0] - 0.1 * e + 0.1 * side,  # 0.1 below the base
            [1.0, 0.0, 0.0] + 0.5 * e + 0.05 * side,  # inside, 0.15 to the side
            [1.0, 0.0, 0.0] + 0.05 * e,  # on the axis, 0.05 above the base
        ]
    )
    dist, n, closest = punch.signed_distance(x, 0.0)
    assert dist.tolist() == pytest.approx([0.3, 0.1, -0.15, -0.05])
    assert n[0].tolist() == pytest.approx(side.tolist())
    assert n[1].tolist() == pytest.approx((-e).tolist())
    assert n[2].tolist() == pytest.approx(side.tolist())
    assert n[3].tolist() == pytest.approx((-e).tolist())  # the base, not the axis
    assert closest[0].tolist() == pytest.approx(x[0] - 0.3 * side)
    # the body moves: at t = 2 it has gone 0.2 along -e
    moving = BodyOfRevolution.cylinder(
        [1.0, 0.0, 0.0], 0.2, 1.0, axis=e, velocity=-0.1 * e
    )
    assert moving.signed_distance(x[1:2], 2.0)[0][0] == pytest.approx(-0.1)
    # A sphere of 64 chords: within R (1 - cos(pi / 128)) = 3e-4 R of exact.
    ball = BodyOfRevolution.sphere([0.0, 0.0, 1.0], 0.5, segments=64)
    rng = np.random.default_rng(1)
    pts = rng.uniform(-1.0, 1.0, (200, 3)) + np.array([0.0, 0.0, 1.0])
    d, n, _ = ball.signed_distance(pts, 0.0)
    r = np.linalg.norm(pts - [0.0, 0.0, 1.0], axis=1)
    assert np.abs(d - (r - 0.5)).max() < 0.5 * (1 - math.cos(math.pi / 128)) + 1e-12
    radial = (pts - [0.0, 0.0, 1.0]) / r[:, None]
    assert np.einsum("nd,nd->n", n, radial).min() > math.cos(math.pi / 64)


def test_plane_distance_bounds_and_contact_area():
    lid = RigidPlane([0.0, 0.0, 1.0], [0.0, 0.0, -3.0], velocity=[0.0, 0.0, -0.5])
    x = np.array([[0.2, 0.7, 0.25], [5.0, -3.0, 1.5]])
    d, n, c = lid.signed_distance(x, 0.5)
    assert d.tolist() == pytest.approx([0.5, -0.75])
    assert np.all(n == [0.0, 0.0, -1.0])
    assert c[:, 2].tolist() == pytest.approx([0.75, 0.75])
    assert lid.contains(x, 0.5).tolist() == [False, True]
    # A unit cube of tetrahedra: its six faces, 6 m^2; the top face's nodes
    # carry 1 m^2 projected on a horizontal plane, the side faces nothing.
    mesh = MeshTet.init_tensor(*3 * [np.linspace(0.0, 1.0, 3)])
    faces = boundary_faces(mesh.t)
    assert face_tributary(mesh.p.T, faces).sum() == pytest.approx(6.0)
    up = np.tile([0.0, 0.0, 1.0], (mesh.p.shape[1], 1))
    area = face_tributary(mesh.p.T, faces, up)
    top = np.isclose(mesh.p[2], 1.0)
    bottom = np.isclose(mesh.p[2], 0.0)
    assert area[top].sum() == pytest.approx(1.0)
    assert area[bottom].sum() == pytest.approx(1.0)
    assert np.all(area[~top & ~bottom] == 0.0)


def test_spanning_tetrahedra():
    # One tetrahedron over a small sphere in its middle (all nodes outside),
    # one beside it.
    x = np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [3, 0, 0], [4, 0, 0], [3, 1, 0]],
        float,
    )
    x = np.vstack([x, [3.0, 0.0, 1.0]])
    t = np.array([[0, 1, 2, 3], [4, 5, 6, 7]]).T
    ball = BodyOfRevolution.sphere([0.25, 0.25, 0.25], 0.2)
    assert spanning_tetrahedra([ball], x, t, 0.0).tolist() == [True, False]
    # a plane under both, and one cutting the first only
    below = RigidPlane([0.0, 0.0, -0.1], [0.0, 0.0, 1.0])
    assert spanning_tetrahedra([below], x, t, 0.0).tolist() == [False, False]
    cut = RigidPlane([0.5, 0.0, 0.0], [1.0, 0.0, 0.0])
    assert spanning_tetrahedra([cut], x, t, 0.0).tolist() == [True, False]


def test_a_node_on_a_punch_rim_takes_the_face_that_moves_onto_it():
    # As in 2D: the bisector would let it slide off the rim diagonally.
    x = np.array([[0.0, 0.2, 1.0]])  # on the rim of the base, at y = r
    bisector = np.array([[0.0, 0.5**0.5, -(0.5**0.5)]])
    for velocity, face in (
        ([0.0, 0.0, -1.0], [0.0, 0.0, -1.0]),  # pushed down: the base
        ([0.0, 1.0, 0.0], [0.0, 1.0, 0.0]),  # towards +y: the side
        ([0.0, 0.0, 0.0], bisector[0]),  # at rest: the bisector
    ):
        punch = BodyOfRevolution.cylinder([0, 0, 1.0], 0.2, 0.5, velocity=velocity)
        d, n, _ = punch.signed_distance(x, 0.0)
        assert d[0] == pytest.approx(0.0, abs=1e-12)
        assert n[0].tolist() == pytest.approx(bisector[0].tolist())
        assert punch.corner_normals(x, n, 0.0)[0].tolist() == pytest.approx(face)


def test_particles_inside_a_3d_body_at_the_start_are_refused():
    mesh = MeshTet.init_tensor(*3 * [np.linspace(0.0, 1.0, 3)])
    soil = npfem.LinearElastic(E, NU, RHO)
    p = npfem.Particles.from_mesh(mesh, soil)
    pile = BodyOfRevolution.cylinder([0.5, 0.5, 0.4], 0.1, 2.0, name="pile")
    model = npfem.Model(dim=3, materials=[soil], bodies=[pile], mode="static")
    with pytest.raises(ParameterError) as info:
        npfem.Simulation(p, model, mesh, 0.1)
    # the node at (0.5, 0.5, 0.5) and the one at (0.5, 0.5, 1.0)
    assert "pile" in str(info.value) and "2 particle(s) inside" in str(info.value)


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: BodyOfRevolution([[0, 0], [1, 0], [1, 1]], axis=[0, 0, 0]), "axis"),
        (lambda: BodyOfRevolution([[-0.1, 0], [1, 0], [1, 1]]), "profile"),
        (lambda: BodyOfRevolution([[0, 0], [1, 0], [2, 0]]), "profile"),
        (lambda: BodyOfRevolution([[0, 0, 0], [1, 0, 0], [1, 1, 0]]), "profile"),
        (
            lambda: BodyOfRevolution([[0, 0], [1, 0], [1, 1]], velocity=[0, -1]),
            "velocity",
        ),
        (lambda: BodyOfRevolution.cylinder([0, 0, 0], 0.0, 1.0), "radius"),
        (lambda: BodyOfRevolution.sphere([0, 0, 0], 1.0, segments=2), "segments"),
        (lambda: BodyOfRevolution.sphere([0, 0], 1.0), "axis_point"),
        (lambda: RigidPlane([0, 0, 0], [0, 0, 0]), "normal"),
        (
            lambda: RigidPlane([0, 0, 0], [0, 0, 1], friction_angle=90.0),
            "friction_angle",
        ),
        (
            lambda: RigidPlane([0, 0, 0], [0, 0, 1], adhesion=1.0, friction_angle=5.0),
            "adhesion",
        ),
        (lambda: RigidPlane([0, 0, 0], [0, 0, 1], name="a plane"), "name"),
    ],
)
def test_bad_3d_bodies_are_refused(make, name):
    with pytest.raises(ParameterError) as info:
        make()
    assert info.value.name == name and "\n" not in str(info.value)


def test_bodies_must_match_the_model_dimension():
    soil = npfem.LinearElastic(E, NU, RHO)
    plane = RigidPlane([0, 0, 0], [0, 0, 1])
    with pytest.raises(ParameterError, match="RigidBody polygon in 2D"):
        npfem.Model(dim=2, materials=[soil], bodies=[plane])
    with pytest.raises(ParameterError, match="distinct names"):
        npfem.Model(
            dim=3, materials=[soil], bodies=[plane, RigidPlane([0, 0, 1], [0, 0, 1])]
        )
    assert npfem.Model(dim=3, materials=[soil], bodies=plane).bodies == [plane]


# --- a plate on a confined block ---------------------------------------------
def _block(L, H, h):
    """Particles of an L x L x H block on a fixed base, rollers on the sides."""
    n, m = round(L / h) + 1, round(H / h) + 1
    mesh = MeshTet.init_tensor(
        np.linspace(0, L, n), np.linspace(0, L, n), np.linspace(0, H, m)
    )
    x = mesh.p.T
    fixed = np.zeros_like(x, dtype=bool)
    fixed[np.isclose(x[:, 2], 0.0)] = True
    for k in (0, 1):
        fixed[np.isclose(x[:, k], 0.0) | np.isclose(x[:, k], L), k] = True
    return mesh, fixed


def test_plate_on_a_confined_block_takes_M_eps_A():
    L, H, h, delta = 0.4, 0.3, 0.1, 0.01
    mesh, fixed = _block(L, H, h)
    soil = npfem.LinearElastic(E, NU, RHO)
    plate = RigidPlane(
        [0.0, 0.0, H], [0.0, 0.0, -1.0], velocity=[0.0, 0.0, -delta], name="plate"
    )
    model = npfem.Model(
        dim=3, materials=[soil], bodies=[plate], mode="static", gravity=0.0
    )
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    sim = npfem.Simulation(p, model, mesh, dt=1.0, progress=False)
    rec = sim.run(steps=1)[-1]
    M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))
    exact = M * delta / H * L * L
    # measured 1.6e-10: the solver's tolerance
    assert rec.extra["plate_force_z"] == pytest.approx(exact, rel=1e-6)
    assert abs(rec.extra["plate_force_x"]) < 1e-8 * exact
    assert abs(rec.extra["plate_force_y"]) < 1e-8 * exact
    assert rec.extra["plate_z"] == pytest.approx(-delta)
    assert rec.extra["plate_penetration"] == pytest.approx(0.0, abs=1e-9 * H)
    # the resultant acts at the middle of the top face: the moment about the
    # plate's reference point (0, 0, H) is (L/2 F, -L/2 F, 0)
    assert rec.extra["plate_moment_x"] == pytest.approx(0.5 * L * exact, rel=1e-6)
    assert rec.extra["plate_moment_y"] == pytest.approx(-0.5 * L * exact, rel=1e-6)
    top = np.isclose(mesh.p[2], H)
    assert sim.particles.u[top, 2] == pytest.approx(-delta, abs=1e-9)


# --- a sphere pressed into a quarter block -----------------------------------
RS, RB, DEPTH, SPACING = 1.0, 0.75, 0.75, 0.075


def _quarter_sphere(delta, steps, mesher, checkpoint=None, spacing=SPACING):
    """A sphere of radius RS pressed by ``delta`` into a quarter block."""
    mesh, fixed = _block(RB, DEPTH, spacing)
    soil = npfem.LinearElastic(E, NU, RHO)
    ball = BodyOfRevolution.sphere(
        [0.0, 0.0, DEPTH + RS],
        RS,
        segments=64,
        velocity=[0.0, 0.0, -delta / steps],
        name="ball",
    )
    model = npfem.Model(
        dim=3, materials=[soil], bodies=[ball], mode="static", gravity=0.0
    )
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    source = npfem.AlphaShapeMesher(h=spacing, alpha=1.3) if mesher else mesh
    steps_seen = []
    sim = npfem.Simulation(
        p,
        model,
        source,
        dt=1.0,
        progress=False,
        callbacks=[lambda s, new, step: steps_seen.append((s.time, new, step))],
        checkpoint_dir=checkpoint,
        checkpoint_every=1 if checkpoint else 0,
    )
    return sim, ball, steps_seen


def _axisymmetric_sphere(delta, steps=1):
    """The same problem as the (r, z) half-section of a cylinder of radius RB."""
    n = round(RB / SPACING) + 1
    mesh = MeshTri.init_tensor(np.linspace(0, RB, n), np.linspace(0, DEPTH, n))
    x = mesh.p.T
    fixed = np.zeros_like(x, bool)
    fixed[np.isclose(x[:, 1], 0.0)] = True
    fixed[np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], RB), 0] = True
    a = np.linspace(-0.5 * math.pi, 0.5 * math.pi, 65)
    outline = np.column_stack([RS * np.cos(a), DEPTH + RS + RS * np.sin(a)])
    outline[[0, -1], 0] = 0.0
    ball = npfem.RigidBody(outline, velocity=[0.0, -delta / steps], name="ball")
    soil = npfem.LinearElastic(E, NU, RHO)
    model = npfem.Model(
        dim=2,
        materials=[soil],
        bodies=[ball],
        mode="static",
        gravity=0.0,
        axisymmetric=True,
    )
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed, axisymmetric=True)
    sim = npfem.Simulation(p, model, mesh, dt=1.0, progress=False)
    return sim.run(steps=steps)[-1].extra["ball_force_y"]


def test_axisymmetric_sphere_force_does_not_depend_on_the_steps():
    """Frictionless elastic contact is path-independent: the same force.

    The sphere is a polygon of 64 sides; the nodes under it sit on its
    faces, and an element edge joining two of them is a chord that cuts a
    sliver off the polygon.  Those elements stay (docs/theory.md, "Moving
    rigid bodies"): measured 1.0006, 0.9993 and 0.9977 times the one-step
    force in 2, 4 and 8 steps (0.62 in four when they were dropped).
    """
    one = _axisymmetric_sphere(0.04)
    assert _axisymmetric_sphere(0.04, steps=4) == pytest.approx(one, rel=0.01)


def test_sphere_in_a_quarter_block_matches_the_axisymmetric_model():
    """Four times the quarter's force against the ring model, same spacing.

    Measured at an indentation of 4 % of the radius (contact radius about
    2.7 spacings), 3D against axisymmetric: -5.0 % at this spacing (-1.2 %
    at 0.1 m, -1.9 % at 0.05 m).  The square quarter block has rollers where
    the ring model's cylinder has its outer wall, 0.75 m from the axis
    against a contact radius of 0.2 m.  The axisymmetric force converges to
    +4.6 % above this spacing's value at a sixth of it.
    """
    delta = 0.04
    sim, _, _ = _quarter_sphere(delta, steps=1, mesher=False)
    rec = sim.run(steps=1)[-1]
    force = 4.0 * rec.extra["ball_force_z"]
    reference = _axisymmetric_sphere(delta)
    assert force == pytest.approx(reference, rel=0.08)
    # both above Hertz's half-space force (measured 1.23 times: a layer
    # of finite depth on a fixed base is stiffer)
    hertz = 4.0 / 3.0 * E / (1 - NU**2) * math.sqrt(RS) * delta**1.5
    assert 1.0 < force / hertz < 1.6
    assert rec.extra["ball_penetration"] == 0.0


def test_remeshed_sphere_run_keeps_particles_and_elements_out():
    delta, steps = 0.06, 3
    sim, ball, seen = _quarter_sphere(delta, steps=steps, mesher=True)
    x0 = sim.particles.x.copy()
    records = sim.run(steps=steps)
    assert {r.status for r in records} <= {"Solved", "AlmostSolved"}
    assert records[-1].extra["ball_z"] == pytest.approx(-delta)
    assert all(r.extra["ball_force_z"] > 0 for r in records)
    # Particles: none inside the (exact) sphere deeper than the chords' sag
    # and the solver's tolerance; the record's worst penetration at most
    # half a spacing (measured 0).
    centre = np.array([0.0, 0.0, DEPTH + RS - delta])
    r = np.linalg.norm(sim.particles.x - centre, axis=1)
    assert r.min() > RS * math.cos(math.pi / 128) - 1e-6
    assert max(rec.extra["ball_penetration"] for rec in records) <= 0.5 * SPACING
    # Elements: no tetrahedron of a step's mesh (on the particles where the
    # step started) has its centroid inside the sphere where the step
    # started, deeper than a tenth of a spacing (a face between nodes on the
    # sphere cuts into it by its sagitta).
    starts = [x0] + [new.x for _, new, _ in seen[:-1]]
    for k, ((_, _, step), x) in enumerate(zip(seen, starts, strict=True)):
        centroid = x[step.active][step.local_t].mean(axis=0)
        centre = np.array([0.0, 0.0, DEPTH + RS]) + ball.displacement(float(k))
        depth = RS - np.linalg.norm(centroid - centre, axis=1)
        assert depth.max() < 0.1 * SPACING


# --- interface laws ----------------------------------------------------------
def _carried_block(phi=0.0, adhesion=0.0, V=1.0, dt=2.5e-3, t_end=0.05):
    """An L x L x H elastic block on a plane moving at V along x under it."""
    L, H, h = 0.2, 0.1, 0.05
    n, m = round(L / h) + 1, round(H / h) + 1
    mesh = MeshTet.init_tensor(
        np.linspace(0, L, n), np.linspace(0, L, n), np.linspace(0, H, m)
    )
    x = mesh.p.T
    mass = RHO * npfem.nodal_integration(mesh).volumes
    belt = RigidPlane(
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        velocity=[V, 0.0, 0.0],
        friction_angle=phi,
        adhesion=adhesion,
        name="belt",
    )
    # The weight as the lagged normal force of the first step, by tributary area.
    up = np.tile([0.0, 0.0, 1.0], (x.shape[0], 1))
    area = face_tributary(x, boundary_faces(mesh.t), up)
    base = np.isclose(x[:, 2], 0.0)
    lagged = np.zeros((x.shape[0], 1))
    lagged[base, 0] = mass.sum() * G * area[base] / area[base].sum()
    p = npfem.Particles.create(x, mass).replace(wall_force=lagged)
    model = npfem.Model(
        dim=3,
        materials=[npfem.LinearElastic(1e7, NU, RHO)],
        mode="dynamic",
        bodies=[belt],
    )
    sim = npfem.Simulation(p, model, mesh, dt, progress=False)
    records = sim.run(t_end=t_end)
    return {
        "s": float(sim.particles.u[:, 0] @ mass / mass.sum()),
        "t": sim.time,
        "mass": float(mass.sum()),
        "area": L * L,
        "last": records[-1].extra,
        "penetration": max(r.extra["belt_penetration"] for r in records),
    }


def test_coulomb_plane_drags_block_at_mu_g():
    """A block on a rough plane moving under it: slip at mu g (lagged normal)."""
    dt, phi = 2.5e-3, 20.0
    r = _carried_block(phi=phi, dt=dt)
    mu = math.tan(math.radians(phi))
    t = r["t"]
    # backward Euler: a t (t + dt) / 2 while it slips (test_bodies.py);
    # measured -4.7e-4
    assert r["s"] == pytest.approx(0.5 * mu * G * t * (t + dt), rel=2e-3)
    weight = r["mass"] * G
    assert r["last"]["belt_force_x"] == pytest.approx(-mu * weight, rel=1e-6)
    assert r["last"]["belt_force_z"] == pytest.approx(-weight, rel=1e-6)
    assert abs(r["last"]["belt_force_y"]) < 1e-6 * weight
    assert r["penetration"] == 0.0


def test_adhesion_plane_drags_block_at_a_A_over_m():
    """Tresca adhesion: the bound is the strength times the contact area."""
    dt, adhesion = 2.5e-3, 500.0
    r = _carried_block(adhesion=adhesion, V=5.0, dt=dt)
    a = adhesion * r["area"] / r["mass"]
    t = r["t"]
    # The lagged normal force given to the first step marks the base nodes
    # in contact from the start: backward Euler, a t (t + dt) / 2 (measured
    # +1.2e-4; the force +1.4e-4: the base strains elastically).
    assert r["s"] == pytest.approx(0.5 * a * t * (t + dt), rel=2e-3)
    assert r["last"]["belt_force_x"] == pytest.approx(-adhesion * r["area"], rel=1e-3)


# --- resume ------------------------------------------------------------------
def test_resumed_run_with_a_3d_body_repeats_the_uninterrupted_one(tmp_path):
    # The body's position is a function of the time, which checkpoints keep
    # with the lagged contact forces (Particles.wall_force).
    args = {"delta": 0.06, "steps": 4, "mesher": True, "spacing": 0.125}
    clean = assert_resume_repeats(
        lambda folder: _quarter_sphere(**args, checkpoint=folder)[0], tmp_path
    )
    assert clean.records[-1].extra["ball_force_z"] > 0.0
    assert clean.records[-1].extra["ball_z"] == pytest.approx(-0.06)
