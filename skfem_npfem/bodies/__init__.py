"""Moving rigid bodies: a footing, a cone, a pipe pushed through the particles.

* :mod:`.body` -- :class:`RigidBody` (a polygon moved at a prescribed
  velocity), particles put back out of a body, the loads a body takes;
* :mod:`.spanning` -- the elements of a step's mesh that span a body (a
  sliver at a corner allowed);
* :mod:`.contact` -- contact with the particles' boundary, found every step
  (boundary nodes against faces, body corners against boundary edges);
* 3D models: :class:`RigidPlane` (:mod:`.plane`, a moving half-space) and
  :class:`BodyOfRevolution` (:mod:`.revolution`, an ``(r, z)`` profile turned
  about an axis), with what they share in :mod:`.solid`; :mod:`.contact3d` --
  the tetrahedra that span them, their contacts and loads.
"""

from .body import (
    RigidBody,
    body_loads,
    check_clear,
    project_out_of_bodies,
)
from .contact import (
    body_contacts,
    boundary_facets,
    boundary_tributary,
    corner_contacts,
    oriented_boundary,
)
from .contact3d import (
    boundary_faces,
    face_tributary,
    solid_contacts,
    solid_loads,
    spanning_tetrahedra,
)
from .plane import RigidPlane
from .revolution import BodyOfRevolution
from .spanning import CLIP_DEPTH, spanning_elements

__all__ = [
    "CLIP_DEPTH",
    "BodyOfRevolution",
    "RigidBody",
    "RigidPlane",
    "body_contacts",
    "body_loads",
    "boundary_faces",
    "boundary_facets",
    "boundary_tributary",
    "check_clear",
    "corner_contacts",
    "face_tributary",
    "oriented_boundary",
    "project_out_of_bodies",
    "solid_contacts",
    "solid_loads",
    "spanning_elements",
    "spanning_tetrahedra",
]
