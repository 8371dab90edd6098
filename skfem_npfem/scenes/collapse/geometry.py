"""The ``geometry`` option of the column-collapse scene.

``column-collapse --set geometry=plane-strain|axisymmetric|quarter-cylinder|box``:

* ``plane-strain`` (default): :mod:`skfem_npfem.scenes.collapse.plane_strain`,
  unchanged (the same particles, steps and metrics);
* ``axisymmetric``: a cylindrical column as the ``(r, z)`` half-section of
  :mod:`skfem_npfem.mesh.axisymmetric` (masses and volumes of the full ring);
* ``quarter-cylinder``: the same column in 3D, the quarter ``x, y >= 0``:
  particles on a symmetry plane have their normal displacement fixed, and the
  planes are frictionless walls for the others (:mod:`.cylinder`);
* ``box``: the plane-strain column in 3D, a slab between frictionless walls
  (:mod:`.box_column`).

The cylindrical geometries default to the reference paper's seed column
(:data:`~skfem_npfem.scenes.collapse.cylinder.SEED`: ``r0 = 3.9`` cm, ``h0 = 7.8`` cm,
the soil of the plane-strain defaults, ``dt = 2`` ms, Drucker-Prager matched to
Mohr-Coulomb in triaxial compression, spacing ``r0/18``); the quarter cylinder
runs with :data:`QUARTER_SPEED` unless told otherwise.  Two of ``radius``,
``height`` and ``aspect`` fix the third; the defaults fill ``radius`` first,
then ``aspect``.  A parameter the chosen geometry does not use, given
explicitly, is refused (``aspect`` with both ``radius`` and ``height``,
``symmetric`` or ``half_width`` with a cylindrical geometry, ...), as is a spacing
above ``r0/4`` or a run whose estimated memory exceeds the machine's
(:func:`~.limits.check_size` with the particle count of :mod:`.sizing`).
:class:`GeometryScene` is a scene whose :meth:`~GeometryScene.resolve` knows
which parameters were given; :mod:`.runs` builds the runs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ...errors import ParameterError, warn_user
from ..base import Scene
from ..common import check_soil, fill_at_rest
from ..limits import LENGTH, check_size
from ..params import POSITIVE, Param, Values
from ..shaking import kh_history
from ..water import derive_drainage
from ..wet_soil import warn_dry_water
from .box_column import DEPTH_SPACINGS
from .cylinder import GEOMETRY_ALPHA, SEED, SEED_DIVISIONS
from .sizing import lattice_particles

__all__ = [
    "CYLINDRICAL",
    "GEOMETRIES",
    "GEOMETRY_METRICS",
    "GEOMETRY_PARAMS",
    "QUARTER_FIXED",
    "QUARTER_SPEED",
    "GeometryScene",
    "finalize",
    "metrics_doc",
    "used_parameters",
]

GEOMETRIES = ("plane-strain", "axisymmetric", "quarter-cylinder", "box")
CYLINDRICAL = ("axisymmetric", "quarter-cylinder")
DP_MATCHES = ("plane-strain", "compression", "extension")
#: Time step of the seed case, s.
SEED_DT = SEED["dt"]
#: The quarter cylinder's speed defaults: a graded lattice (fine along the free
#: surfaces and the floor, twice as coarse in the core), the solver preset
#: ``fast`` and steps of up to 6 ms that keep the largest particle displacement
#: a step near one mean particle spacing of the mesh (a step that moves further
#: shortens the next; :class:`~skfem_npfem.run.Simulation`'s
#: ``max_displacement``).  Each applies unless its own parameters are given
#: (``refine``; ``accuracy`` or ``tol``; ``dt`` or ``max_displacement``: a
#: ``dt`` given alone is a fixed step).  docs/performance.md measures them.
QUARTER_SPEED: dict[str, Any] = {
    "refine": "surface",
    "accuracy": "fast",
    "dt": 6e-3,
    "max_displacement": 1.0,
}
#: Overrides that turn :data:`QUARTER_SPEED` off: the uniform lattice, the
#: interior-point tolerance 1e-8 and the paper's fixed 2 ms (what the quarter
#: cylinder ran before it had speed defaults).
QUARTER_FIXED: dict[str, Any] = {"refine": "none", "tol": 1e-8, "dt": SEED_DT}

GEOMETRY_PARAMS = [
    Param(
        "geometry",
        "plane-strain",
        "-",
        "model of the column: plane-strain (2D), axisymmetric ((r, z) half-section "
        "of a cylinder), quarter-cylinder (3D quarter, symmetry planes x = 0 and "
        "y = 0: normal displacement fixed on them, frictionless walls for the "
        "other particles), box (3D slab of the plane-strain column between smooth "
        "walls). "
        "The cylindrical geometries default to the seed column (radius 3.9 cm, "
        "height 7.8 cm, spacing r0/18, dt = 2 ms, Drucker-Prager compression "
        "match; the quarter cylinder with its speed defaults: refine=surface, "
        "accuracy=fast, steps of up to 6 ms with max_displacement 1); box: "
        "Drucker-Prager plane-strain match",
        str,
        GEOMETRIES,
    ),
    Param(
        "radius",
        None,
        "m",
        "cylindrical geometries: column radius r0 (default 3.9 cm, or height / aspect)",
        float,
        **LENGTH,
    ),
    Param(
        "height",
        None,
        "m",
        "cylindrical geometries: column height h0 (default aspect * r0: 7.8 cm)",
        float,
        **POSITIVE,
    ),
    Param(
        "depth",
        None,
        "m",
        f"box: slab depth W between the smooth walls y = 0 and y = W (default "
        f"{DEPTH_SPACINGS} spacings)",
        float,
        **LENGTH,
    ),
    Param(
        "buried_slivers",
        "keep",
        "-",
        "3D (quarter-cylinder, box): keep = mesh the flat slivers buried in the "
        "body, so that the tetrahedra stay conforming where a nearly cubic "
        "lattice splits neighbouring cubes along different face diagonals; "
        "drop = leave them out, as in 2D (the library's 3D rule before; "
        "docs/theory.md)",
        str,
        ("keep", "drop"),
    ),
    Param(
        "strength_floor",
        1e-6,
        "-",
        "3D and axisymmetric: raise yield strengths below this fraction of the "
        "largest to it (stress-free cohesionless particles otherwise stall the "
        "interior-point method; 0: off; plane strain: off)",
        float,
        lo=0,
        hi=1e-2,
        hi_open=True,
    ),
    Param(
        "dp_match",
        None,
        "-",
        "3D and axisymmetric Drucker-Prager: fit to Mohr-Coulomb (default "
        "compression for the cylindrical geometries, plane-strain for box)",
        str,
        DP_MATCHES,
    ),
]

#: Summary metrics of the cylindrical geometries and the box (which also has
#: the plane-strain metrics, measured along x and with heights along z).
GEOMETRY_METRICS = {
    "runout_radius": "cylindrical geometries: final run-out radius r_inf, the "
    "radius within which 99 % of the mass lies, m",
    "reference_runout_lube2004": "cylindrical geometries: Lube et al. 2004, "
    "(r_inf - r0)/r0 = 1.24 a (a <= 1.7), 1.6 a^(1/2) (a > 1.7)",
    "reference_runout_lajeunesse2004": "cylindrical geometries: Lajeunesse et al. "
    "2004, (r_inf - r0)/r0 = a (a <= 0.74), 2 a^(1/2) (a > 0.74); with Lube's, "
    "the experimental band",
    "mass_basis": "3D and axisymmetric: what masses, volumes and energies are "
    "of (axisymmetric: the full ring, 2 pi r weight; 3D: the modelled quarter or "
    "slab)",
}

#: What the shared metric names mean for the cylindrical geometries.
CYLINDRICAL_MEANING = {
    "normalised_runout": "(r_inf - r0) / r0",
    "final_height": "h_inf / r0",
    "height_ratio": "h_inf / h0",
    "collapse_time": "when the 99 % front radius stops",
    "collapse_time_normalised": "collapse_time / sqrt(h0 / g)",
    "volume_change": "full-ring volume (axisymmetric), quarter volume (3D)",
    "runout_main_body": "not reported",
    "normalised_runout_main_body": "not reported",
    "runout_tip": "not reported",
}


def metrics_doc(plane: dict[str, str]) -> dict[str, str]:
    """The plane-strain metric descriptions with the other geometries' meaning."""
    doc = {
        k: (
            f"{v}; cylindrical: {CYLINDRICAL_MEANING[k]}"
            if k in CYLINDRICAL_MEANING
            else v
        )
        for k, v in plane.items()
    }
    return {**doc, **GEOMETRY_METRICS}


