"""Scene parameters: declared with unit, default and bounds, parsed from text.

A :class:`Param` checks a value (strings as typed on the command line are
parsed first, :func:`parse_value`) and says what is allowed in the message of
its :class:`~skfem_npfem.errors.ParameterError`.  The values of a run, with
their derived defaults filled in once, are a read-only :class:`Values`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from ..errors import ParameterError
from .limits import MAGNITUDES

__all__ = ["ANGLE", "POSITIVE", "Param", "Values", "parse_value"]

#: Bounds of a parameter that must be a finite number > 0 (``Param(..., **POSITIVE)``).
POSITIVE = {"lo": 0, "lo_open": True}

#: Bounds of an angle in degrees, in [0, 90) (``Param(..., **ANGLE)``).
ANGLE = {"lo": 0, "hi": 90, "hi_open": True}


@dataclass(frozen=True)
class Param:
    """One scene parameter.

    Attributes
    ----------
    name : str
        Name used with ``--set name=value``.
    default : object
        Default value (None: derived from other parameters, see ``help``).
    unit : str
        SI unit ("-" for dimensionless).
    help : str
        One-line description.
    kind : type
        float, int, str or bool.
    choices : tuple or None
        Allowed values for str/int parameters.
    lo, hi : float
        Allowed closed range for numbers (``lo_open``/``hi_open`` make it open).
    note : str
        Appended in parentheses to the allowed values (in the docs and in the
        error of a refused value), e.g. why a method is not offered.
    or_file : bool
        A number parameter that also takes the path of a file (text that is
        not a number is kept as it is; the scene reads and checks the file).
    """

    name: str
    default: Any
    unit: str
    help: str
    kind: type = float
    choices: tuple | None = None
    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False
    note: str = ""
    or_file: bool = False

    def allowed(self) -> str:
        """Human-readable allowed values."""
        if self.note:
            return f"{self._allowed()} ({self.note})"
        return self._allowed()

    def _allowed(self) -> str:
        if self.choices is not None:
            return "one of " + ", ".join(map(str, self.choices))
        if self.kind is bool:
            return "true or false"
        if self.kind is str:
            return "a text"
        what = "an integer" if self.kind is int else "a finite number"
        lo, hi, lo_open, hi_open, zero = self.bounds()
        left = "(" if lo_open or math.isinf(lo) else "["
        right = ")" if hi_open or math.isinf(hi) else "]"
        text = f"{what} in {left}{lo:g}, {hi:g}{right}"
        text = f"0 or {text}" if zero else text
        return f"{text}, or a file's path" if self.or_file else text

    def bounds(self) -> tuple[float, float, bool, bool, bool]:
        """``(lo, hi, lo_open, hi_open, zero_allowed)`` of a number.

        The parameter's own range intersected with the magnitudes the scenes
        run at (:data:`~skfem_npfem.scenes.limits.MAGNITUDES`); ``zero_allowed``
        says that 0 is allowed besides ``lo..hi``.
        """
        lo, hi, lo_open, hi_open = self.lo, self.hi, self.lo_open, self.hi_open
        window = MAGNITUDES.get(self.name)
        if window is None or not lo >= 0:
            return lo, hi, lo_open, hi_open, False
        zero = lo == 0 and not lo_open
        if window[0] > lo:
            lo, lo_open = window[0], False
        if window[1] < hi:
            hi, hi_open = window[1], False
        return lo, hi, lo_open, hi_open, zero

    def check(self, value: Any) -> Any:
        """Convert and validate a value (strings are parsed).

        Numbers may be Python or numpy scalars (``np.int64(2)``,
        ``np.float32(0.3)``); booleans Python or numpy bools.
        """
        if value is None and self.default is None:
            return None
        v = parse_value(self, value) if isinstance(value, str) else value
        if isinstance(v, np.generic) and v.ndim == 0:
            v = v.item()  # numpy scalar -> Python bool/int/float/str
        if self.or_file and isinstance(v, str | Path):
            if not str(v).strip():
                raise ParameterError(self.name, value, self.allowed())
            return str(v)
        if self.kind is bool:
            if not isinstance(v, bool):
                raise ParameterError(self.name, value, self.allowed())
            return v
        if self.kind in (int, float):
            if isinstance(v, bool) or not isinstance(v, int | float):
                raise ParameterError(self.name, value, self.allowed())
            if self.kind is int and not (math.isfinite(v) and int(v) == v):
                raise ParameterError(self.name, value, self.allowed())
            v = self.kind(v)
            lo, hi, lo_open, hi_open, zero = self.bounds()
            ok = math.isfinite(v)
            ok = ok and (v > lo if lo_open else v >= lo)
            ok = ok and (v < hi if hi_open else v <= hi)
            if not (ok or (zero and v == 0)):
                raise ParameterError(self.name, value, self.allowed())
        if self.kind is str and not isinstance(v, str):
            raise ParameterError(self.name, value, self.allowed())
        if self.choices is not None and v not in self.choices:
            raise ParameterError(self.name, value, self.allowed())
        return v


def parse_value(param: Param, text: str) -> Any:
    """Parse the text of ``--set name=text`` according to the parameter kind."""
    t = text.strip()
    try:
        if param.kind is bool:
            low = t.lower()
            if low in ("1", "true", "yes", "on"):
                return True
            if low in ("0", "false", "no", "off"):
                return False
            raise ValueError
        if param.kind is int:
            f = float(t)
            if f != int(f):
                raise ValueError
            return int(f)
        if param.kind is float:
            return float(t)
    except (ValueError, OverflowError):
        if param.or_file and t and param.kind is float:
            return t
        raise ParameterError(param.name, text, param.allowed()) from None
    return t


class Values(Mapping[str, Any]):
    """The parameter values of a run: checked, derived defaults filled, read-only.

    A scene resolves its values once, before its run is built
    (:meth:`Scene.resolve <skfem_npfem.scenes.base.Scene.resolve>`); the
    stages read them (``values["dt"]`` or ``values.dt``) and none writes one.
    ``dict(values)`` is the plain dict of the summary and the checkpoints.

    Parameters
    ----------
    data : mapping
        Parameter name -> value (copied).

    Examples
    --------
    >>> v = Values({"spacing": 0.5, "dt": None})
    >>> v.spacing, v["dt"], dict(v)
    (0.5, None, {'spacing': 0.5, 'dt': None})
    >>> v["dt"] = 0.01
    Traceback (most recent call last):
    ...
    TypeError: 'Values' object does not support item assignment
    """

    __slots__ = ("_data",)

    def __init__(self, data: Mapping[str, Any]) -> None:
        object.__setattr__(self, "_data", MappingProxyType(dict(data)))

    def __getitem__(self, key: str) -> Any:
        return self._data[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._data[name]
        except KeyError:
            raise AttributeError(
                f"no parameter {name!r} (parameters: {', '.join(self._data)})"
            ) from None

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is read-only ({name})")

    def __reduce__(self) -> tuple[type, tuple[dict[str, Any]]]:
        return type(self), (dict(self._data),)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({dict(self._data)!r})"
