"""Exceptions raised by skfem-npfem.

Every error a user can trigger through the public API or the CLI derives from
:class:`NpfemError`; input errors are also :class:`ValueError` so that ordinary
``except ValueError`` code keeps working.
"""

from __future__ import annotations


class NpfemError(Exception):
    """Base class of all library errors."""


class ParameterError(NpfemError, ValueError):
    """A user-supplied parameter is invalid.

    The message always names the parameter, the offending value and what is
    allowed.
    """

    def __init__(self, name: str, value: object, allowed: str) -> None:
        self.name = name
        self.value = value
        self.allowed = allowed
        super().__init__(f"invalid {name}={value!r}: {allowed}")


class SolverError(NpfemError):
    """The cone solver did not return an acceptable solution.

    Attributes
    ----------
    status : str
        Clarabel's status string (for example ``"NumericalError"``).
    step : int or None
        Index of the time step that failed, when known.
    iterations : int
        Interior-point iterations spent.
    """

    def __init__(
        self, status: str, step: int | None, iterations: int, hint: str = ""
    ) -> None:
        self.status = status
        self.step = step
        self.iterations = iterations
        where = "" if step is None else f" at step {step}"
        msg = (
            f"cone solver returned status {status}{where} after {iterations} iterations"
        )
        if hint:
            msg += f"; {hint}"
        super().__init__(msg)


class CheckpointError(NpfemError, ValueError):
    """A checkpoint or result folder is missing, corrupted or incompatible."""
