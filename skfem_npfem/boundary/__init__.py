"""Boundaries: rigid walls and moving rigid bodies, and what a step asks of them.

* :mod:`.contacts` -- :class:`Contacts`, the contact candidates of a step;
* :mod:`.protocol` -- :class:`Boundary`, what a step needs of any boundary
  (lagged-force columns, elements it spans, contact rows, particles put back,
  record keys) and the step's nodes as the rows see them
  (:class:`ContactNodes`); the step asks them in
  :mod:`skfem_npfem.step.boundary_jobs`;
* :mod:`.walls` -- :class:`RigidWall` (a fixed plane, with :func:`floor` and
  :func:`wall_x`), its contact rows and projection, and :class:`Walls`, a
  model's walls as one boundary;
* :mod:`.rigid_bodies` -- :class:`RigidBodies`, a model's bodies as one
  boundary;
* the bodies: :mod:`.body` -- :class:`RigidBody` (a polygon moved at a
  prescribed velocity) and what every body shares (its motion, interface and
  inside test), particles put back out of a body, the loads a body takes;
  :class:`RigidPlane` (:mod:`.plane`, a moving half-space) and
  :class:`BodyOfRevolution` (:mod:`.revolution`, an ``(r, z)`` profile turned
  about an axis) in 3D, with the checks of their inputs in :mod:`.solid`;
* their contacts: :mod:`.contact` -- contact with the particles' boundary,
  found every step, in 2D and 3D (boundary nodes against faces, body corners
  against boundary edges); :mod:`.spanning` -- the elements of a 2D mesh that
  span a body (a sliver at a corner allowed); :mod:`.contact3d` -- the
  boundary faces of a 3D mesh, their tributary areas and the tetrahedra that
  span a body.
"""

from .body import (
    START_DEPTH,
    RigidBody,
    body_loads,
    check_clear,
    project_out_of_bodies,
    start_clear,
)
from .contact import (
    body_contacts,
    boundary_tributary,
    corner_contacts,
    oriented_boundary,
)
from .contact3d import (
    boundary_faces,
    face_tributary,
    spanning_tetrahedra,
)
from .contacts import Contacts
from .plane import RigidPlane
from .protocol import Boundary, ContactNodes
from .revolution import BodyOfRevolution
from .rigid_bodies import RigidBodies
from .spanning import CLIP_DEPTH, spanning_elements
from .walls import RigidWall, Walls, floor, node_contacts, project_to_walls, wall_x

__all__ = [
    "CLIP_DEPTH",
    "START_DEPTH",
    "BodyOfRevolution",
    "Boundary",
    "ContactNodes",
    "Contacts",
    "RigidBodies",
    "RigidBody",
    "RigidPlane",
    "RigidWall",
    "Walls",
    "body_contacts",
    "body_loads",
    "boundary_faces",
    "boundary_tributary",
    "check_clear",
    "corner_contacts",
    "face_tributary",
    "floor",
    "node_contacts",
    "oriented_boundary",
    "project_out_of_bodies",
    "project_to_walls",
    "spanning_elements",
    "spanning_tetrahedra",
    "start_clear",
    "wall_x",
]
