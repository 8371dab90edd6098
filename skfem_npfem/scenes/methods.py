"""The method of a scene: N-PFEM, FEM with remapping, or the explicit SPFEM.

Every scene where the choice makes sense adds :data:`METHOD_PARAMS` to its
parameters, :data:`METHOD_METRICS` to its metrics and passes its finished
:class:`~skfem_npfem.scenes.base.SceneRun` through :func:`with_method`.  The
run then keeps the scene's particles, walls, mesh source, time stepping,
callbacks and output; only the step changes (``Simulation.stepper``), so a
comparison changes one word: ``--set method=fem-remap``.

This module is the one place where a method is chosen by name:
:func:`make_method` checks the name and its options (an unknown method, or an
``element``/``transfer`` given to a method other than fem-remap, or
``damping``/``explicit_dt`` to one other than spfem), and
:meth:`~skfem_npfem.baseline.SPFEM.check` checks the run (a quasi-static scene,
an explicit step above the stable one): each is one
:class:`~skfem_npfem.errors.ParameterError` before the first step.

Every method reports the stress roughness of :mod:`skfem_npfem.metrics`
(on each step record and in the summary) and the method-specific metrics of
:data:`METHOD_METRICS` (``null`` for the methods they do not apply to).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..baseline import SPFEM, TRANSFERS, FemRemap
from ..baseline.operators import ELEMENTS
from ..errors import ParameterError
from ..metrics import stress_roughness
from ..profiles import profile_point_data
from .base import SceneRun
from .params import POSITIVE, Param

__all__ = [
    "METHODS",
    "METHOD_METRICS",
    "METHOD_METRICS_NO_SPFEM",
    "METHOD_OPTIONS",
    "METHOD_PARAMS",
    "make_method",
    "method_metrics",
    "method_params",
    "with_method",
]

#: Method names: the library's N-PFEM, FEM with remapping, explicit SPFEM.
METHODS = ("npfem", "fem-remap", "spfem")

#: Options each method accepts.
METHOD_OPTIONS: dict[str, tuple[str, ...]] = {
    "npfem": (),
    "fem-remap": ("element", "transfer"),
    "spfem": ("damping", "explicit_dt"),
}


def make_method(name: str, **options: Any) -> FemRemap | SPFEM | None:
    """Build a baseline method object (None for N-PFEM, the library's step).

    Parameters
    ----------
    name : {"npfem", "fem-remap", "spfem"}
    **options
        ``element``, ``transfer`` (fem-remap) or ``damping``, ``explicit_dt``
        (spfem); options given as None are ignored.

    Raises
    ------
    ParameterError
        Unknown method, an option the method does not have, or a bad value.

    Examples
    --------
    >>> make_method("fem-remap", element="p2", transfer="nearest")
    FemRemap(element='p2', transfer='nearest')
    >>> make_method("spfem", element="p2")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    skfem_npfem.errors.ParameterError: invalid element='p2': spfem has no option ...
    """
    if name not in METHODS:
        raise ParameterError("method", name, f"one of {METHODS}")
    given = {k: v for k, v in options.items() if v is not None}
    allowed = METHOD_OPTIONS[name]
    for key, value in given.items():
        if key not in allowed:
            has = ", ".join(allowed) if allowed else "none"
            raise ParameterError(
                key, value, f"{name} has no option {key}; its options: {has}"
            )
    if name == "fem-remap":
        return FemRemap(**given)
    if name == "spfem":
        return SPFEM(**given)
    return None


def method_params(
    methods: tuple[str, ...] = tuple(METHODS), spfem: str = "", missing: str = ""
) -> list[Param]:
    """The method parameters of a scene that offers ``methods``.

    Parameters
    ----------
    methods : tuple of str
        The methods the scene can run (a subset of
        :data:`METHODS`); the parameters of a method not
        offered (``damping``, ``explicit_dt`` of spfem; ``element``,
        ``transfer`` of fem-remap) are left out.
    spfem : str
        When spfem is offered: where it runs, added to the help (e.g.
        ``"mode=dynamic only"``).
    missing : str
        Why the methods left out are not offered (shown with the allowed
        values, so ``--set method=spfem`` says it).
    """
    what = {
        "npfem": "npfem (nodal integration, cone program)",
        "fem-remap": "fem-remap (Gauss-point state remapped after each remesh, "
        "same cone program)",
        "spfem": f"spfem (explicit nodal integration{'; ' + spfem if spfem else ''})",
    }
    names = [what[m] for m in methods]
    text = ", ".join(names[:-1]) + " or " + names[-1] if len(names) > 1 else names[0]
    params = [Param("method", "npfem", "-", text, str, tuple(methods), note=missing)]
    if "fem-remap" in methods:
        params += [
            Param(
                "element",
                None,
                "-",
                "fem-remap only: p1 or p2 elements (default p1)",
                str,
                ELEMENTS,
            ),
            Param(
                "transfer",
                None,
                "-",
                "fem-remap only: nearest or recovery (patch recovery + "
                "interpolation) transfer of Gauss-point state to a new mesh "
                "(default recovery)",
                str,
                TRANSFERS,
            ),
        ]
    if "spfem" in methods:
        params += [
            Param(
                "damping",
                None,
                "1/s",
                "spfem only: mass-proportional damping coefficient (default 0)",
                float,
                lo=0,
            ),
            Param(
                "explicit_dt",
                None,
                "s",
                "spfem only: explicit substep, at most the stable step (default "
                "0.9 x the stable step of each step's mesh)",
                float,
                **POSITIVE,
            ),
        ]
    return params


#: The method parameters of a dynamic scene (every method).
METHOD_PARAMS = method_params()

METHOD_METRICS = {
    "stress_roughness": "stress roughness R of the vertical stress at the last "
    "step: rms over interior particles of (s_i - mean of its mesh neighbours) / "
    "rms(s_i) (skfem_npfem.stress_roughness; ~0 for a smooth field, ~1 for "
    "a checkerboard)",
    "stress_roughness_max": "largest stress roughness over the steps",
    "yield_violations": "fem-remap: mapped Gauss-point stresses outside the yield "
    "surface, returned to it, summed over the run (null: other methods)",
    "remapped_steps": "fem-remap: steps whose mesh changed, so the Gauss-point "
    "state was transferred (null: other methods)",
    "outside_old_mesh": "fem-remap: new Gauss points outside the previous mesh "
    "(given the nearest value), summed over the run (null: other methods)",
    "explicit_steps": "spfem: explicit substeps of the run (the steps of the "
    "summary are the output steps of dt) (null: other methods)",
    "stable_dt": "spfem: smallest stable explicit step of the run's meshes, s "
    "(null: other methods)",
    "explicit_dt": "spfem: largest explicit substep used, s (null: other methods)",
}

#: :data:`METHOD_METRICS` of a scene that does not offer spfem.
METHOD_METRICS_NO_SPFEM = METHOD_METRICS | {
    k: "spfem only: always null here (spfem is not available in this scene)"
    for k in ("explicit_steps", "stable_dt", "explicit_dt")
}

#: Record keys summed (or reduced) into each method-specific metric.
_FROM_RECORDS = {
    "yield_violations": ("yield_violations", sum),
    "remapped_steps": ("remapped", sum),
    "outside_old_mesh": ("outside_old_mesh", sum),
    "explicit_steps": ("substeps", sum),
    "stable_dt": ("stable_dt", min),
    "explicit_dt": ("explicit_dt", max),
}


def with_method(values: Mapping[str, Any], srun: SceneRun) -> SceneRun:
    """Run a scene with the method of ``values`` (see the module notes).

    Raises
    ------
    ParameterError
        For a bad method or option (:func:`make_method`),
        SPFEM in a quasi-static run, a baseline with a soil profile or with
        particle insertion (``refine``), or an
        ``explicit_dt`` above the stable step of the initial mesh.
    """
    name = values["method"]
    method = make_method(
        name,
        element=values.get("element"),
        transfer=values.get("transfer"),
        damping=values.get("damping"),
        explicit_dt=values.get("explicit_dt"),
    )
    sim = srun.simulation
    if method is not None and profile_point_data(sim.particles):
        raise ParameterError(
            "method",
            name,
            "npfem with a soil profile (su_gradient): a baseline keeps one "
            "strength and stiffness per material",
        )
    if method is not None and sim.refiner is not None:
        raise ParameterError(
            "method",
            name,
            "npfem with refine (a baseline keeps its own state per element or "
            "node and takes no added particles)",
        )
    if method is not None:  # what a baseline would refuse at its first step
        sim.model.refuse_loads(name)
    if isinstance(method, SPFEM):
        if sim.model.mode != "dynamic":
            raise ParameterError(
                "method",
                name,
                "npfem or fem-remap for a quasi-static run: spfem is explicit and "
                "needs inertia (mode=dynamic)",
            )
        method.check(sim.particles, sim.model, sim.mesh_source)
    if method is not None:
        sim.particles = method.initial_state(sim.particles, sim.mesh_source)
        sim.stepper = method.advance
    sim.callbacks.append(_record_roughness)
    scene_metrics = srun.metrics
    srun.metrics = lambda s: {**scene_metrics(s), **method_metrics(s)}
    return srun


def _record_roughness(sim: Any, p: Any, result: Any) -> bool:
    """Callback: the step's stress roughness on its record (kept by checkpoints)."""
    result.record.extra["stress_roughness"] = stress_roughness(result.cells, p.stress)
    return False


def method_metrics(sim: Any) -> dict[str, Any]:
    """The :data:`METHOD_METRICS` of a finished run.

    The method itself is the ``method`` parameter of the summary.  Metrics
    that do not apply (or need more interior particles) are None (``null`` in
    the JSON summary).
    """
    recs = sim.records
    # NaN (too few interior particles) comes back from a checkpoint as None.
    rough = [r.extra.get("stress_roughness") for r in recs]
    rough = [np.nan if v is None else float(v) for v in rough]
    finite = [v for v in rough if np.isfinite(v)]
    out: dict[str, Any] = {
        "stress_roughness": rough[-1] if rough and np.isfinite(rough[-1]) else None,
        "stress_roughness_max": max(finite) if finite else None,
    }
    for metric, (key, reduce) in _FROM_RECORDS.items():
        vals = [r.extra[key] for r in recs if key in r.extra]
        out[metric] = reduce(vals) if vals else None
    return out
