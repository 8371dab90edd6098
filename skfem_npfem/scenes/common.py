"""Helpers shared by the scenes: solver and size parameters, the result writer.

The up-front size and step-count checks live in :mod:`.limits`
(:func:`~.limits.check_size`, :func:`~.limits.check_steps`); scenes call
:func:`check_size` with their particle count before building anything.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..io import ResultWriter, checkpoint_step
from ..step.model import NODAL_MASS
from ..step.solver import ACCURACY_PRESETS, LINEAR_SOLVERS, SolverOptions
from ..step.stabilisation import STABILISATION_MODES
from .params import POSITIVE, Param

__all__ = [
    "elastic_params",
    "make_writer",
    "solver_from",
    "solver_params",
    "window_mean",
]


def elastic_params(E: float) -> list[Param]:
    """Young's modulus (default ``E``, Pa) and Poisson's ratio parameters."""
    return [
        Param("E", E, "Pa", "Young's modulus", float, **POSITIVE),
        Param(
            "nu",
            0.3,
            "-",
            "Poisson's ratio",
            float,
            lo=-1,
            hi=0.5,
            lo_open=True,
            hi_open=True,
        ),
    ]


def solver_params() -> list[Param]:
    """Parameters every scene exposes for the cone solver and the size check."""
    return [
        Param(
            "linear_solver", "auto", "-", "Clarabel direct solver", str, LINEAR_SOLVERS
        ),
        Param(
            "threads",
            0,
            "-",
            "threads of the faer / MKL Pardiso solver (0: automatic)",
            int,
            lo=0,
        ),
        Param(
            "reproducible",
            True,
            "-",
            "MKL Pardiso: bit-identical reruns and resumes (false: ~20 % faster "
            "MKL steps, round-off varies between runs)",
            bool,
        ),
        Param(
            "tol",
            1e-8,
            "-",
            "interior-point tolerances",
            float,
            lo=0,
            hi=1e-2,
            lo_open=True,
            hi_open=True,
        ),
        Param(
            "accuracy",
            None,
            "-",
            "solver preset (overrides tol): high = tol 1e-8, fast = tol 1e-6 "
            "(default: use tol)",
            str,
            tuple(ACCURACY_PRESETS),
        ),
        Param(
            "size_check",
            True,
            "-",
            "refuse a run estimated to need more memory than this machine has "
            "or more than 1e6 steps (false: run it anyway)",
            bool,
        ),
    ]


def solver_from(values: Mapping[str, Any]) -> SolverOptions:
    """SolverOptions from resolved scene values."""
    return SolverOptions(
        linear_solver=values["linear_solver"],
        max_threads=values["threads"],
        tol=values["tol"],
        accuracy=values.get("accuracy"),
        reproducible=values.get("reproducible", True),
    )


def make_writer(out: str | Path | None, resume: bool = False):
    """A :class:`~skfem_npfem.io.ResultWriter` for ``out`` (None: no output).

    With ``resume`` the steps up to the latest checkpoint in ``out`` are kept
    (and later ones deleted), so the continued run appends to the series.  The
    writer is deferred: it touches no file in ``out`` before the scene runner
    has finished its checks and calls :meth:`~skfem_npfem.io.ResultWriter.open`
    (or the first step is written).
    """
    if out is None:
        return None
    after = checkpoint_step(out)[1] if resume else None
    return ResultWriter(out, resume_after_step=after, defer=True)


def fidelity_params(
    stabilisation: float,
    where: str = "",
    volume_correction: float = 0.0,
    kappa_where: str = "",
    mode: str = "full",
    mode_where: str = "",
) -> list[Param]:
    """The stress stabilisation, the nodal-mass rule and the volume correction.

    ``stabilisation`` and ``volume_correction`` are the scene's defaults of
    ``beta`` and ``kappa`` for N-PFEM, chosen from measurements
    (docs/validation.md); see :class:`~skfem_npfem.step.model.Model`.  ``where``
    qualifies the stabilisation's default in the help (e.g. "in plane strain"),
    ``kappa_where`` the volume correction's; ``mode`` and ``mode_where`` the
    default ``stabilisation_mode`` and its qualifier.
    """
    if volume_correction:
        kappa_default = None
        kappa_help = (
            f"default {volume_correction:g} for method=npfem{kappa_where}, else 0; "
            "0: off"
        )
    else:
        kappa_default, kappa_help = 0.0, "method=npfem only; 0: off"
    if stabilisation:
        beta_help = (
            f"default {stabilisation:g} for method=npfem{where}, 0 for the other "
            "methods; 0: off"
        )
    else:  # off by default for every method of the scene
        beta_help = "default 0: off; > 0 with method=npfem only"
    return [
        Param(
            "stabilisation",
            None,
            "-",
            "factor beta of the consistent element-residual stabilisation of the "
            f"N-PFEM stresses ({beta_help}; docs/theory.md)",
            float,
            lo=0,
            hi=1e4,
        ),
        Param(
            "stabilisation_mode",
            None,
            "-",
            "what the stabilisation couples: full (every stress component), "
            "vertical (the vertical momentum row), sigma_v (only the vertical "
            "normal stress), mean (only the mean stress, one auxiliary scalar "
            f"per particle); default {mode}{mode_where}; the reduced modes fill "
            "the step's factor less (docs/theory.md)",
            str,
            STABILISATION_MODES,
        ),
        Param(
            "nodal_mass",
            "mesh",
            "-",
            "node masses: mesh = cell volume x the material's mean density (exact "
            "total, uniform load density); particle = each particle's own mass",
            str,
            NODAL_MASS,
        ),
        Param(
            "volume_correction",
            kappa_default,
            "-",
            "rate kappa at which a uniform volumetric eigenstrain returns the "
            "volume deficit (particle masses / rho against the mesh): it decays "
            f"as (1 + kappa n)(1 - kappa)^n over n steps ({kappa_help}; "
            "docs/theory.md)",
            float,
            lo=0,
            hi=1,
        ),
    ]


def fidelity_from(
    values: Mapping[str, Any],
    stabilisation: float,
    volume_correction: float = 0.0,
    mode: str = "full",
) -> dict[str, Any]:
    """Model keyword arguments of :func:`fidelity_params`.

    ``stabilisation``, ``volume_correction`` and ``mode`` are the scene's
    defaults for N-PFEM (the other methods default to 0).

    Raises
    ------
    ParameterError
        For a stabilisation or a volume correction > 0 with a method other than
        N-PFEM (both are defined for nodal stresses and cells).
    """
    beta = values["stabilisation"]
    method = values.get("method", "npfem")
    if beta is None:
        beta = stabilisation if method == "npfem" else 0.0
    elif beta > 0 and method != "npfem":
        raise ParameterError(
            "stabilisation",
            beta,
            f"0 with method={method} (the element-residual stabilisation is "
            "defined for the nodal stresses of N-PFEM)",
        )
    kappa = values.get("volume_correction", 0.0)
    if kappa is None:
        kappa = volume_correction if method == "npfem" else 0.0
    kappa = float(kappa)
    if kappa > 0 and method != "npfem":
        raise ParameterError(
            "volume_correction",
            kappa,
            f"0 with method={method} (the volume correction acts on the nodal "
            "cells of N-PFEM)",
        )
    out = {
        "stabilisation": float(beta),
        "nodal_mass": values["nodal_mass"],
        "volume_correction": kappa,
    }
    chosen = values.get("stabilisation_mode")
    if chosen is not None or mode != "full":
        out["stabilisation_mode"] = mode if chosen is None else chosen
    return out


def fill_at_rest(values: dict[str, Any]) -> None:
    """Fill ``K0`` left at None with Jaky's ``1 - sin phi`` (in place).

    Examples
    --------
    >>> v = {"phi": 30.0, "K0": None}
    >>> fill_at_rest(v)
    >>> v["K0"]
    0.5
    """
    if values["K0"] is None:
        values["K0"] = 1.0 - math.sin(math.radians(values["phi"]))


def check_soil(values: Mapping[str, Any]) -> None:
    """Psi <= phi, and a cohesionless Mohr-Coulomb K0 inside the yield cone.

    Raises
    ------
    ParameterError
        Naming ``psi`` or ``K0`` and the allowed range.
    """
    phi, psi, K0 = values["phi"], values["psi"], values["K0"]
    if psi > phi:
        raise ParameterError("psi", psi, f"at most phi = {phi:g} degrees")
    if values["material"] == "mohr-coulomb" and values["c"] == 0:
        s = math.sin(math.radians(phi))
        lo, hi = (1 - s) / (1 + s), (1 + s) / (1 - s)
        if not lo <= K0 <= hi:
            raise ParameterError(
                "K0", K0, f"in [{lo:.4g}, {hi:.4g}] (inside the yield cone)"
            )


def refuse_frictional(values: Mapping[str, Any], given: frozenset[str]) -> None:
    """Refuse ``phi`` or ``psi`` given (non-zero) with ``material=tresca``.

    Tresca has neither a friction nor a dilation angle, so the value would be
    ignored while the summary records it.

    Raises
    ------
    ParameterError
        Naming the angle, its value and the materials that use it.
    """
    if values["material"] != "tresca":
        return
    for name, what in (("phi", "friction"), ("psi", "dilation")):
        if name in given and values[name]:
            raise ParameterError(
                name,
                values[name],
                f"0 or left out with material=tresca (Tresca has no {what} "
                f"angle); choose material=mohr-coulomb for {name} = "
                f"{values[name]:g} degrees",
            )


def warn_unused(given: frozenset[str], names: Iterable[str], why: str) -> None:
    """Warn that the given ones of ``names`` are not used, and why.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_unused(frozenset({"E", "c"}), ("E", "nu"), "analysis=limit")
    >>> str(w[0].message)
    'E not used: analysis=limit'
    """
    unused = [name for name in names if name in given]
    if unused:
        warnings.warn(f"{', '.join(unused)} not used: {why}", stacklevel=5)


def window_mean(
    curve: list[list[float]], w: float, half: float
) -> tuple[float | None, list[float] | None]:
    """Mean of a ``[x, y]`` curve over ``[w - half, w + half]`` and its range there.

    The curve starts from ``(0, 0)`` (a load-settlement curve of steps).

    The window is cut at the curve's end; None when the curve stops short of
    ``w``.  The mean is that of the linear interpolant (the trapezoidal
    integral over the window's length).

    Examples
    --------
    >>> window_mean([[0.1, 1.0], [0.2, 3.0], [0.3, 1.0]], 0.2, 0.1)
    (2.0, [1.0, 3.0])
    """
    if not curve or curve[-1][0] < w * (1 - 1e-9):
        return None, None
    c = np.array([[0.0, 0.0], *curve])
    lo, hi = max(w - half, 0.0), min(w + half, c[-1, 0])
    if hi <= lo:
        value = float(np.interp(w, c[:, 0], c[:, 1]))
        return value, [value, value]
    inner = c[(c[:, 0] > lo) & (c[:, 0] < hi)]
    ws = np.concatenate([[lo], inner[:, 0], [hi]])
    qs = np.interp(ws, c[:, 0], c[:, 1])
    mean = float(np.sum(0.5 * (qs[1:] + qs[:-1]) * np.diff(ws)) / (hi - lo))
    return mean, [float(qs.min()), float(qs.max())]