def used_parameters(
    geometry: str, given: frozenset[str], plane_names: frozenset[str]
) -> set[str]:
    """Parameters a geometry uses (the others may not be given).

    ``plane_names`` are the parameters of the plane-strain scene: plane strain
    uses exactly those (and ``geometry``); the other geometries use the
    parameters listed here, so a parameter added to the plane-strain scene
    later is refused for them until they use it.
    """
    if geometry == "plane-strain":
        return set(plane_names) | {"geometry"}
    common = {"geometry", "dp_match", "size_check", "strength_floor"}
    common |= {"stabilisation", "stabilisation_mode", "nodal_mass"}
    common |= {"volume_correction", "drainage", "water_level", "rho_w"}
    common |= {
        "spacing", "material", "rho", "E", "nu", "phi", "psi", "c",
        "floor_friction", "K0", "gravity", "dt", "t_end", "rest_fraction",
        "min_time", "alpha", "theta1", "theta2", "output_every",
        "checkpoint_every", "linear_solver", "threads", "reproducible", "tol",
        "accuracy",
    }  # fmt: skip
    if geometry == "box":
        return common | {
            "aspect", "half_width", "symmetric", "depth", "max_displacement",
            "buried_slivers", "kh",
        }  # fmt: skip
    used = common | {"radius", "height", "refine", "refine_band"}
    if not {"radius", "height"} <= given:
        used.add("aspect")
    if geometry == "quarter-cylinder":
        used.add("max_displacement")  # (axisymmetric: h from ring volumes)
        used.add("buried_slivers")
    return used


