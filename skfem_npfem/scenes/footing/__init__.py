"""The footing scenes: strip footing, footing penetration and cone penetration.

``strip`` is ``strip-footing`` (its soil block in ``mesh``, its pictures in
``scenery``, its settlement steps in ``plateau``, what its material and
analysis use in ``usage``); ``penetration`` a footing pushed into the soil and
``cone`` the cone penetration test, which share the graded lattice, the
interfaces, the derived defaults and the warnings of ``penetration_common``.
"""

from .cone import SCENE as CONE_PENETRATION
from .penetration import SCENE as FOOTING_PENETRATION
from .strip import SCENE as STRIP_FOOTING

__all__ = ["CONE_PENETRATION", "FOOTING_PENETRATION", "STRIP_FOOTING"]
