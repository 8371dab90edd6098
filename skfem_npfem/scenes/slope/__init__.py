"""The ``slope`` scene: a slope's factor of safety, its mechanism, and the run-out.

``scene`` declares the scene and builds its run; ``section`` is the
cross-section (parametric or a file), ``stages`` the initial stresses, the
factor of safety and the run-out's model, ``runout`` the run-out measures.
"""

from .scene import SCENE as SLOPE

__all__ = ["SLOPE"]
