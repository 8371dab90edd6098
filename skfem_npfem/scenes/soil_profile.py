"""Scene parameters of a soil's strength: growing with depth, softening, rate.

``su_gradient`` (k, Pa/m) makes a scene's cohesion, or undrained strength,
``s_u(z) = s_u0 + k z`` with ``z`` the depth below the ground and ``s_u0`` the
scene's own strength parameter; ``stiffness_profile`` says whether ``E``
follows it (``strength``: ``E`` proportional to ``s_u``, a uniform rigidity
index) or stays uniform.  The factors go on the particles
(:func:`~skfem_npfem.profiles.linear_strength`), so the step, the limit
analysis and the factor of safety all see the same profile.

``sensitivity``, ``ductility``, ``rate_parameter`` and ``reference_rate`` are
the clay's softening and rate law (:class:`~skfem_npfem.strength_laws.ClayStrength`),
``softening_length`` its regularisation: the softening reads the plastic
shear strain averaged over that distance
(:func:`~skfem_npfem.strength_laws.nonlocal_average`), so that a band is as
wide on every lattice.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..particles import Particles
from ..profiles import StrengthProfile
from ..strength_laws import ClayStrength
from .params import POSITIVE, Param

__all__ = [
    "CLAY_PARAMS",
    "PROFILE_PARAMS",
    "UNIFORM_VALUES",
    "check_layers",
    "clay_law",
    "has_profile",
    "profile_factors",
    "strength_profile",
    "with_profile",
]

#: The strength parameters at the values of a uniform, ideally plastic soil
#: (a run with these records none of them).
UNIFORM_VALUES = {
    "su_gradient": 0.0,
    "layers": None,
    "stiffness_profile": "strength",
    "sensitivity": 1.0,
    "ductility": 10.0,
    "rate_parameter": 0.0,
    "reference_rate": 3.0e-6,
    "softening_length": None,
}

#: How ``E`` follows a strength profile.
STIFFNESS_PROFILES = ("strength", "uniform")


def profile_params(strength: str) -> list[Param]:
    """``su_gradient``, ``layers``, ``stiffness_profile``; ``strength``: ``s_u0``."""
    return [
        Param(
            "su_gradient",
            0.0,
            "Pa/m",
            f"increase of the strength with depth below the ground, k: "
            f"s_u(z) = {strength} + k z (0: a uniform soil)",
            float,
            lo=0.0,
        ),
        Param(
            "layers",
            None,
            "-",
            "layered strength: a JSON list of [top, s_u] or [top, s_u, k] rows, "
            "each layer's top (m below the ground; the first 0), its strength "
            "there (Pa) and its increase with depth (Pa/m, default 0), down to "
            f"the next top; replaces su_gradient ({strength} stays the strength "
            "the scene's factors are over; default none)",
            str,
        ),
        Param(
            "stiffness_profile",
            "strength",
            "-",
            "with su_gradient or layers: strength (E proportional to s_u(z), a "
            "uniform rigidity index) or uniform (E the same at every depth)",
            str,
            STIFFNESS_PROFILES,
        ),
    ]


#: The profile parameters of a scene whose strength parameter is ``c``.
PROFILE_PARAMS = profile_params("c")


def has_profile(values: Mapping[str, Any]) -> bool:
    """Whether the run's strength varies with depth."""
    return values.get("su_gradient", 0.0) > 0.0 or values.get("layers") is not None


def check_layers(values: Mapping[str, Any]) -> None:
    """Refuse ``layers`` that are not layers (when the values are resolved)."""
    if values.get("layers") is not None:
        strength_profile(values, 1.0)


def strength_profile(values: Mapping[str, Any], s0: float) -> StrengthProfile:
    """The run's ``s_u(z)``: its ``layers``, else ``s0 + su_gradient z``.

    Raises
    ------
    ParameterError
        ``layers`` that is not JSON rows of layers, or given with
        ``su_gradient``.
    """
    text = values.get("layers")
    if text is None:
        return StrengthProfile.linear(s0, values.get("su_gradient", 0.0))
    if values.get("su_gradient", 0.0) > 0.0:
        raise ParameterError(
            "su_gradient",
            values["su_gradient"],
            "0 with layers (each layer has its own gradient: [top, s_u, k])",
        )
    try:
        rows = json.loads(text)
    except json.JSONDecodeError as err:
        raise ParameterError("layers", text, f"JSON rows ({err.msg})") from None
    try:
        return StrengthProfile.from_rows(rows)
    except ParameterError as err:  # name the text as it was given
        raise ParameterError("layers", text, err.allowed) from None