def finalize(
    values: dict[str, Any], given: frozenset[str], plane_names: frozenset[str]
) -> None:
    """Geometry defaults and refusals (in place; see the module notes).

    Parameters
    ----------
    values : dict
        Resolved values (defaults and the given overrides).
    given : frozenset of str
        Names set explicitly.
    plane_names : frozenset of str
        The parameters of the plane-strain scene.
    """
    geo = values["geometry"]
    unused = sorted(given - used_parameters(geo, given, plane_names))
    if values.get("method", "npfem") == "npfem" and "method" in unused:
        unused.remove("method")  # N-PFEM is every geometry's method
    if unused:
        name = unused[0]
        why = _unused_reason(geo, name)
        raise ParameterError(name, values[name], why)
    warn_dry_water(values, given)
    if geo == "plane-strain":
        fill_column_defaults(values)
        return
    if geo in CYLINDRICAL:
        if "strain" in str(values["refine"]).split("+"):
            raise ParameterError(
                "refine",
                values["refine"],
                f"none or surface with geometry={geo} (particles are added "
                "where the soil flows in plane strain only)",
            )
        _cylinder_sizes(values, given)
        if geo == "quarter-cylinder":
            _speed_defaults(values, given)
        elif "dt" not in given:
            values["dt"] = SEED_DT
        if "alpha" not in given:
            values["alpha"] = GEOMETRY_ALPHA[geo]
    else:
        h = values["spacing"] or values["half_width"] / 22.0
        values["spacing"] = h
        if values["depth"] is None:
            values["depth"] = DEPTH_SPACINGS * h
    _material(values, given)
    fill_column_defaults(values)
    _check_values(values)
    n = lattice_particles(geo, values, values["spacing"])
    blame = "spacing" if "spacing" in given or geo == "box" else "radius"
    dim = 2 if geo == "axisymmetric" else 3
    check_size(n, dim, values, blame, "use a larger spacing or a smaller column")


def _speed_defaults(values: dict[str, Any], given: frozenset[str]) -> None:
    """Fill :data:`QUARTER_SPEED` where the user did not choose (in place)."""
    if "refine" not in given:
        values["refine"] = QUARTER_SPEED["refine"]
    if not given & {"accuracy", "tol"}:
        values["accuracy"] = QUARTER_SPEED["accuracy"]
    if "dt" not in given:
        values["dt"] = QUARTER_SPEED["dt"]
        if "max_displacement" not in given:
            values["max_displacement"] = QUARTER_SPEED["max_displacement"]


