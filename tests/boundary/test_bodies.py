"""Moving rigid bodies: geometry, unilateral contact, adhesion, lagged Coulomb.

Known answers:

* a block on a belt (a rigid body moving at ``V``) with Coulomb friction
  accelerates at ``mu g`` until it moves with the belt; the belt takes the
  friction force ``mu W`` while the block slips and none after;
* with Tresca adhesion ``a`` (no friction) it accelerates at ``a L / m``
  whatever its weight;
* a body moving away from soil takes no force and moves no particle
  (unilateral contact).

Backward Euler moves a uniformly accelerated body by ``a t (t + dt) / 2``
after ``t / dt`` steps: the ``dt / t`` part of the difference to
``a t^2 / 2`` is the time discretisation (as in test_contact.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from skfem import MeshTri

import skfem_npfem as npfem
from skfem_npfem import ParameterError, RigidBody
from skfem_npfem.boundary import (
    body_contacts,
    boundary_tributary,
    corner_contacts,
    oriented_boundary,
    spanning_elements,
)

G = 9.81
RHO = 2000.0
SQUARE = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]


def _soil_block():
    """A 1 m elastic square, 0.25 m lattice, on a fixed base: mesh, soil, particles."""
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 1, 5))
    soil = npfem.LinearElastic(1e6, 0.3, 1.0)
    fixed = np.zeros((mesh.p.shape[1], 2), bool)
    fixed[np.isclose(mesh.p[1], 0.0)] = True
    return mesh, soil, npfem.Particles.from_mesh(mesh, soil, fixed=fixed)


# --- geometry ----------------------------------------------------------------
def test_signed_distance_and_normals():
    body = RigidBody(SQUARE[::-1], velocity=[0.0, -1.0])  # clockwise: reordered
    x = np.array([[0.5, -0.25], [1.5, 0.5], [0.5, 0.75], [2.0, -1.0], [1.0, 0.0]])
    dist, n, closest = body.signed_distance(x, 0.0)
    assert dist[:3].tolist() == pytest.approx([0.25, 0.5, -0.25])
    assert dist[3] == pytest.approx(math.sqrt(2.0))  # outside the corner
    assert n[0].tolist() == pytest.approx([0.0, -1.0])
    assert n[1].tolist() == pytest.approx([1.0, 0.0])
    assert n[2].tolist() == pytest.approx([0.0, 1.0])  # nearest edge, outward
    assert n[3].tolist() == pytest.approx([0.5**0.5, -(0.5**0.5)])
    assert n[4].tolist() == pytest.approx([0.5**0.5, -(0.5**0.5)])  # on a corner
    # the body moves: at t = 1 it is one metre lower
    assert body.signed_distance(x[:1], 1.0)[0][0] == pytest.approx(-0.25)
    assert closest[1].tolist() == pytest.approx([1.0, 0.5])


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"vertices": [[0, 0], [1, 0]]}, "vertices"),
        ({"vertices": [[0, 0], [1, 0], [2, 0]]}, "vertices"),
        ({"vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]}, "vertices"),
        ({"vertices": SQUARE, "velocity": [1.0, np.nan]}, "velocity"),
        ({"vertices": SQUARE, "friction_angle": 90.0}, "friction_angle"),
        ({"vertices": SQUARE, "adhesion": -1.0}, "adhesion"),
        ({"vertices": SQUARE, "adhesion": 1.0, "friction_angle": 10.0}, "adhesion"),
        ({"vertices": SQUARE, "name": "my body"}, "name"),
    ],
)
def test_bad_bodies_are_refused(kwargs, name):
    with pytest.raises(ParameterError) as info:
        RigidBody(**kwargs)
    assert info.value.name == name and "\n" not in str(info.value)


def test_bodies_need_a_2d_model_and_distinct_names():
    soil = npfem.LinearElastic(1e6, 0.3, 1.0)
    body = RigidBody(SQUARE)
    with pytest.raises(ParameterError, match="2D models"):
        npfem.Model(dim=3, materials=[soil], bodies=[body])
    with pytest.raises(ParameterError, match="distinct names"):
        npfem.Model(dim=2, materials=[soil], bodies=[body, RigidBody(SQUARE)])


def test_spanning_elements_thin_body_and_tributary():
    # Two triangles over a thin vertical blade at x = 0.5 (all nodes outside it).
    x = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.0]])
    t = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 2]]).T
    blade = RigidBody([[0.49, 0.2], [0.51, 0.2], [0.51, 0.21], [0.49, 0.21]])
    assert spanning_elements([blade], x, t, 0.0).tolist() == [True, False, False]
    # contact areas: half the boundary edges at each node (perimeter 4 + sqrt 2)
    area = boundary_tributary(x, oriented_boundary(x, t))
    assert area.sum() == pytest.approx(4.0 + math.sqrt(2.0))
    assert area[3] == pytest.approx(1.0)


def test_spanning_elements_keep_a_sliver_at_a_corner_only():
    # Nodes on the two faces at the corner (1, 1) of the unit square: the
    # edge joining them cuts the corner 0.141 deep, under 0.3 of the
    # element's mean edge (0.17); nodes 0.6 from the corner cut it 0.42 deep.
    body = RigidBody([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    x = np.array([[0.8, 1.0], [1.0, 0.8], [1.5, 1.5], [0.4, 1.0], [1.0, 0.4]])
    t = np.array([[0, 1, 2], [3, 4, 2]]).T
    assert spanning_elements([body], x, t, 0.0).tolist() == [False, True]
    assert spanning_elements([body], x, t, 0.0, sliver=0.0).tolist() == [True, True]
    # an edge from a face node to a soil node off the body crosses the other
    # face: the corner 0.014 from it (kept), or 0.42 (dropped: 0.3 of the
    # element's mean edge is 0.33)
    x = np.array([[0.8, 1.0], [1.5, 0.95], [1.5, 1.5], [0.2, 1.0], [1.5, 0.2]])
    x = np.vstack([x, [1.1, 1.1]])
    t = np.array([[0, 1, 2], [3, 4, 5]]).T
    assert spanning_elements([body], x, t, 0.0).tolist() == [False, True]


def test_particles_inside_a_body_at_the_start_are_refused():
    mesh = MeshTri.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 1, 3))
    soil = npfem.LinearElastic(1e6, 0.3, 1.0)
    p = npfem.Particles.from_mesh(mesh, soil)
    body = RigidBody([[0.4, 0.4], [0.6, 0.4], [0.6, 2.0], [0.4, 2.0]], name="pile")
    model = npfem.Model(dim=2, materials=[soil], bodies=[body], mode="static")
    with pytest.raises(ParameterError) as info:
        npfem.Simulation(p, model, mesh, 0.1)
    assert "pile" in str(info.value) and "2 particle(s) inside" in str(info.value)


# --- contact -----------------------------------------------------------------
def _belt(V, *, phi=0.0, adhesion=0.0, dt=2.5e-3, t_end=0.2, h=0.025, E=1e7):
    """An L x H elastic block resting on a belt moving at V along x."""
    L, H = 0.2, 0.1
    mesh = MeshTri.init_tensor(
        np.linspace(0, L, round(L / h) + 1), np.linspace(0, H, round(H / h) + 1)
    )
    mass = RHO * npfem.nodal_integration(mesh).volumes
    x = mesh.p.T
    belt = RigidBody(
        [[-5.0, -0.1], [5.0, -0.1], [5.0, 0.0], [-5.0, 0.0]],
        velocity=[V, 0.0],
        friction_angle=phi,
        adhesion=adhesion,
        name="belt",
    )
    # Lagged normal force of the first step: the weight, by tributary length.
    base = np.flatnonzero(np.isclose(x[:, 1], 0.0))
    share = np.full(base.size, h)
    share[[0, -1]] = h / 2
    lagged = np.zeros((x.shape[0], 1))
    lagged[base, 0] = mass.sum() * G * share / share.sum()
    p = npfem.Particles.create(x, mass).replace(wall_force=lagged)
    model = npfem.Model(
        dim=2,
        materials=[npfem.LinearElastic(E, 0.3, RHO)],
        mode="dynamic",
        bodies=[belt],
    )
    sim = npfem.Simulation(p, model, mesh, dt, progress=False)
    sim.run(t_end=t_end)
    q = sim.particles
    return {
        "s": float(q.u[:, 0] @ mass / mass.sum()),
        "uy": float(q.u[:, 1] @ mass / mass.sum()),
        "t": sim.time,
        "weight": float(mass.sum() * G),
        "mass": float(mass.sum()),
        "records": sim.records,
    }


def _carried(a, V, t, dt):
    """Distance of a block accelerated at ``a`` up to the belt speed V.

    Analytic, and backward Euler (``a t (t + dt) / 2`` while it slips).
    """
    ts = V / a
    if t <= ts:
        return 0.5 * a * t**2, 0.5 * a * t * (t + dt)
    n = round(ts / dt)  # discrete: reaches V after about ts/dt steps
    return 0.5 * a * ts**2 + V * (t - ts), 0.5 * a * ts * (ts + dt) + V * (t - n * dt)


def test_coulomb_belt_drags_block_at_mu_g():
    """Lagged Coulomb against a moving body: slip at mu g, then carried along."""
    dt, phi, V = 2.5e-3, 20.0, 1.0
    r = _belt(V, phi=phi, dt=dt, t_end=0.2)
    mu = math.tan(math.radians(phi))
    exact, euler = _carried(mu * G, V, r["t"], dt)
    # measured +1.2 % (dt/t = 1.3 %) and -3e-5 against the discrete value
    assert r["s"] == pytest.approx(exact, rel=0.02)
    assert r["s"] == pytest.approx(euler, rel=2e-3)
    fx = [rec.extra["belt_force_x"] for rec in r["records"]]
    fy = [rec.extra["belt_force_y"] for rec in r["records"]]
    # the soil holds the belt back by mu W while it slips, presses with W
    assert fx[-1] == pytest.approx(-mu * r["weight"], rel=1e-6)
    assert fy[-1] == pytest.approx(-r["weight"], rel=1e-6)
    assert max(rec.extra["belt_penetration"] for rec in r["records"]) == 0.0
    assert abs(r["uy"]) < 1e-4


def test_coulomb_belt_carries_block_after_it_catches_up():
    dt, phi, V = 2.5e-3, 20.0, 0.5
    r = _belt(V, phi=phi, dt=dt, t_end=0.3)
    mu = math.tan(math.radians(phi))
    exact, _ = _carried(mu * G, V, r["t"], dt)
    assert r["s"] == pytest.approx(exact, rel=0.02)  # measured +0.55 %
    assert abs(r["records"][-1].extra["belt_force_x"]) < 1e-6 * r["weight"]


def test_adhesion_belt_drags_block_at_a_L_over_m():
    """Tresca adhesion: the bound is the strength times the contact length."""
    dt, adhesion, V = 2.5e-3, 500.0, 5.0
    r = _belt(V, adhesion=adhesion, dt=dt, t_end=0.1)
    a = adhesion * 0.2 / r["mass"]
    exact, _ = _carried(a, V, r["t"], dt)
    # measured +2.5 % (dt / t = 2.5 %; the first step has no adhesion: no
    # contact in the step before it)
    assert r["s"] == pytest.approx(exact, rel=0.05)
    # the contact length along the belt: 0.2 m, up to the base's elastic strain
    assert r["records"][-1].extra["belt_force_x"] == pytest.approx(
        -adhesion * 0.2, rel=1e-3
    )


def test_unilateral_soil_stays_when_body_leaves():
    mesh, soil, p = _soil_block()
    lid = RigidBody(
        [[0.0, 1.0], [1.0, 1.0], [1.0, 1.5], [0.0, 1.5]], velocity=[0.0, 0.1]
    )
    model = npfem.Model(
        dim=2, materials=[soil], bodies=[lid], mode="static", gravity=0.0
    )
    sim = npfem.Simulation(p, model, mesh, 0.1, progress=False)
    sim.run(steps=3)
    assert np.abs(sim.particles.u).max() < 1e-12
    assert sim.records[-1].extra["body_force_y"] == pytest.approx(0.0, abs=1e-9)
    assert sim.records[-1].extra["body_y"] == pytest.approx(0.03)


# --- corners -----------------------------------------------------------------
def test_a_node_on_a_corner_takes_the_face_that_moves_onto_it():
    """The bisector would let it slide off the footing's edge diagonally."""
    x = np.array([[1.0, 0.0], [0.5, -0.01]])
    facets = np.array([[0], [1]])
    lagged = np.zeros((2, 1))
    args = (x, np.zeros_like(x), np.zeros_like(x, bool), np.zeros_like(x), lagged)
    rest = (facets, 0.1, 0.05, 0.0, 0.0)
    down = RigidBody(SQUARE, velocity=[0.0, -1.0])
    c, _ = body_contacts([down], *args, *rest)
    assert c.normal[0].tolist() == pytest.approx([0.0, -1.0])  # the base
    assert c.gap[0] == pytest.approx(-0.1)  # closes by V dt
    sideways = RigidBody(SQUARE, velocity=[1.0, 0.0])
    c, _ = body_contacts([sideways], *args, *rest)
    assert c.normal[0].tolist() == pytest.approx([1.0, 0.0])  # the side
    c, _ = body_contacts([RigidBody(SQUARE)], *args, *rest)
    assert c.normal[0].tolist() == pytest.approx([0.5**0.5, -(0.5**0.5)])


