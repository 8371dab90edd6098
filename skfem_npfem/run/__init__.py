"""The time loop.

:class:`Simulation` (output, checkpoints, resume, progress) and run control
(signals, progress lines).
"""

from .simulation import AtRest, Simulation

__all__ = ["AtRest", "Simulation"]
