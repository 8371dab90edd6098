"""Exceptions raised by skfem-npfem, and how it warns.

Every error a user can trigger through the public API or the CLI derives from
:class:`NpfemError`; input errors are also :class:`ValueError` so that ordinary
``except ValueError`` code keeps working.  Every warning goes through
:func:`warn_user`, which names the user's line, not the package's.
"""

from __future__ import annotations

import os
import signal
import sys
import warnings

_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__)) + os.sep


class NpfemError(Exception):
    """Base class of all library errors."""


class ParameterError(NpfemError, ValueError):
    """A user-supplied parameter is invalid.

    The message always names the parameter, the offending value and what is
    allowed.

    Parameters
    ----------
    name : str
        The parameter (or scene parameter, or argument) at fault.
    value : object
        The value given.
    allowed : str
        What is allowed, in words (``"a number in (0, 1)"``).
    """

    def __init__(self, name: str, value: object, allowed: str) -> None:
        self.name = name
        self.value = value
        self.allowed = allowed
        super().__init__(f"invalid {name}={value!r}: {allowed}")

    @classmethod
    def missing(cls, name: str, allowed: str) -> ParameterError:
        """A required parameter was not given: ``missing NAME: allowed``.

        Examples
        --------
        >>> str(ParameterError.missing("--grid", "give at least one --grid a=1,2"))
        'missing --grid: give at least one --grid a=1,2'
        """
        err = cls(name, None, allowed)
        err.args = (f"missing {name}: {allowed}",)
        return err


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


class RunInterrupted(KeyboardInterrupt):
    """A run was stopped by SIGINT (Ctrl-C) or SIGTERM between two steps.

    Raised by :meth:`~skfem_npfem.run.simulation.Simulation.run` after the step in
    progress finished (or was abandoned at a second signal) and a checkpoint
    was written.  It is a :class:`KeyboardInterrupt`, so code that stops on
    Ctrl-C keeps doing so.

    Attributes
    ----------
    signum : int
        The signal (``signal.SIGINT`` or ``signal.SIGTERM``).
    step : int
        The last finished step.
    time : float
        Its time, s.
    checkpoint : pathlib.Path or None
        The checkpoint written (None without a checkpoint folder).
    abandoned : bool
        True if a second signal abandoned the step in progress.
    summary : dict or None
        The partial summary (set by the scene runner).
    summary_path : pathlib.Path or None
        Where the partial summary was written (set by the scene runner).
    """

    def __init__(
        self,
        signum: int,
        step: int,
        time: float,
        checkpoint: object = None,
        abandoned: bool = False,
    ) -> None:
        self.signum = int(signum)
        self.step = int(step)
        self.time = float(time)
        self.checkpoint = checkpoint
        self.abandoned = abandoned
        self.summary: dict | None = None
        self.summary_path: object = None
        super().__init__(f"{self.signal_name} after step {step} (t = {time:.6g} s)")

    @property
    def signal_name(self) -> str:
        """``"SIGINT"``, ``"SIGTERM"`` or ``"signal N"``."""
        try:
            return signal.Signals(self.signum).name
        except ValueError:
            return f"signal {self.signum}"

    @property
    def exit_code(self) -> int:
        """The shell's exit code of a process ended by the signal (128 + N)."""
        return 128 + self.signum


def warn_user(message: str, category: type[Warning] = UserWarning) -> None:
    """Warn with the user's line named: the first caller outside the package.

    A warning raised deep in a scene's metrics would otherwise be attributed
    to a line of this package that the user never wrote.  On Python 3.12 and
    later this is ``warnings.warn(..., skip_file_prefixes=...)``; before, the
    stack level is counted to the first frame outside the package.

    Parameters
    ----------
    message : str
        The warning's text.
    category : type of Warning
        Its category.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warn_user("a note")
    >>> str(caught[0].message), caught[0].filename.startswith(_PACKAGE_DIR)
    ('a note', False)
    """
    if sys.version_info >= (3, 12):
        warnings.warn(message, category, skip_file_prefixes=(_PACKAGE_DIR,))
        return
    level = 2
    frame = sys._getframe(1)
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(
        _PACKAGE_DIR
    ):
        frame = frame.f_back
        level += 1
    warnings.warn(message, category, stacklevel=level)