def fill_column_defaults(values: dict[str, Any]) -> None:
    """Fill the column's ``drainage``, ``K0``, ``floor_friction``, ``min_time``.

    Jaky's ``K0 = 1 - sin phi``, a floor as rough as the soil (``phi``), and
    the earliest stop at rest ``2 sqrt(H0 / g)`` (with ``rest_fraction > 0``)
    once the column's height is known.
    """
    derive_drainage(values)
    fill_at_rest(values)
    kh_history(values)  # a file of t, k_h rows is read and checked now
    if values["floor_friction"] is None:
        values["floor_friction"] = values["phi"]
    if values["min_time"] is None and values["rest_fraction"] > 0:
        if values.get("geometry", "plane-strain") in CYLINDRICAL:
            H0 = values["height"]
        else:
            H0 = values["aspect"] * values["half_width"]
        values["min_time"] = 2 * math.sqrt(H0 / values["gravity"])


def _unused_reason(geometry: str, name: str) -> str:
    if name == "aspect":
        return "not with both radius and height (they fix the aspect ratio h0/r0)"
    if name == "max_displacement":
        return "not in axisymmetry (its spacing would come from ring volumes)"
    if name == "buried_slivers":
        return "3D geometries only (quarter-cylinder, box): 2D meshes have no slivers"
    if name == "kh":
        return (
            "plane-strain or box only: a horizontal acceleration would break "
            f"the symmetry of geometry={geometry}'s axis or planes"
        )
    if name == "method":
        return f"npfem: the other methods are not available for geometry={geometry}"
    if geometry == "plane-strain":
        return f"a geometry that uses it; geometry=plane-strain does not use {name}"
    return f"not used by geometry={geometry}; leave it out"


def _cylinder_sizes(values: dict[str, Any], given: frozenset[str]) -> None:
    """radius, height and aspect of a cylindrical column; spacing and its bound."""
    r, h0, a = values["radius"], values["height"], values["aspect"]
    if r is None and h0 is None:
        r = SEED["radius"]
    if r is None:
        r = h0 / a
    elif h0 is None:
        h0 = a * r
    values["radius"], values["height"], values["aspect"] = r, h0, h0 / r
    h = values["spacing"] if values["spacing"] is not None else r / SEED_DIVISIONS
    if h > r / 4 or h > h0 / 2:
        raise ParameterError(
            "spacing", h, f"at most min(r0/4, h0/2) = {min(r / 4, h0 / 2):g} m"
        )
    values["spacing"] = h


def _material(values: dict[str, Any], given: frozenset[str]) -> None:
    """Drucker-Prager by default; Mohr-Coulomb only in axisymmetry."""
    geo = values["geometry"]
    if "material" not in given:
        values["material"] = "drucker-prager"
    if values["material"] == "mohr-coulomb":
        if geo != "axisymmetric":
            raise ParameterError(
                "material",
                "mohr-coulomb",
                "drucker-prager in 3D (Mohr-Coulomb is not a second-order cone "
                "there); axisymmetric Mohr-Coulomb is exact",
            )
        if values["dp_match"] is not None:
            raise ParameterError(
                "dp_match", values["dp_match"], "only with material=drucker-prager"
            )
    elif values["dp_match"] is None:
        values["dp_match"] = "plane-strain" if geo == "box" else "compression"


def _check_values(values: Mapping[str, Any]) -> None:
    """Material and time-integration checks (as the plane-strain scene's)."""
    check_soil(values)
    if values["geometry"] == "box":
        L0, H0, h = (
            values["half_width"],
            values["aspect"] * values["half_width"],
            values["spacing"],
        )
        if h > L0 / 2 or h > H0 / 2:
            raise ParameterError(
                "spacing", h, f"at most min(L0, H0)/2 = {min(L0, H0) / 2:g} m"
            )
    if values["theta2"] < 1.0:
        warn_user(
            f"theta2={values['theta2']:g}: impacts on the floor have restitution "
            f"{1 / values['theta2'] - 1:.2f}; keep theta2 = 1 (1/2 makes them "
            "elastic and the collapse unstable)",
        )


@dataclass
class GeometryScene(Scene):
    """A scene whose :meth:`resolve` applies :func:`finalize`.

    The geometry rules need to know which parameters were given, not only
    their values.
    """

    #: Names of the plane-strain scene's parameters.
    plane_names: frozenset[str] = frozenset()

    def resolve(self, overrides: Mapping[str, Any] | None = None) -> Values:
        """Defaults updated with validated overrides, then the geometry rules."""
        values = self.checked(overrides)
        finalize(values, frozenset(overrides or {}), self.plane_names)
        return Values(values)
