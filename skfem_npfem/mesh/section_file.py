"""The JSON file of a cross-section: read, checked, and doubted.

The geometry file of the ``slope`` scene (:func:`read_cross_section`) is JSON::

    {
      "materials": {
        "clay": {"c": 10000, "phi": 20, "rho": 2000},
        "sand": {"c": 0, "phi": 35, "rho": 1900, "E": 5e7, "nu": 0.3}
      },
      "regions": [
        {"material": "clay", "polygon": [[0, 0], [40, 0], [40, 5], [0, 5], [0, 0]]},
        {"material": "sand", "polygon": [[0, 5], [25, 5], [15, 15], [0, 15], [0, 5]]}
      ],
      "supports": {"base": "fixed", "sides": "rollers"}
    }

Lengths in m, stresses in Pa, angles in degrees, densities ``rho`` in kg/m^3 (the
unit weight is ``rho g``). A region may give its own ``"spacing"`` (finer where
asked: a thin layer, the zone where a slip is expected); edges it shares with
coarser regions take its points, and its particles keep it in a run-out
(:func:`~skfem_npfem.mesh.regions.point_spacing`). A material may also give
``E``, ``nu`` and ``psi`` (defaults: the scene's), and ``k``, its hydraulic
conductivity (m/s) for the steady seepage of ``"heads"``: every material or none
(none: one uniform ``k``; the heads of a soil of one conductivity do not depend
on its value). Polygons
are closed: the last vertex repeats the first. The base is the lowest ``y`` of
the section (``fixed``: both velocities zero; ``rollers``: vertical only), the
sides its smallest and largest ``x`` (``rollers``: horizontal velocity zero;
``free``: no support).

A section may also give its water (``"water"``: the phreatic line;
``"heads"``: the heads of steady seepage; ``"boundaries"``: named polylines;
:mod:`.section_water`), and may be drawn as a mesh file instead of polygons
(``"mesh": FILE``, a gmsh ``.msh`` whose physical surface groups are the
regions, mapped to materials by ``"regions": [{"group": ..., "material":
...}]`` or by name; :mod:`.section_mesh`).

Every error names its place in the file (``materials.fill.phi``,
``regions[1].polygon``, ``supports.base``); :func:`implausible_values` lists
the values that are valid but most likely in other units.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from .regions import CrossSection, Region
from .section_mesh import group_outlines, line_polyline, read_section_mesh
from .section_water import (
    read_boundaries,
    read_heads,
    read_water,
    section_boundaries,
)

__all__ = ["implausible_values", "read_cross_section"]

#: Keys a material of a geometry file may have.
MATERIAL_KEYS = ("c", "phi", "psi", "rho", "E", "nu", "k")
#: Physical ranges of a material's properties: (low, high, low open, high open, what).
MATERIAL_RANGES = {
    "c": (0.0, math.inf, False, True, "a cohesion >= 0 (Pa)"),
    "phi": (0.0, 90.0, False, True, "a friction angle in [0, 90) (degrees)"),
    "psi": (0.0, 90.0, False, True, "a dilation angle in [0, 90) (degrees)"),
    "rho": (0.0, math.inf, True, True, "a density > 0 (kg/m^3)"),
    "E": (0.0, math.inf, True, True, "a Young's modulus > 0 (Pa)"),
    "nu": (-1.0, 0.5, True, True, "a Poisson's ratio in (-1, 0.5)"),
    "k": (0.0, math.inf, True, True, "a hydraulic conductivity > 0 (m/s)"),
}
#: Allowed supports.
BASES, SIDES = ("fixed", "rollers"), ("rollers", "free")


def _materials(mats: object) -> dict[str, dict[str, float]]:
    """The ``materials`` object of a cross-section file, checked."""
    if not isinstance(mats, dict) or not mats:
        raise ParameterError("materials", mats, "an object: name -> properties")
    materials: dict[str, dict[str, float]] = {}
    for name, props in mats.items():
        if not isinstance(props, dict):
            raise ParameterError(f"materials.{name}", props, "an object of properties")
        for key, val in props.items():
            where = f"materials.{name}.{key}"
            if key not in MATERIAL_KEYS:
                raise ParameterError(
                    where, val, "no such property: one of " + ", ".join(MATERIAL_KEYS)
                )
            if (
                isinstance(val, bool)
                or not isinstance(val, int | float)
                or not math.isfinite(val)
            ):
                raise ParameterError(where, val, "a finite number")
            lo, hi, lo_open, hi_open, what = MATERIAL_RANGES[key]
            if (
                val < lo
                or val > hi
                or (lo_open and val == lo)
                or (hi_open and val == hi)
            ):
                raise ParameterError(where, val, what)
        materials[name] = {k: float(v) for k, v in props.items()}
    given = [name for name, props in materials.items() if "k" in props]
    if given:
        for name, props in materials.items():
            if "k" not in props:
                raise ParameterError(
                    f"materials.{name}.k",
                    None,
                    "a hydraulic conductivity > 0 (m/s): every material gives "
                    f"one when any does ({', '.join(given)} do)",
                )
    return materials


def implausible_values(
    materials: dict[str, dict[str, float]], in_file: bool = True
) -> list[str]:
    """One line for every material property that looks like a unit mistake.

    The file's units are SI (Pa, kg/m^3) and degrees; a value that is valid
    but implausible for a soil or rock most likely came in other units: a
    density ``rho`` outside 500-3000 kg/m^3 (a unit weight in kN/m^3, or
    t/m^3), a cohesion ``c`` below 100 Pa with a friction angle below 5
    degrees (kPa meant: such a soil hardly stands), a friction or dilation
    angle between 0 and 1 degree (radians meant; 0 is a purely cohesive
    soil), a Young's modulus ``E`` below 100 kPa (MPa meant).

    Parameters
    ----------
    materials : dict
        Material name -> properties, as in :class:`CrossSection`.
    in_file : bool
        The values come from a file: a message names ``materials.NAME.KEY``;
        False: the key alone (a scene parameter).

    Returns
    -------
    list of str
        The messages (empty when every value is plausible), each naming the
        property's place in the file (``materials.fill.phi``).

    Examples
    --------
    >>> implausible_values({"fill": {"rho": 20.0}})[0][:38]
    'materials.fill.rho = 20: a density in '
    >>> implausible_values({"clay": {"c": 20000.0, "phi": 10.0, "rho": 1900.0}})
    []
    """
    out = []
    for name, props in materials.items():
        at = {k: f"materials.{name}.{k}" if in_file else k for k in MATERIAL_KEYS}
        rho, c, phi = props.get("rho"), props.get("c"), props.get("phi")
        if rho is not None and not 500 <= rho <= 3000:
            out.append(
                f"{at['rho']} = {rho:g}: a density in kg/m^3 is expected "
                "(soils and rocks 500-3000); a unit weight in kN/m^3 is about "
                f"rho g / 1000, so {rho:g} kN/m^3 would be rho = {rho * 1e3 / 9.81:.0f}"
            )
        if c is not None and c < 100 and (phi is None or phi < 5):
            out.append(
                f"{at['c']} = {c:g}: a cohesion in Pa is expected, and "
                f"below 100 Pa with a friction angle below 5 degrees a soil "
                f"hardly stands (kPa meant? {c:g} kPa is c = {c * 1e3:g})"
            )
        for key in ("phi", "psi"):
            val = props.get(key)
            if val is not None and 0 < val < 1:
                out.append(
                    f"{at[key]} = {val:g}: an angle in degrees is "
                    f"expected (radians meant? {val:g} rad is "
                    f"{math.degrees(val):.1f} degrees)"
                )
        E = props.get("E")
        if E is not None and E < 1e5:
            out.append(
                f"{at['E']} = {E:g}: a Young's modulus in Pa is expected "
                f"(soils 1e6-1e9; MPa meant? {E:g} MPa is E = {E * 1e6:g})"
            )
    return out


def _region_keys(
    k: int, r: object, shape: str, materials: dict[str, dict[str, float]]
) -> tuple[str, float | None]:
    """Material and own spacing of region ``k``, which gives ``shape`` too."""
    if not isinstance(r, dict) or shape not in r or "material" not in r:
        raise ParameterError(
            f"regions[{k}]", r, f"an object with 'material' and '{shape}'"
        )
    if r["material"] not in materials:
        raise ParameterError(
            f"regions[{k}].material",
            r["material"],
            "one of the materials of the file: " + ", ".join(materials),
        )
    hr = r.get("spacing")
    if hr is not None and not (
        isinstance(hr, int | float)
        and not isinstance(hr, bool)
        and math.isfinite(hr)
        and hr > 0
    ):
        raise ParameterError(f"regions[{k}].spacing", hr, "a length > 0 (m)")
    return r["material"], hr


def _region(k: int, r: object, materials: dict[str, dict[str, float]]) -> Region:
    """Region ``k`` of a cross-section file, checked (the polygon left open)."""
    material, hr = _region_keys(k, r, "polygon", materials)
    try:
        poly = np.asarray(r["polygon"], dtype=float)
    except (TypeError, ValueError):
        poly = np.zeros((0,))
    if poly.ndim != 2 or poly.shape[1] != 2 or not np.all(np.isfinite(poly)):
        raise ParameterError(
            f"regions[{k}].polygon", r["polygon"], "a list of [x, y] vertices"
        )
    if len(poly) < 4 or not np.allclose(poly[0], poly[-1]):
        raise ParameterError(
            f"regions[{k}].polygon",
            f"{len(poly)} vertices, from {poly[0].tolist() if len(poly) else None} "
            f"to {poly[-1].tolist() if len(poly) else None}",
            "a closed polygon: at least 3 vertices and the last one repeating "
            "the first (this one is open)",
        )
    return Region(material, poly[:-1], hr)


def _mesh_regions(
    folder: Path, data: dict, materials: dict[str, dict[str, float]]
) -> tuple[list[Region], dict[str, np.ndarray]]:
    """Regions and named lines of a section given as ``"mesh"`` (module notes)."""
    name = data["mesh"]
    if not isinstance(name, str) or not name:
        raise ParameterError(
            "mesh", name, "the path of a mesh file (relative to the JSON file)"
        )
    mesh = read_section_mesh(folder / name)
    spec = data.get("regions")
    if spec is None:
        for g in mesh.groups:
            if g not in materials:
                raise ParameterError(
                    f"mesh group {g!r}",
                    f"{len(mesh.groups[g])} triangles",
                    "a material of the file (without 'regions' a group's name is "
                    "its material): one of " + ", ".join(materials),
                )
        spec = [{"material": g, "group": g} for g in mesh.groups]
    if not isinstance(spec, list):
        raise ParameterError("regions", spec, "a list of {'material', 'group'}")
    regions = []
    for k, r in enumerate(spec):
        material, hr = _region_keys(k, r, "group", materials)
        if r["group"] not in mesh.groups:
            raise ParameterError(
                f"regions[{k}].group",
                r["group"],
                "a physical surface group of the mesh: " + ", ".join(mesh.groups),
            )
        for poly in group_outlines(r["group"], mesh.points, mesh.groups[r["group"]]):
            regions.append(Region(material, poly, hr))
    listed = {r["group"] for r in spec}
    for g in mesh.groups:
        if g not in listed:
            raise ParameterError(
                f"mesh group {g!r}",
                f"{len(mesh.groups[g])} triangles",
                "a group that 'regions' gives a material (every triangle needs "
                "one): listed are " + ", ".join(sorted(listed)),
            )
    lines = {n: line_polyline(n, s, mesh.points) for n, s in mesh.lines.items()}
    return regions, lines


def read_cross_section(path: str | Path) -> CrossSection:
    """Read and check the JSON geometry file (format in the module notes).

    Raises
    ------
    ParameterError
        For a file that cannot be read or parsed, a missing or unknown key, an
        open polygon, a region whose material is not in ``materials``, a
        bad support; a mesh file that cannot be read or whose groups do not
        map to materials (:func:`~.section_mesh.read_section_mesh`); a water
        line that does not span the section, a head on a boundary it lacks
        (:mod:`.section_water`).  Geometry checks that need the spacing are
        :func:`check_regions`.
    """
    p = Path(path)
    try:
        data = json.loads(p.read_text())
    except OSError as err:
        raise ParameterError(
            "geometry", str(path), f"a readable file ({err.strerror})"
        ) from None
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        line = getattr(err, "lineno", None)
        where = f"line {line}: {err.msg}" if line else "not text"
        raise ParameterError(
            "geometry",
            str(path),
            f"a JSON file ({where}; a mesh file is named in one: "
            '{"mesh": FILE, "materials": ...})',
        ) from None
    if (
        not isinstance(data, dict)
        or "materials" not in data
        or ("regions" not in data and "mesh" not in data)
    ):
        raise ParameterError(
            "geometry",
            str(path),
            "a JSON object with 'materials' and 'regions' (or 'mesh')",
        )
    materials = _materials(data["materials"])
    if "mesh" in data:
        regions, named = _mesh_regions(p.parent, data, materials)
    else:
        regions = [_region(k, r, materials) for k, r in enumerate(data["regions"])]
        named = {}
    named.update(read_boundaries(data.get("boundaries", {})))
    supports = {"base": "fixed", "sides": "rollers"}
    for key, val in dict(data.get("supports", {})).items():
        allowed = {"base": BASES, "sides": SIDES}.get(key)
        if allowed is None:
            raise ParameterError(f"supports.{key}", val, "keys base and sides")
        if val not in allowed:
            raise ParameterError(f"supports.{key}", val, "one of " + ", ".join(allowed))
        supports[key] = val
    if not regions:
        raise ParameterError("regions", [], "at least one region")
    boundaries = section_boundaries(regions, named)
    water = data.get("water")
    if water is not None:
        water = read_water(water, regions, boundaries)
    heads = read_heads(data.get("heads", []), boundaries)
    return CrossSection(regions, materials, supports, water, heads)
