"""What strip-footing's chosen material and analysis use.

A parameter given for a material or analysis that ignores it is refused
(``phi``, ``psi`` with Tresca) or warned about (the incremental run's
parameters with ``analysis=limit``; ``K0`` of a weightless soil, ``p0`` of
a soil with weight; ``rho_w`` of a dry soil).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..common import refuse_frictional, warn_unused
from ..wet_soil import warn_dry_water

__all__ = ["LIMIT_UNUSED", "ignored"]


#: Parameters that analysis=limit does not use (it has no elasticity, no
#: steps, and associated flow).
LIMIT_UNUSED = (
    "E",
    "nu",
    "psi",
    "K0",
    "settlement",
    "steps",
    "plateau_tol",
    "growth",
    "max_settlement",
    "max_steps",
    "large_deformation",
)


def ignored(values: Mapping[str, Any], given: frozenset[str]) -> None:
    """Refuse phi/psi with Tresca; warn about parameters the run does not use."""
    refuse_frictional(values, given)
    warn_dry_water(values, given)
    if values["analysis"] == "limit":
        warn_unused(
            given,
            LIMIT_UNUSED,
            "analysis=limit solves one rigid-plastic cone program on the "
            "initial mesh (no elasticity, no steps, associated flow); choose "
            "analysis=incremental to use them",
        )
    elif values["rho"] == 0:
        warn_unused(
            given, ("K0",), "a weightless soil (rho = 0) has no geostatic stress"
        )
    else:
        warn_unused(
            given,
            ("p0",),
            "a soil with weight (rho > 0) starts from its geostatic stress",
        )
