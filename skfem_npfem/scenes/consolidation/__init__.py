"""The ``consolidation`` scene: Terzaghi's column and Mandel's specimen, coupled."""

from .scene import SCENE as CONSOLIDATION

__all__ = ["CONSOLIDATION"]
