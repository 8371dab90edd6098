"""The time loop.

:class:`Simulation` (output, checkpoints, resume, progress) and run control
(signals, progress lines), and the solver statistics of a run.
"""

from .rest import AtRest
from .simulation import Simulation

__all__ = ["AtRest", "Simulation"]
