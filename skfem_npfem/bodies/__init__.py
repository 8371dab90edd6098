"""Moving rigid bodies: a footing, a cone, a pipe pushed through the particles.

* :mod:`.body` -- :class:`RigidBody` (a polygon moved at a prescribed
  velocity), the elements a body spans, particles put back out of a body, the
  loads a body takes;
* :mod:`.contact` -- contact with the particles' boundary, found every step
  (boundary nodes against faces, body corners against boundary edges).
"""

from .body import (
    RigidBody,
    body_loads,
    check_clear,
    project_out_of_bodies,
    spanning_elements,
)
from .contact import (
    body_contacts,
    boundary_facets,
    boundary_tributary,
    corner_contacts,
    oriented_boundary,
)

__all__ = [
    "RigidBody",
    "body_contacts",
    "body_loads",
    "boundary_facets",
    "boundary_tributary",
    "check_clear",
    "corner_contacts",
    "oriented_boundary",
    "project_out_of_bodies",
    "spanning_elements",
]
