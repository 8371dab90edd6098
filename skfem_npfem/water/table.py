"""The water table and the hydrostatic pore pressure below it."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError

__all__ = ["WaterTable"]


@dataclass(frozen=True)
class WaterTable:
    """A phreatic surface: a horizontal level or a polyline of a section.

    Below the table the pore pressure is hydrostatic, ``p = rho_w g (z_w -
    z)`` with ``z`` the vertical coordinate (the last one) and ``z_w`` the
    table's elevation above the point; above it the pore pressure is zero
    (no suction).  A table above the ground means free water over it, whose
    pressure loads the surface.

    Parameters
    ----------
    level : float, optional
        Elevation of a horizontal table, m.
    line : array_like (k, 2), optional
        A polyline ``(x, z)`` of a plane or axisymmetric section, ``x``
        strictly increasing; the elevation is interpolated linearly between
        its vertices (2D models only).  Points outside its ``x`` range are
        refused when the pressure is asked for.

    Exactly one of ``level`` and ``line`` is given.

    Examples
    --------
    >>> t = WaterTable(level=2.0)
    >>> t.pressure(np.array([[0.0, 1.0], [0.0, 3.0]]), rho_w=1000.0, gravity=10.0)
    array([10000.,     0.])
    """

    level: float | None = None
    line: np.ndarray | None = None

    def __post_init__(self) -> None:
        if (self.level is None) == (self.line is None):
            raise ParameterError(
                "water table",
                f"level={self.level!r}, line={self.line!r}",
                "exactly one of a level (m) and a line [[x, z], ...]",
            )
        if self.level is not None:
            lv = self.level
            if isinstance(lv, bool) or not (
                isinstance(lv, int | float) and math.isfinite(lv)
            ):
                raise ParameterError("water_level", lv, "a finite elevation (m)")
            return
        try:
            line = np.array(self.line, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(
                "water", self.line, "a polyline [[x, z], ...] of numbers"
            ) from None
        if line.ndim != 2 or line.shape[1] != 2 or line.shape[0] < 2:
            raise ParameterError(
                "water", f"shape {line.shape}", "at least two points [[x, z], ...]"
            )
        if not np.all(np.isfinite(line)):
            raise ParameterError("water", "NaN or inf", "finite coordinates (m)")
        if np.any(np.diff(line[:, 0]) <= 0):
            raise ParameterError(
                "water", line[:, 0].tolist(), "x strictly increasing along the line"
            )
        object.__setattr__(self, "line", line)

    def elevation(self, x: np.ndarray) -> np.ndarray:
        """Elevation of the table above each point ``x`` (N, d), m."""
        x = np.asarray(x, float)
        if self.level is not None:
            return np.full(x.shape[0], float(self.level))
        if x.shape[1] != 2:
            raise ParameterError(
                "water", "a polyline", "a level in 3D models (a line is 2D)"
            )
        line = self.line
        lo, hi = line[0, 0], line[-1, 0]
        tol = 1e-9 * max(1.0, hi - lo)
        out = (x[:, 0] < lo - tol) | (x[:, 0] > hi + tol)
        if np.any(out):
            i = int(np.flatnonzero(out)[0])
            raise ParameterError(
                "water",
                f"a line over x in [{lo:g}, {hi:g}]",
                f"a line that spans the soil (x = {x[i, 0]:g} is outside it)",
            )
        return np.interp(x[:, 0], line[:, 0], line[:, 1])

    def pressure(self, x: np.ndarray, rho_w: float, gravity: float) -> np.ndarray:
        """Hydrostatic pore pressure at ``x`` (N, d), Pa; zero above the table."""
        x = np.asarray(x, float)
        head = self.elevation(x) - x[:, -1]
        return rho_w * gravity * np.maximum(head, 0.0)
