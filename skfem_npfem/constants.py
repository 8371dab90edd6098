"""Physical constants used by the scenes and the pictures (SI units)."""

from __future__ import annotations

__all__ = ["GRAVITY"]

#: Gravitational acceleration of the scenes, m/s^2 (the value the references use).
GRAVITY: float = 9.81
