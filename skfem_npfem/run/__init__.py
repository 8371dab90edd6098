"""The time loop.

:class:`Simulation` (output, checkpoints, resume, progress) and run control
(signals, progress lines).
"""

from .rest import AtRest
from .simulation import Simulation

__all__ = ["AtRest", "Simulation"]
