"""Pseudo-static shaking of the slope: a horizontal body force ``k_h`` x the weight.

A horizontal acceleration ``k_h g`` toward ``+x`` (out of the parametric
slope's face) loads every particle with ``k_h`` times its weight along
``+x``.  The factor of safety takes a constant ``kh`` with gravity; the
critical ``k_h`` (:func:`loaded_limits`) is one limit analysis with gravity as
the dead load and ``k_h`` as the multiplier; the run-out is shaken by the
constant or by a recorded history (a file of ``t, k_h`` rows,
:func:`~skfem_npfem.scenes.shaking.kh_history`) through
:attr:`~skfem_npfem.Model.kh`.  The pore pressure stays the static field
(its force is gravity's).  docs/theory.md ("Limit analysis") derives the
program.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from typing import Any

import numpy as np
from skfem import MeshTri

from ...constants import GRAVITY
from ...errors import ParameterError, SolverError, warn_user
from ...limit.loads import gravity_load
from ...limit.safety import CAP
from ...materials import Material
from ...mesh.smoothing import nodal_integration
from ...water import Water
from ..shaking import kh_history, kh_param, static_kh
from .surcharge import dead_load_multiplier, surcharge_collapse, surcharge_load
from .water import slope_water, static_pressure

__all__ = [
    "KH_PARAM",
    "SEISMIC_METRICS",
    "check_kh",
    "loaded_limits",
    "slope_loads",
]

KH_PARAM = kh_param(
    "toward +x (out of the slope's face; negative: into it)",
    "a number acts in the factor of safety and shakes the run-out; a file "
    "of rows t, k_h is a recorded history that shakes the run-out from its "
    "start, with the static factor of safety",
)

SEISMIC_METRICS = {
    "critical_kh": "analysis=limit: the pseudo-static k_h (toward +x, with "
    "gravity) at which the slope just fails with its strengths unreduced (one "
    "more limit analysis: gravity the dead load, k_h the multiplier, capped at "
    "1e3); null without analysis=limit or when gravity alone brings the slope "
    "down",
}


def check_kh(values: Mapping[str, Any]) -> None:
    """A history of ``kh`` is read (and refused) before anything is solved.

    It shakes the run-out only: without ``runout=true`` it is refused.
    """
    if kh_history(values) is not None and not values["runout"]:
        raise ParameterError(
            "kh",
            values["kh"],
            "a number without runout=true (a file of t, k_h rows shakes the "
            "run-out; the factor of safety takes a number)",
        )


def slope_loads(
    ni: Any,
    mats: list[Material],
    material: np.ndarray,
    mesh: MeshTri,
    water: Water | None,
) -> tuple[np.ndarray, np.ndarray]:
    """The slope's gravity load and the load of a unit pseudo-static ``k_h``.

    Gravity's load is the (saturated) weight plus the pore water's force
    (:func:`~skfem_npfem.limit.loads.gravity_load`); a horizontal
    acceleration ``k_h g`` toward ``+x`` (out of the parametric slope's face)
    puts ``k_h`` times the weight ``rho g V`` on every node along ``+x``
    (the mixture's inertia; the pore pressure stays the static field).

    Returns
    -------
    gravity : ndarray (N, 2)
        N.
    shaking : ndarray (N, 2)
        The load of ``k_h = 1``, N.
    """
    rho = np.array([m.rho for m in mats])[material]
    x = mesh.p.T
    p = static_pressure(water, x, mesh.t, material)
    gravity = gravity_load(ni, rho, GRAVITY, x=x, pore_pressure=p)
    shaking = np.zeros_like(gravity)
    shaking[:, 0] = rho * GRAVITY * np.asarray(ni.volumes, float)
    return gravity, shaking


def loaded_limits(
    values: Mapping[str, Any], body: Any, mats: list[Material]
) -> dict[str, Any]:
    """``critical_kh`` and ``surcharge_collapse`` of a limit run, - and Pa.

    Two limit analyses on the initial mesh (``body``: the slope's
    :class:`~.body.SlopeBody`), with the strengths as they are (``mats``:
    undrained, the undrained strengths of the factor of safety).  The critical
    ``k_h`` is the multiplier of a unit ``k_h``'s load (:func:`slope_loads`)
    with gravity (its water's force, a surcharge on the crest) held; the
    strip's collapse pressure holds gravity and a constant ``kh``
    (:func:`~.surcharge.surcharge_collapse`).  A slope that its dead load
    alone brings down has neither (None).
    """
    ni = nodal_integration(body.mesh, (0, 1, 3))
    water = slope_water(values, body.sec)
    gravity, shaking = slope_loads(ni, mats, body.material, body.mesh, water)
    strip = surcharge_load(body.pts, body.sec, values)
    held = gravity if strip is None else gravity + strip
    dead = gravity + static_kh(values) * shaking if static_kh(values) else gravity
    out: dict[str, Any] = {"notes": []}
    kh_run = partial(dead_load_multiplier, values, body, mats, ni, shaking, held, CAP)
    strip_run = partial(surcharge_collapse, values, body, mats, ni, dead)
    for name, run in (("critical_kh", kh_run), ("surcharge_collapse", strip_run)):
        try:
            out[name] = run()
        except SolverError as err:
            # A second analysis: its failure must not cost the factor of safety.
            out[name] = None
            out["notes"].append(
                f"slope: {name} was not found ({err}); the factor of safety stands"
            )
            warn_user(out["notes"][-1])
    return out
