"""Choosing a method by name: N-PFEM or one of the two baselines.

:func:`make_method` is the one place where a method name and its options are
checked, so that a scene or the command line can refuse a bad combination
(an unknown method, an ``element`` or ``transfer`` given to a method that has
none, a ``damping`` or ``explicit_dt`` given to an implicit method) with one
:class:`~skfem_npfem.errors.ParameterError` before any work.
"""

from __future__ import annotations

from typing import Any

from ..errors import ParameterError
from .fem_remap import FemRemap
from .spfem import SPFEM

__all__ = ["METHODS", "METHOD_OPTIONS", "make_method"]

#: Method names: the library's N-PFEM, FEM with remapping, explicit SPFEM.
METHODS = ("npfem", "fem-remap", "spfem")

#: Options each method accepts.
METHOD_OPTIONS: dict[str, tuple[str, ...]] = {
    "npfem": (),
    "fem-remap": ("element", "transfer"),
    "spfem": ("damping", "explicit_dt"),
}


def make_method(name: str, **options: Any) -> FemRemap | SPFEM | None:
    """Build a baseline method object (None for N-PFEM, the library's step).

    Parameters
    ----------
    name : {"npfem", "fem-remap", "spfem"}
    **options
        ``element``, ``transfer`` (fem-remap) or ``damping``, ``explicit_dt``
        (spfem); options given as None are ignored.

    Raises
    ------
    ParameterError
        Unknown method, an option the method does not have, or a bad value.

    Examples
    --------
    >>> make_method("fem-remap", element="p2", transfer="nearest")
    FemRemap(element='p2', transfer='nearest')
    >>> make_method("spfem", element="p2")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    skfem_npfem.errors.ParameterError: invalid element='p2': spfem has no option ...
    """
    if name not in METHODS:
        raise ParameterError("method", name, f"one of {METHODS}")
    given = {k: v for k, v in options.items() if v is not None}
    allowed = METHOD_OPTIONS[name]
    for key, value in given.items():
        if key not in allowed:
            has = ", ".join(allowed) if allowed else "none"
            raise ParameterError(
                key, value, f"{name} has no option {key}; its options: {has}"
            )
    if name == "fem-remap":
        return FemRemap(**given)
    if name == "spfem":
        return SPFEM(**given)
    return None
