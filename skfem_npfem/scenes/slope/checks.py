"""What the slope scene refuses, and what it warns is unused.

:func:`ignored` is the scene's check of the chosen material, section and
stages, run before anything is solved.
"""

from __future__ import annotations

from typing import Any

from ...errors import ParameterError
from ..common import refuse_frictional, warn_unused
from ..refinement import check_refine
from ..soil_profile import check_layers
from .profile import check_profile
from .push import check_push, pushing
from .seismic import check_kh
from .surcharge import check_surcharge

__all__ = ["ignored"]

#: Parameters only the failure and run-out stage uses.
RUNOUT_ONLY = (
    "psi",
    "reduction",
    "margin",
    "dt",
    "t_end",
    "rest_fraction",
    "alpha",
    "max_displacement",
)

#: What the footing's push uses of :data:`RUNOUT_ONLY`.
PUSH_USES = ("psi", "alpha")

#: The cross-section's own parameters (a geometry file replaces them).
SECTION = ("height", "angle", "foundation_depth", "crest_length", "toe_length")


def ignored(values: dict[str, Any], given: frozenset[str]) -> None:
    """Refuse what the chosen material, section or analysis would ignore silently.

    ``phi``/``psi`` with Tresca, Tresca with a cross-section file (whose
    regions are Mohr-Coulomb) and ``runout=true`` with ``analysis=limit`` are
    refused; parameters of a stage that does not run are warned about.
    """
    refuse_frictional(values, given)
    limit = values["analysis"] == "limit"
    # Undrained, the factor of safety needs the initial effective stresses.
    stresses = not limit or values.get("drainage") == "undrained"
    if values["geometry"]:
        if values["material"] == "tresca":
            raise ParameterError(
                "material",
                "tresca",
                "mohr-coulomb with geometry (the regions of a cross-section "
                "file are Mohr-Coulomb: give a material phi = 0 there for an "
                "undrained clay)",
            )
        warn_unused(given, SECTION, "geometry (the cross-section file) replaces them")
    if limit and values["runout"]:
        raise ParameterError(
            "runout",
            True,
            "false with analysis=limit (one cone program: no failure and "
            "run-out stage); choose analysis=incremental for the run-out",
        )
    check_kh(values)
    check_surcharge(values)
    check_push(values)
    check_layers(values)
    check_refine(values, True, "surface", values["runout"] and not limit)
    check_profile(values)
    if not stresses:
        warn_unused(
            given,
            ("E", "nu", "initial_stress", "K0"),
            "analysis=limit solves one rigid-plastic cone program (no "
            "elasticity, no initial stresses)",
        )
    elif values["initial_stress"] == "gravity":
        warn_unused(
            given, ("K0",), "initial_stress=gravity (K0 sets initial_stress=k0)"
        )
    if pushing(values):
        warn_unused(
            given,
            tuple(n for n in RUNOUT_ONLY if n not in PUSH_USES),
            "push_depth > 0 pushes a footing instead of the run-out",
        )
    elif limit or not values["runout"]:
        warn_unused(
            given,
            RUNOUT_ONLY,
            "the run-out stage does not run (it needs runout=true with "
            "analysis=incremental)",
        )
    if not pushing(values):
        warn_unused(
            given,
            ("push_speed",),
            "no footing is pushed (it needs push_depth > 0 with analysis=incremental)",
        )
