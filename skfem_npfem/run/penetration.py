"""The time loop's check of the rigid bodies' contract: half a spacing.

A particle that ends a step inside a :class:`~skfem_npfem.RigidBody` is put
back on its outline (``<name>_penetration`` of the step record is how deep it
got).  Up to half a particle spacing that is the discretisation's own error;
deeper, the body's load of that step is off and the soil has in effect passed
into the body (a thin skirt, a fast body).  :class:`PenetrationCheck` warns
once per body and run when that happens, for any model, not only the scenes'.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import warn_user

__all__ = ["PENETRATION_LIMIT", "PenetrationCheck"]

#: Deepest a particle may get inside a body before the check warns, spacings.
PENETRATION_LIMIT = 0.5

_KEY = "_penetration"


@dataclass
class PenetrationCheck:
    """Warn when a particle got deeper than half a spacing inside a body.

    Attributes
    ----------
    enabled : bool
        False: no check (a scene that reports the penetration itself).
    warned : set of str
        The bodies already warned about in this run.
    """

    enabled: bool = True
    warned: set = field(default_factory=set)

    def __call__(self, sim: Any, record: Any) -> list[str]:
        """Check ``record`` (a step of ``sim``); returns the messages warned."""
        deep = {
            key[: -len(_KEY)]: depth
            for key, depth in record.extra.items()
            if key.endswith(_KEY) and isinstance(depth, float) and depth > 0.0
        }
        if not (self.enabled and deep):
            return []
        h = spacing(sim.mesh_source, sim.particles.x)
        said = []
        for name, depth in deep.items():
            if name not in self.warned and depth > PENETRATION_LIMIT * h:
                self.warned.add(name)
                said.append(
                    f"body {name!r}: a particle got {depth / h:.2f} spacings "
                    f"inside it at step {record.step} (t = {record.time:.4g} s; "
                    f"more than {PENETRATION_LIMIT:g}, the contract) before it "
                    "was put back on its outline, so the body's load of that step "
                    "is off: lower dt, refine the spacing near the body, or make "
                    "its thin parts (a skirt) at least two spacings thick"
                )
                warn_user(said[-1])
        return said


def spacing(mesh_source: Any, x: np.ndarray) -> float:
    """The particle spacing of a run, m.

    An :class:`~skfem_npfem.mesh.sources.AlphaShapeMesher` declares it: ``h``,
    or for a graded lattice a spacing per particle, whose smallest is taken
    (the finest particles are those next to a body).  Otherwise (a
    :class:`~skfem_npfem.mesh.sources.FixedMesh`) it is the median edge length
    of the mesh at the particles' positions ``x``.
    """
    local = getattr(mesh_source, "spacing", None)
    if local is not None and np.size(local):
        return float(np.min(local))
    h = getattr(mesh_source, "h", None)
    if isinstance(h, int | float):
        return float(h)
    t = np.asarray(mesh_source.t)
    edges = np.concatenate([t[[i, j]] for i in range(len(t)) for j in range(i)], 1)
    return float(np.median(np.linalg.norm(x[edges[0]] - x[edges[1]], axis=1)))
