"""Old names that still work for one release, with a ``DeprecationWarning``.

A module whose public class was renamed keeps the old name through
:pep:`562`'s module ``__getattr__``::

    def __getattr__(name):
        return renamed(__name__, name, {"StepData": ConeInput})

The old name is the same class object as the new one, so ``isinstance`` and
pickles made before the rename keep working.
"""

from __future__ import annotations

import warnings
from typing import Any

__all__ = ["RENAMED", "renamed"]

#: Renamed step types: old name -> new name (removed in the next release).
RENAMED = {
    "StepData": "ConeInput",
    "StepSolution": "ConeSolution",
    "StepResult": "Step",
}


def renamed(module: str, name: str, objects: dict[str, Any]) -> Any:
    """The object of an old name of ``module``, with a ``DeprecationWarning``.

    Parameters
    ----------
    module : str
        The module's ``__name__``.
    name : str
        The attribute asked for.
    objects : dict of str to object
        Old names of this module and the objects they now stand for.

    Raises
    ------
    AttributeError
        If ``name`` is not an old name of ``module``.
    """
    if name not in objects:
        raise AttributeError(f"module {module!r} has no attribute {name!r}")
    new = objects[name]
    warnings.warn(
        f"{module}.{name} is renamed {new.__name__} (import "
        f"skfem_npfem.{new.__name__}); the old name will be removed in the next "
        "release",
        DeprecationWarning,
        stacklevel=3,
    )
    return new
