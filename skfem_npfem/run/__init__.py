"""The time loop.

* :mod:`.simulation` -- :class:`Simulation`: adaptive steps, callbacks, output
  and checkpoints as steps finish, resume;
* :mod:`.rest` -- :class:`AtRest`, the stop rule of a flow that came to rest;
* :mod:`.penetration` -- the warning of a particle deeper than half a spacing
  inside a rigid body;
* :mod:`.control` -- progress lines and SIGINT/SIGTERM handling;
* :mod:`.statistics` -- the solver statistics of a run (a summary's ``solver``
  block).
"""

from .rest import AtRest
from .simulation import Simulation

__all__ = ["AtRest", "Simulation"]
