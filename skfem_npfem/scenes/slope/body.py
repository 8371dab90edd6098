"""The slope's section filled with particles: positions, mesh, supports, strengths.

:func:`slope_body` fills the section (parametric or a file) at the spacing;
:func:`body_from` makes the body of any points of it (the refined lattices of an
adaptive limit analysis, :mod:`~skfem_npfem.scenes.refinement`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from skfem import MeshTri

from ...materials import Material
from ...mesh.regions import CrossSection, fill_regions, point_spacing
from ...mesh.sources import AlphaShapeMesher
from .profile import profile_factors
from .section import section_materials, section_of, supports

__all__ = ["SlopeBody", "body_from", "run_out_mesher", "slope_body"]


@dataclass
class SlopeBody:
    """The slope's section filled with particles, and their mesh.

    Attributes
    ----------
    sec : CrossSection
        Regions and materials of the section.
    h : float
        Particle spacing, m.
    pts : ndarray (n, 2)
        Particle positions, m.
    tri : ndarray (3, n_t)
        Triangles of the particles' mesh.
    material : ndarray (n,) int
        Material index per particle (into ``mats``).
    mesh : MeshTri
        The particles' mesh.
    fixed : ndarray (n, 2) bool
        Supports: the fixed base and the side rollers.
    mats : list of Material
        The section's materials (limit analysis and initial stresses).
    strength, stiffness : ndarray (n,) or None
        The particles' factors of a strength growing with depth
        (:mod:`~.profile`); None: uniform.
    """

    sec: CrossSection
    h: float
    pts: np.ndarray
    tri: np.ndarray
    material: np.ndarray
    mesh: MeshTri
    fixed: np.ndarray
    mats: list[Material]
    strength: np.ndarray | None = None
    stiffness: np.ndarray | None = None


def slope_body(values: Mapping[str, Any]) -> SlopeBody:
    """The section of ``values`` (parametric or a file) filled at the spacing.

    Parameters
    ----------
    values : mapping
        The scene's parameter values.

    Returns
    -------
    SlopeBody
    """
    sec, _ = section_of(values)
    return body_from(values, sec, *fill_regions(sec.regions, values["spacing"]))


def body_from(
    values: Mapping[str, Any],
    sec: CrossSection,
    pts: np.ndarray,
    tri: np.ndarray,
    region: np.ndarray,
) -> SlopeBody:
    """The body of the section's points ``pts``, triangles ``tri`` (3, m), regions."""
    h = values["spacing"]
    names = list(sec.materials)
    material = np.array([names.index(sec.regions[r].material) for r in region])
    mesh = MeshTri(np.ascontiguousarray(pts.T), np.ascontiguousarray(tri))
    fixed = supports(pts, sec)
    mats = section_materials(sec, values)
    strength, stiffness = profile_factors(values, pts)
    return SlopeBody(sec, h, pts, tri, material, mesh, fixed, mats, strength, stiffness)


def run_out_mesher(body: SlopeBody, alpha: float) -> AlphaShapeMesher:
    """The run-out's remesher: each particle keeps its region's spacing.

    A section whose regions give their own ``spacing`` fills each at its own;
    the alpha test then reads the spacing of every particle (a simplex is
    kept below ``alpha`` times the largest spacing of its particles), and
    ``refine=surface`` adds a particle where an edge is stretched beyond
    ``refine_ratio`` times that spacing, so a fine region stays fine as it
    slides.  Without region spacings: ``alpha`` times the section's spacing
    everywhere, as before.
    """
    own = point_spacing(body.pts, body.tri, body.sec.regions, body.h)
    if own is None:
        return AlphaShapeMesher(body.h, alpha)
    return AlphaShapeMesher(float(own.min()), alpha, spacing=own)
