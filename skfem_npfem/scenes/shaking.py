"""Pseudo-static shaking: a horizontal body force ``k_h`` times the weight.

A horizontal acceleration ``k_h g`` along ``+x`` loads every particle with
``k_h`` times its weight (:attr:`~skfem_npfem.Model.kh`): a number for the
whole run, or a recorded history, a file of ``t, k_h`` rows
(:func:`kh_history`), linear between rows and held after the last.  The
scenes with gravity whose geometry allows a horizontal load take it as the
parameter ``kh`` (:func:`kh_param`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from .params import Param

__all__ = ["kh_history", "kh_param", "model_kh", "static_kh"]


def kh_param(direction: str, use: str) -> Param:
    """The parameter ``kh`` of a scene: its ``direction`` and ``use`` said."""
    return Param(
        "kh",
        0.0,
        "-",
        f"pseudo-static horizontal acceleration k_h g {direction}, a body force "
        f"k_h times the weight: {use} (a file's rows: s, -; commas or spaces, "
        "# comments; 0: none)",
        float,
        lo=-10,
        hi=10,
        or_file=True,
    )


def kh_history(values: Mapping[str, Any]) -> np.ndarray | None:
    """The rows ``[t, k_h]`` of ``kh``'s file, checked; None for a number."""
    kh = values["kh"]
    if not isinstance(kh, str):
        return None
    path = Path(kh)
    if not path.is_file():
        raise ParameterError("kh", kh, "a number, or the path of an existing file")
    try:
        rows = np.loadtxt(path, delimiter="," if "," in path.read_text() else None)
    except ValueError as err:
        raise ParameterError(
            "kh", kh, f"a file of rows t, k_h (two numbers a row): {err}"
        ) from None
    rows = np.atleast_2d(rows)
    if rows.ndim != 2 or rows.shape[1] != 2 or not np.all(np.isfinite(rows)):
        raise ParameterError(
            "kh", kh, f"rows of two finite numbers t, k_h (read {rows.shape})"
        )
    if np.any(np.diff(rows[:, 0]) <= 0):
        i = int(np.flatnonzero(np.diff(rows[:, 0]) <= 0)[0])
        raise ParameterError(
            "kh",
            kh,
            f"rows with increasing t (row {i + 2}: t = {rows[i + 1, 0]:g} after "
            f"{rows[i, 0]:g})",
        )
    if np.any(np.abs(rows[:, 1]) > 10):
        raise ParameterError("kh", kh, "k_h within [-10, 10] in every row")
    return rows


def static_kh(values: Mapping[str, Any]) -> float:
    """The ``k_h`` of the factor of safety: the number, or 0 with a history."""
    kh = values["kh"]
    return 0.0 if isinstance(kh, str) else float(kh)


def model_kh(values: Mapping[str, Any]) -> float | np.ndarray:
    """What the run-out's :class:`~skfem_npfem.Model` takes as ``kh``."""
    rows = kh_history(values)
    return static_kh(values) if rows is None else rows
