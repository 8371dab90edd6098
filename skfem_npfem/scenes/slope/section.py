"""The slope's cross-section.

The parametric shape or a user's file, its materials, supports and surface.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from ...materials import Material, MohrCoulomb, Tresca
from ...mesh.regions import CrossSection, Region, check_regions, region_thickness
from ...mesh.section_file import implausible_values, read_cross_section
from ..limits import check_size

__all__ = [
    "check_section",
    "parametric_section",
    "section_materials",
    "section_of",
    "section_warnings",
    "supports",
    "toe_and_crest",
]


# -- geometry -------------------------------------------------------------------
def parametric_section(values: Mapping[str, Any]) -> CrossSection:
    """The slope of the parameters as a one-region cross-section."""
    H, D = values["height"], values["foundation_depth"]
    crest = values["crest_length"]
    toe = values["toe_length"]
    crest = 1.5 * H if crest is None else crest
    toe = 2.5 * H if toe is None else toe
    run = 0.0 if values["angle"] >= 90 else H / math.tan(math.radians(values["angle"]))
    x_crest, x_toe = crest, crest + run
    W = x_toe + toe
    pts = [(0, 0), (W, 0)]
    if D > 0:
        pts.append((W, D))
    pts += [(x_toe, D), (x_crest, D + H), (0, D + H)]
    poly = np.array(pts, dtype=float)
    props = {
        "c": values["c"],
        "phi": 0.0 if values["material"] == "tresca" else values["phi"],
        "rho": values["rho"],
    }
    return CrossSection([Region("soil", _dedupe(poly))], {"soil": props})


def _dedupe(poly: np.ndarray) -> np.ndarray:
    """Drop repeated consecutive vertices (a zero-length crest or toe)."""
    keep = np.linalg.norm(poly - np.roll(poly, 1, axis=0), axis=1) > 1e-12
    return poly[keep]


def section_of(values: Mapping[str, Any]) -> tuple[CrossSection, float]:
    """The cross-section (file or parametric) and its default spacing.

    The default spacing is H/10 (a file: its tallest region / 20); the
    spacing of a run is ``values["spacing"]`` once resolved.
    """
    if values["geometry"]:
        sec = read_cross_section(values["geometry"])
        heights = [float(np.ptp(r.polygon[:, 1])) for r in sec.regions]
        default_h = max(heights) / 20
    else:
        sec = parametric_section(values)
        default_h = values["height"] / 10
    return sec, default_h


#: Thinnest region, in spacings, whose factor of safety is converged: a weak
#: layer 0.8 m thick under the two-layer example's fill gives F = 0.984 / 0.909
#: / 0.894 at 1 / 2 / 4 spacings across it (docs/scenes.md, "Thin layers").
MIN_SPACINGS = 4


def check_section(sec: CrossSection, h: float, values: Mapping[str, Any]) -> None:
    """Refuse a section the run cannot do at spacing ``h``; warn on doubtful ones.

    Refused: a section too large for the machine, regions that cannot be
    meshed or that float (:func:`~skfem_npfem.mesh.regions.check_regions`).
    Warned
    (:func:`section_warnings`): implausible material values, regions thinner
    than :data:`MIN_SPACINGS` spacings.
    """
    area = sum(abs(_area(r.polygon)) for r in sec.regions)
    check_size(area / h**2, 2, values, advice="use a larger spacing")
    check_regions(sec.regions, h)
    for msg in section_warnings(sec, h, values):
        warnings.warn(msg, stacklevel=2)


def section_warnings(
    sec: CrossSection, h: float, values: Mapping[str, Any]
) -> list[str]:
    """What to doubt in a section at spacing ``h``: one line each.

    Implausible material values (a unit mistake:
    :func:`~skfem_npfem.mesh.section_file.implausible_values`) of a file or
    of the parameters, and every region
    thinner than :data:`MIN_SPACINGS` spacings (its own spacing, if it has
    one): its factor of safety is not converged.

    Parameters
    ----------
    sec : CrossSection
        The section.
    h : float
        The spacing of the run, m.
    values : mapping
        The scene's parameter values (``geometry``).

    Returns
    -------
    list of str
    """
    if values["geometry"]:
        out = implausible_values(sec.materials)
    else:
        props = {**sec.materials["soil"], "E": values["E"]}
        if values["material"] == "tresca":
            props.pop("phi")  # not a friction angle the user gave
        out = implausible_values({"soil": props}, in_file=False)
    for k, r in enumerate(sec.regions):
        hr = h if r.spacing is None else r.spacing
        t = region_thickness(r, h)
        if t < MIN_SPACINGS * hr:
            out.append(
                f"slope: regions[{k}] ({r.material!r}) is {t:.3g} m thick, "
                f"{t / hr:.1f} spacings (fewer than {MIN_SPACINGS}): a factor of "
                "safety that depends on it is not converged (a weak layer gave "
                "F = 0.984 / 0.909 / 0.894 at 1 / 2 / 4 spacings across it); "
                f"use spacing <= {t / MIN_SPACINGS:.3g}, or give the region "
                'its own "spacing"'
            )
    return out


def _area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def section_materials(
    sec: CrossSection, values: Mapping[str, Any], flow: bool = False
) -> list[Material]:
    """One material per name of the section (scene values as defaults)."""
    mats = []
    for props in sec.materials.values():
        c = props.get("c", values["c"])
        phi = props.get("phi", values["phi"])
        rho = props.get("rho", values["rho"])
        E, nu = props.get("E", values["E"]), props.get("nu", values["nu"])
        psi = min(props.get("psi", values["psi"]), phi) if flow else phi
        if values["material"] == "tresca" and not values["geometry"]:
            mats.append(Tresca(E, nu, rho, c=c))
        else:
            mats.append(
                MohrCoulomb(E, nu, rho, c=c, phi=phi, psi=psi, tension_cutoff=flow)
            )
    return mats


def supports(x: np.ndarray, sec: CrossSection) -> np.ndarray:
    """Fixed dofs: the base (lowest y) and the sides (smallest/largest x)."""
    lo, hi = x.min(axis=0), x.max(axis=0)
    tol = 1e-9 * max(float(np.ptp(x)), 1.0)
    fixed = np.zeros_like(x, dtype=bool)
    base = np.abs(x[:, 1] - lo[1]) < tol
    fixed[base, 1] = True
    if sec.supports["base"] == "fixed":
        fixed[base, 0] = True
    if sec.supports["sides"] == "rollers":
        fixed[(np.abs(x[:, 0] - lo[0]) < tol) | (np.abs(x[:, 0] - hi[0]) < tol), 0] = (
            True
        )
    return fixed


def _surface_height(x: np.ndarray, at: np.ndarray, width: float = 0.0) -> np.ndarray:
    """Highest particle y near each of ``at`` (NaN where there is none).

    The particles are binned in columns ``width`` wide (default: half the
    median gap between distinct x); a query takes the highest particle of its
    column and the two neighbouring ones (within ``width`` to ``2 width``).
    """
    if width <= 0:
        gaps = np.diff(np.unique(np.round(x[:, 0], 9)))
        width = 0.5 * float(np.median(gaps)) if gaps.size else 1.0
    x0 = min(float(x[:, 0].min()), float(np.min(at))) - 2 * width
    b = np.floor((x[:, 0] - x0) / width).astype(int)
    qb = np.floor((np.asarray(at) - x0) / width).astype(int)
    top = np.full(max(int(b.max()), int(qb.max())) + 2, -np.inf)
    np.maximum.at(top, b, x[:, 1])
    out = np.maximum(np.maximum(top[qb - 1], top[qb]), top[qb + 1])
    return np.where(np.isfinite(out), out, np.nan)


def toe_and_crest(sec: CrossSection, values: Mapping[str, Any]):
    """Toe and crest points of the section (parametric: exact; file: estimated)."""
    if not values["geometry"]:
        H, D = values["height"], values["foundation_depth"]
        crest = 1.5 * H if values["crest_length"] is None else values["crest_length"]
        run = (
            0.0
            if values["angle"] >= 90
            else H / math.tan(math.radians(values["angle"]))
        )
        return crest + run, D, crest, D + H
    allp = np.concatenate([r.polygon for r in sec.regions])
    top = allp[:, 1].max()
    crest_pts = allp[np.isclose(allp[:, 1], top)]
    x_crest = float(crest_pts[:, 0].max())
    right = allp[allp[:, 0] > x_crest + 1e-9]
    if right.size == 0:
        return x_crest, top, x_crest, top
    y_toe = float(right[:, 1].max()) if right.size else top
    low = right[np.isclose(right[:, 1], right[:, 1].max())]
    return float(low[:, 0].min()), y_toe, x_crest, float(top)