def test_corner_rows_of_a_wedge_tip_between_two_nodes():
    # One triangle below the edge (1, 1) -> (0, 1); a wedge tip 5 cm above
    # the edge at x = 0.3 moves down 1 cm in the step.
    x = np.array([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    t = np.array([[0], [1], [2]])
    edges = oriented_boundary(x, t)
    assert edges.T.tolist() == [[0, 1], [1, 2], [2, 0]]  # mesh on the left
    wedge = RigidBody([[0.3, 1.05], [0.5, 1.5], [0.1, 1.5]], velocity=[0.0, -1.0])
    none = np.zeros_like(x)
    c = corner_contacts(
        wedge, x, edges, none.astype(bool), none, np.full(3, 0.1), 0.01, 0.0
    )
    assert c.size == 1
    assert (c.node[0], c.partner[0]) == (1, 2)
    assert c.share[0] == pytest.approx(0.7)  # x_s = 0.3 x_1 + 0.7 x_2
    assert c.normal[0].tolist() == pytest.approx([0.0, -1.0])  # into the soil
    assert c.gap[0] == pytest.approx(0.05 - 0.01)
    assert c.points(x)[0].tolist() == pytest.approx([0.3, 1.0])
    # A flat face over the edge presses through its nodes, not its corners.
    flat = RigidBody([[0.2, 1.05], [0.4, 1.05], [0.4, 1.5], [0.2, 1.5]])
    c = corner_contacts(
        flat, x, edges, none.astype(bool), none, np.full(3, 0.1), 0.01, 0.0
    )
    assert c.size == 0


def test_wedge_tip_between_nodes_pushes_the_soil_edge():
    """Only a corner row can carry this load: both nodes are outside the wedge.

    The edge under the tip ends at the tip (the row is active, its gap
    closed) and the wedge takes the force the soil pushes back with; no
    particle gets inside it.
    """
    mesh, soil, p = _soil_block()
    tip = RigidBody(  # tip at x = 0.375, between the nodes at 0.25 and 0.5
        [[0.375, 1.0], [0.575, 1.4], [0.175, 1.4]], velocity=[0.0, -0.1], name="wedge"
    )
    model = npfem.Model(
        dim=2, materials=[soil], bodies=[tip], mode="static", gravity=0.0
    )
    sim = npfem.Simulation(p, model, mesh, 0.1, progress=False)
    sim.run(steps=1)
    q = sim.particles.x
    top = np.isclose(mesh.p[1], 1.0)
    left = np.flatnonzero(np.isclose(mesh.p[0], 0.25) & top)[0]
    right = np.flatnonzero(np.isclose(mesh.p[0], 0.5) & top)[0]
    y_edge = 0.5 * (q[left, 1] + q[right, 1])
    assert y_edge == pytest.approx(1.0 - 0.01, abs=1e-8)
    assert sim.records[-1].extra["wedge_force_y"] > 0.0
    assert sim.records[-1].extra["wedge_penetration"] == 0.0


def test_elements_along_a_sloping_face_do_not_span_it():
    """Nodes placed on a sloping edge are on it only up to rounding.

    A 60-degree cone's face carries nodes computed as ``tip + s (shoulder -
    tip)``; the elements that join two of them to a node outside have no
    part inside the cone and must stay, while an element reaching across the
    face must go.
    """
    R = 0.01785
    tip = np.array([0.0, 0.3927])
    shoulder = tip + np.array([R, R * math.sqrt(3.0)])
    cone = RigidBody([tip, shoulder, [R, 1.0], [0.0, 1.0]], name="cone")
    s = np.linspace(0.0, 1.0, 6)
    face = tip + s[:, None] * (shoulder - tip)
    normal = np.array([math.sqrt(3.0) / 2, -0.5])
    outside = 0.5 * (face[:-1] + face[1:]) + 0.004 * normal
    x = np.concatenate([face, outside, [face[2] - 0.004 * normal]])
    tri = np.array([[i, i + 1, 6 + i] for i in range(5)] + [[6, 7, 11]]).T
    drop = spanning_elements([cone], x, tri, 0.0)
    assert not drop[:5].any()
    assert drop[5]


def test_adhesion_per_edge_follows_the_corners_order():
    # Given clockwise, stored counter-clockwise: each edge keeps its strength.
    square = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]  # clockwise
    body = RigidBody(square, adhesion=[1.0, 2.0, 3.0, 4.0])
    x = np.array([[-0.1, 0.5], [0.5, 1.1], [1.1, 0.5], [0.5, -0.1]])
    assert body.adhesion_at(x, 0.0).tolist() == [1.0, 2.0, 3.0, 4.0]
    assert body.interface == "adhesion"
    with pytest.raises(ParameterError, match="one per edge"):
        RigidBody(square, adhesion=[1.0, 2.0])
    with pytest.raises(ParameterError, match="one per edge"):
        RigidBody(square, adhesion=[1.0, -2.0, 0.0, 0.0])
    assert RigidBody(square, adhesion=2.0).adhesion == 2.0


# --- the half-a-spacing contract, said by the API ---------------------------
def _wedge_run(mesh_source=None):
    mesh, soil, p = _soil_block()
    tip = RigidBody(
        [[0.375, 1.0], [0.575, 1.4], [0.175, 1.4]], velocity=[0.0, -0.1], name="skirt"
    )
    model = npfem.Model(
        dim=2, materials=[soil], bodies=[tip], mode="static", gravity=0.0
    )
    source = mesh if mesh_source is None else mesh_source
    return npfem.Simulation(p, model, source, 0.1, progress=False)


@pytest.mark.parametrize(
    ("source", "h"),
    [
        (None, 0.25),  # a fixed mesh: its median edge, the lattice's 0.25 m
        (npfem.AlphaShapeMesher(0.2, 1.4), 0.2),  # the spacing it declares
    ],
)
def test_a_particle_deeper_than_half_a_spacing_in_a_body_is_warned(source, h):
    # Reproducer: a user's skirted footing (skirts one spacing thick) let
    # particles 0.63 spacings into it; only the scenes warned, the API said
    # nothing.  The step's record holds the depth (what put_back measured).
    sim = _wedge_run(source)
    sim.run(steps=1)
    rec = sim.records[-1]
    rec.extra["skirt_penetration"] = 0.49 * h  # within the contract: quiet
    assert sim.penetration_check(sim, rec) == []
    rec.extra["skirt_penetration"] = 0.63 * h
    with pytest.warns(UserWarning, match="0.63 spacings inside it at step 1") as w:
        (msg,) = sim.penetration_check(sim, rec)
    assert "body 'skirt'" in msg and w[0].filename == __file__
    assert sim.penetration_check(sim, rec) == []  # once per body and run


def test_a_run_whose_particles_stay_out_of_the_body_is_not_warned(recwarn):
    sim = _wedge_run()
    sim.run(steps=2)
    assert max(r.extra["skirt_penetration"] for r in sim.records) == 0.0
    assert not [w for w in recwarn if "spacings inside" in str(w.message)]


def test_a_skirted_footing_run_warns_of_a_particle_deep_in_a_skirt():
    # Reproducer, run for real: a skirted footing whose skirts are 1.5 spacings
    # thick (a particle can then end up to 0.75 spacings inside one) pushed
    # half a spacing a step into a remeshed Tresca block.  Measured: 0.63
    # spacings at step 4 (0.41 at step 1), so the API warns once, at step 4.
    h = 0.1
    mesh = MeshTri.init_tensor(np.arange(0, 1 + 1e-9, h), np.arange(0, 0.5 + 1e-9, h))
    soil = npfem.Tresca(1e6, 0.49, rho=1000.0, c=1e3)
    fixed = np.zeros((mesh.p.shape[1], 2), bool)
    fixed[np.isclose(mesh.p[1], 0.0)] = True
    fixed[np.isclose(mesh.p[0], 0.0) | np.isclose(mesh.p[0], 1.0), 0] = True
    p = npfem.Particles.from_mesh(mesh, soil, fixed=fixed)
    t, bot, top = 1.5 * h, 0.501, 0.7
    outline = [[0.3, bot], [0.3 + t, bot], [0.3 + t, top - h], [0.7 - t, top - h]]
    outline += [[0.7 - t, bot], [0.7, bot], [0.7, top], [0.3, top]]
    footing = RigidBody(
        outline,
        velocity=[0.0, -0.5 * h],
        name="skirt",
    )
    model = npfem.Model(
        dim=2, materials=[soil], bodies=[footing], mode="static", gravity=0.0
    )
    sim = npfem.Simulation(p, model, npfem.AlphaShapeMesher(h, 1.3), 1.0)
    with pytest.warns(UserWarning, match="spacings inside it") as said:
        sim.run(steps=6)
    depth = [r.extra["skirt_penetration"] / h for r in sim.records]
    first = next(k for k, d in enumerate(depth) if d > 0.5)
    assert max(depth) <= 0.75 + 1e-9  # half the skirt's thickness
    deep = [w for w in said if "spacings inside it" in str(w.message)]
    assert len(deep) == 1  # once per body and run
    assert f"{depth[first]:.2f} spacings inside it at step {first + 1}" in str(
        deep[0].message
    )
