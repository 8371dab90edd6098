"""The ``elastic-column`` scene: a soil column under its own weight (oedometric)."""

from .column import SCENE as ELASTIC_COLUMN

__all__ = ["ELASTIC_COLUMN"]
