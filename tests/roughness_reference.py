"""An independent implementation of the stress-roughness index, for the tests.

Written from the definition with plain Python sets and counters (no sparse
matrices, no code shared with :func:`skfem_npfem.stress_roughness`):

    R = rms_i(s_i - mean_{j ~ i} s_j) / rms_i(s_i)

over the interior nodes ``i``: nodes of a cell that lie on no boundary facet (a
facet of exactly one cell) and have no neighbour on one; ``j ~ i`` are the
nodes sharing a cell with ``i``.  Fewer than 10 interior nodes give NaN.
"""

from __future__ import annotations

import math
from collections import Counter, defaultdict
from itertools import combinations
from typing import Any


def reference_roughness(cells: Any, values: Any) -> tuple[float, int]:
    """``(R, number of interior nodes)`` of nodal ``values`` on simplex ``cells``."""
    cells = [tuple(int(v) for v in c) for c in cells]
    k = len(cells[0])
    neighbours: dict[int, set[int]] = defaultdict(set)
    for c in cells:
        for a in c:
            neighbours[a].update(b for b in c if b != a)
    facets = Counter(frozenset(f) for c in cells for f in combinations(c, k - 1))
    boundary = {v for f, n in facets.items() if n == 1 for v in f}
    interior = [
        i for i in neighbours if i not in boundary and not neighbours[i] & boundary
    ]
    if len(interior) < 10:
        return math.nan, len(interior)
    s = [float(v) for v in values]
    dev = [
        s[i] - sum(s[j] for j in neighbours[i]) / len(neighbours[i]) for i in interior
    ]
    scale = math.sqrt(sum(s[i] ** 2 for i in interior) / len(interior))
    if scale == 0.0:
        return 0.0, len(interior)
    return math.sqrt(sum(d * d for d in dev) / len(dev)) / scale, len(interior)