def profile_factors(
    values: Mapping[str, Any], depth: np.ndarray, s0: float, name: str = "c"
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Strength and stiffness factors at ``depth`` (None, None: uniform).

    Parameters
    ----------
    values : mapping
        The run's parameters (``su_gradient``, ``layers``,
        ``stiffness_profile``).
    depth : ndarray (N,)
        Depth of each particle below the ground, m.
    s0 : float
        The strength at the ground, Pa (the scene's ``name`` parameter): the
        factors are ``s_u(z) / s0``.
    name : str
        The scene's strength parameter, for the error of ``s0 <= 0``.

    Raises
    ------
    ParameterError
        A profile with no strength at the ground to scale.
    """
    if not has_profile(values):
        return None, None
    if not s0 > 0:
        raise ParameterError(
            name,
            s0,
            f"> 0 with su_gradient or layers (the factors are s_u(z) / {name})",
        )
    f = strength_profile(values, s0).at(depth) / s0
    return f, (f.copy() if values["stiffness_profile"] == "strength" else None)


def with_profile(
    values: Mapping[str, Any],
    particles: Particles,
    depth: np.ndarray,
    s0: float,
    name: str = "c",
) -> Particles:
    """The particles with the factors of the run's profile (unchanged if uniform).

    As :func:`profile_factors`, whose arguments these are.
    """
    strength, stiffness = profile_factors(values, depth, s0, name)
    if strength is None:
        return particles
    return particles.replace(strength=strength, stiffness=stiffness)


#: The clay's softening and rate law (``material=tresca``).
CLAY_PARAMS = [
    Param(
        "sensitivity",
        1.0,
        "-",
        "S_t: intact over remoulded strength; the strength softens to s_u/S_t "
        "with the accumulated plastic shear strain (1: no softening)",
        float,
        lo=1.0,
        hi=1.0e3,
    ),
    Param(
        "ductility",
        10.0,
        "-",
        "xi_95: the accumulated plastic shear strain at 95 % of the softening",
        float,
        **POSITIVE,
    ),
    Param(
        "rate_parameter",
        0.0,
        "-",
        "mu: the strength's rise per decade of plastic shear-strain rate above "
        "reference_rate (0: rate independent; about 0.1 in clays)",
        float,
        lo=0.0,
        hi=1.0,
    ),
    Param(
        "reference_rate",
        3.0e-6,
        "1/s",
        "the shear-strain rate of the reference strength (a laboratory test's, "
        "about 1 %/hour)",
        float,
        **POSITIVE,
    ),
    Param(
        "softening_length",
        None,
        "m",
        "regularisation: the softening reads the plastic shear strain averaged "
        "over this distance (nonlocal; a few spacings or more; default none: "
        "each particle's own)",
        float,
        **POSITIVE,
    ),
]


def clay_law(values: Mapping[str, Any]) -> ClayStrength | None:
    """The run's softening and rate law (None for an ideally plastic soil)."""
    if values["sensitivity"] == 1.0 and values["rate_parameter"] == 0.0:
        return None
    if values.get("material", "tresca") != "tresca":
        raise ParameterError(
            "sensitivity" if values["sensitivity"] != 1.0 else "rate_parameter",
            values["sensitivity"]
            if values["sensitivity"] != 1.0
            else values["rate_parameter"],
            "left at its default unless material=tresca (the law is an "
            "undrained strength's)",
        )
    return ClayStrength(
        sensitivity=values["sensitivity"],
        ductility=values["ductility"],
        rate_parameter=values["rate_parameter"],
        reference_rate=values["reference_rate"],
        length=values["softening_length"] or 0.0,
    )
