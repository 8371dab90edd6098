"""The ``column-collapse`` scene: plane strain, axisymmetric and 3D columns.

``plane_strain`` is the 2D scene and ``params`` its parameters; ``geometry``
adds the column geometries and ``runs`` builds their runs (``cylinder``:
the round columns, ``box_column``: the 3D box, ``sizing``: their particle
counts before anything is built); ``runout`` holds the run-out measures.
"""

from .runs import COLUMN_COLLAPSE, bare_method

__all__ = ["COLUMN_COLLAPSE", "bare_method"]
