"""Cylindrical granular columns: particles, walls and models (no scene wiring).

Two models of the same column of radius ``r0`` and height ``h0`` standing on a
floor (gravity along the last axis):

* ``"axisymmetric"``: the ``(r, z)`` half-section ``[0, r0] x [0, h0]`` of
  :mod:`skfem_npfem.mesh.axisymmetric` (volumes and masses of the full ring, kg);
  particles on the axis have ``u_r`` fixed and a frictionless wall at ``r = 0``
  keeps every other particle at ``r >= 0``;
* ``"quarter-cylinder"``: a 3D quarter ``x, y >= 0`` (masses of the quarter,
  kg); particles on a symmetry plane have its normal displacement fixed
  (``u_x`` on ``x = 0``, ``u_y`` on ``y = 0``) and frictionless walls
  ``x = 0`` and ``y = 0`` keep every other particle in the quarter.

Both start from a regular lattice (the alpha-shape remesher breaks the
co-circular ties of a lattice with its lifted jitter), a geostatic stress
``s_zz = -rho g (h0 - z)``, ``s_rr = s_tt = K0 s_zz`` (``s_xx = s_yy`` in 3D),
masses ``rho V_i`` from the initial mesh, and floor forces equal to the weight
of the lattice column standing on each base particle (the lagged normal force of
the first step's floor friction: docs/theory.md, "Wall friction: lagged normal
forces").

The seed case (:data:`SEED`) is the reference paper's column: ``r0 = 3.9`` cm,
``h0 = 7.8`` cm, ``rho = 1800``, ``E = 10`` MPa, ``nu = 0.3``, ``phi = 30``,
``psi = 0``, ``c = 0``, ``dt = 2`` ms, ``theta1 = theta2 = 1``; the floor friction
angle defaults to ``phi``.  The yield cone is Drucker-Prager matched to
Mohr-Coulomb in triaxial compression, the stress path of a spreading column
(docs/theory.md, "Axisymmetric N-PFEM").
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...boundary import RigidWall, floor, wall_x
from ...constants import GRAVITY
from ...errors import ParameterError
from ...materials import DruckerPrager
from ...mesh.axisymmetric import AxisymmetricMohrCoulomb, axisymmetric_integration
from ...mesh.smoothing import nodal_integration
from ...mesh.sources import AlphaShapeMesher
from ...particles import Particles
from ...step.model import Model
from ...step.solver import SolverOptions
from ..shaking import model_kh

__all__ = [
    "GEOMETRIES",
    "GEOMETRY_ALPHA",
    "SEED",
    "SEED_DIVISIONS",
    "ColumnSetup",
    "column_model",
    "column_particles",
    "column_walls",
    "cylinder_column",
    "graded_column",
    "half_section_lattice",
    "mass_quantile",
    "quarter_cylinder_lattice",
    "radial_front",
]

GEOMETRIES = ("axisymmetric", "quarter-cylinder")

#: Lattice spacings over the seed radius at the seed's resolution: 10 027
#: particles in the 3D quarter (the paper's mesh has 10 759 nodes), 703 in the
#: axisymmetric half-section.
SEED_DIVISIONS = 18

#: The reference paper's column (SI units, angles in degrees).
SEED: dict[str, Any] = {
    "radius": 0.039,
    "height": 0.078,
    "rho": 1800.0,
    "E": 10.0e6,
    "nu": 0.3,
    "phi": 30.0,
    "psi": 0.0,
    "c": 0.0,
    "dt": 2.0e-3,
    "theta1": 1.0,
    "theta2": 1.0,
    "K0": 0.5,
    "gravity": GRAVITY,
    "alpha": 1.3,
}

#: Alpha-shape factor of each geometry (``alpha`` in :data:`SEED` is the
#: section's).  The 3D quarter takes 2.0: a cubic lattice's cells have the
#: circumradius ``sqrt(3)/2 h`` against the square's ``h/sqrt(2)``, so 1.3
#: leaves 3D only 1.5x that margin (1.84x in 2D), and at 1.3 the alpha test
#: trimmed the stretched front of the spreading quarter: the r0/8 column lost
#: 28.8 % of its volume at rest against 14.9 % at 2.0 (docs/seed_column.md,
#: "Where the 3D volume goes").
GEOMETRY_ALPHA = {"axisymmetric": 1.3, "quarter-cylinder": 2.0}


def _divisions(radius: float, height: float, spacing: float) -> tuple[int, int]:
    """Lattice divisions over the radius and the height (at least 1 each)."""
    for name, val in (("radius", radius), ("height", height), ("spacing", spacing)):
        if not (isinstance(val, int | float) and math.isfinite(val) and val > 0):
            raise ParameterError(name, val, "a finite length > 0 (m)")
    return max(1, round(radius / spacing)), max(1, round(height / spacing))


def half_section_lattice(
    radius: float, height: float, spacing: float
) -> tuple[np.ndarray, float]:
    """Regular lattice of the axisymmetric half-section ``[0, r0] x [0, h0]``.

    Returns
    -------
    x : ndarray (N, 2)
        Particle positions ``(r, z)``, m.
    h : float
        Radial lattice spacing ``r0 / round(r0 / spacing)``, m.

    Examples
    --------
    >>> x, h = half_section_lattice(0.039, 0.078, 0.039 / 12)
    >>> x.shape[0], round(h * 12 / 0.039, 12)
    (325, 1.0)
    """
    nr, nz = _divisions(radius, height, spacing)
    r = np.linspace(0.0, radius, nr + 1)
    z = np.linspace(0.0, height, nz + 1)
    R, Z = np.meshgrid(r, z, indexing="ij")
    return np.column_stack([R.ravel(), Z.ravel()]), radius / nr


def quarter_cylinder_lattice(
    radius: float, height: float, spacing: float
) -> tuple[np.ndarray, float]:
    """Cubic lattice clipped to the quarter cylinder ``x, y >= 0``, ``x^2+y^2 <= r0^2``.

    The lattice has ``round(r0 / spacing)`` spacings over the radius (so it
    reaches ``r0`` on both symmetry planes) and ``round(h0 / spacing)`` over the
    height; lattice points with ``x^2 + y^2 <= r0^2 (1 + 1e-9)`` are kept (the
    tolerance of ``benchmarks/suite.py``'s quarter cylinder).

    Returns
    -------
    x : ndarray (N, 3)
        Particle positions, m.
    h : float
        Lattice spacing in the plane, m.

    Examples
    --------
    >>> x, h = quarter_cylinder_lattice(0.039, 0.078, 0.039 / 12)
    >>> x.shape[0]
    3075
    """
    nr, nz = _divisions(radius, height, spacing)
    g = np.linspace(0.0, radius, nr + 1)
    z = np.linspace(0.0, height, nz + 1)
    X, Y, Z = np.meshgrid(g, g, z, indexing="ij")
    x = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    keep = x[:, 0] ** 2 + x[:, 1] ** 2 <= radius**2 * (1.0 + 1e-9)
    return x[keep], radius / nr


def column_walls(geometry: str, floor_friction: float) -> list[RigidWall]:
    """Walls of a cylindrical column; the floor is always wall 0.

    Axisymmetric: floor (friction ``floor_friction`` degrees) and a frictionless
    wall at ``r = 0``.  Quarter cylinder: floor and the frictionless symmetry
    planes ``x = 0`` and ``y = 0``.
    """
    if geometry == "axisymmetric":
        return [floor(2, floor_friction), _named(wall_x(2, 0.0, 1, 0.0), "axis")]
    if geometry == "quarter-cylinder":
        return [
            floor(3, floor_friction),
            RigidWall([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.0, "x=0"),
            RigidWall([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.0, "y=0"),
        ]
    raise ParameterError("geometry", geometry, f"one of {GEOMETRIES}")


def _named(wall: RigidWall, name: str) -> RigidWall:
    return RigidWall(wall.point, wall.normal, wall.friction_angle, name)


def graded_column(
    x: np.ndarray, h: float, radius: float, height: float, band: float
) -> tuple[np.ndarray, np.ndarray]:
    """A cylindrical lattice with every other point kept in its core.

    ``x`` and ``h`` are a lattice of :func:`half_section_lattice` or
    :func:`quarter_cylinder_lattice` and its spacing.  Points within ``band``
    of the top, the floor or the column's free side (``r > r0 - band``) keep
    the spacing; the others only where every lattice index is even (twice
    the spacing).  The axis and the symmetry planes are no free surfaces:
    the core reaches them.  Returns the points and the spacing of each.
    """
    hz = height / max(1, round(height / h))
    z = x[:, -1]
    r = np.linalg.norm(x[:, :-1], axis=1)
    fine = (z > height - band) | (z < band) | (r > radius - band)
    idx = np.rint(np.column_stack([x[:, :-1] / h, z / hz])).astype(int)
    keep = fine | np.all(idx % 2 == 0, axis=1)
    return x[keep], np.where(fine[keep], h, 2.0 * h)


def column_particles(
    x: np.ndarray,
    mesher: AlphaShapeMesher,
    *,
    geometry: str,
    rho: float,
    gravity: float,
    height: float,
    K0: float,
    n_walls: int,
    floor_id: int = 0,
) -> Particles:
    """Particles at rest: geostatic stress, mesh masses, floor forces, axis fixity.

    Masses are ``rho V_i`` of the initial alpha-shape mesh (``2 pi r``-weighted
    in axisymmetry: kg of the full ring).  The floor force of a base particle
    (``z = 0``) is the weight of the particles of its lattice column (same
    ``r``, or same ``(x, y)`` in 3D), so the floor forces add up to the weight of
    the column exactly.  Axisymmetric particles on the axis get ``u_r`` fixed;
    in the quarter cylinder, particles on a symmetry plane get the normal
    displacement fixed (``u_x`` on ``x = 0``, ``u_y`` on ``y = 0``), so they
    need no contact row with that plane.
    """
    active, _ = mesher(x)
    if active.size != x.shape[0]:
        raise ParameterError("spacing", mesher.h, "all lattice particles meshed")
    mesh = mesher.last.mesh()
    axi = geometry == "axisymmetric"
    ni = axisymmetric_integration(mesh) if axi else nodal_integration(mesh)
    volumes = np.zeros(x.shape[0])
    volumes[active] = ni.volumes
    d = x.shape[1]
    sv = -rho * gravity * (height - x[:, -1])
    stress = np.zeros((x.shape[0], 4 if d == 2 else 6))
    stress[:, :3] = K0 * sv[:, None]
    stress[:, d - 1] = sv  # the vertical slot: 1 in (r, z), 2 in 3D
    fixed = np.zeros(x.shape, bool)
    if axi:
        fixed[:, 0] = x[:, 0] == 0.0  # on the axis: u_r = 0 (symmetry)
    elif geometry == "quarter-cylinder":
        # On a symmetry plane the normal displacement is zero by symmetry: a
        # prescribed dof, not a contact row (the wall stays for the others).
        fixed[:, :2] = x[:, :2] == 0.0
    p = Particles.create(x, rho * volumes, stress=stress, fixed=fixed, n_walls=n_walls)
    # Lattice columns: particles with the same horizontal position.
    key = np.round(x[:, :-1] / mesher.h, 6)
    _, column = np.unique(key, axis=0, return_inverse=True)
    column = column.ravel()
    weight = np.bincount(column, weights=p.mass * gravity)
    base = np.flatnonzero(np.isclose(x[:, -1], 0.0, atol=1e-9 * height))
    wall_force = np.zeros((x.shape[0], n_walls))
    wall_force[base, floor_id] = weight[column[base]]
    return p.replace(wall_force=wall_force)


@dataclass
class ColumnSetup:
    """A ready column problem: particles, model, remesher and time step.

    Built by :func:`cylinder_column` or, for the 3D slab,
    :func:`~skfem_npfem.scenes.collapse.box_column.box_column`.

    Attributes
    ----------
    geometry : str
        ``"axisymmetric"``, ``"quarter-cylinder"`` or ``"box"``.
    particles : Particles
        Initial state (masses: full ring in axisymmetry, the modelled part in 3D).
    model : Model
        Physics and solver settings.
    mesher : AlphaShapeMesher
        Remesher of every step.
    spacing : float
        Lattice spacing, m.
    dt : float
        Time step, s.
    parameters : dict
        The values used (seed defaults plus overrides).
    """

    geometry: str
    particles: Particles
    model: Model
    mesher: AlphaShapeMesher
    spacing: float
    dt: float
    parameters: dict[str, Any]

    @property
    def n_particles(self) -> int:
        """Number of particles."""
        return self.particles.n


def cylinder_column(
    geometry: str = "axisymmetric",
    spacing: float | None = None,
    *,
    floor_friction: float | None = None,
    match: str = "compression",
    material: str = "drucker-prager",
    solver: SolverOptions | None = None,
    band: float | None = None,
    **overrides: float,
) -> ColumnSetup:
    """The seed column (or a variant) as particles, model and remesher.

    Parameters
    ----------
    geometry : {"axisymmetric", "quarter-cylinder"}
        Model of the column.
    spacing : float, optional
        Lattice spacing, m (default ``r0 / 18``: :data:`SEED_DIVISIONS`).
    floor_friction : float, optional
        Floor friction angle, degrees (default ``phi``).
    match : str
        Drucker-Prager match to Mohr-Coulomb (default triaxial compression).
    material : {"drucker-prager", "mohr-coulomb"}
        Yield criterion; Mohr-Coulomb (three cones with the hoop stress,
        :class:`~skfem_npfem.mesh.axisymmetric.AxisymmetricMohrCoulomb`) only in
        axisymmetry (3D Mohr-Coulomb is not a second-order cone).
    solver : SolverOptions, optional
        Clarabel settings.
    band : float, optional
        A graded lattice (:func:`graded_column`): the spacing within ``band``
        lattice spacings of the free surfaces and the floor, twice it in the
        core.  None: the uniform lattice.
    **overrides
        Any key of :data:`SEED` (``radius``, ``height``, ``rho``, ``E``, ...).
        ``alpha`` defaults to the section's 1.3 here for both geometries; the
        column-collapse scene takes :data:`GEOMETRY_ALPHA`.

    Returns
    -------
    ColumnSetup
    """
    unknown = sorted(set(overrides) - set(SEED))
    if unknown:
        name = unknown[0]
        raise ParameterError(name, overrides[name], f"one of {sorted(SEED)}")
    v = {**SEED, **overrides}
    r0, h0 = v["radius"], v["height"]
    h = r0 / SEED_DIVISIONS if spacing is None else spacing
    if not (math.isfinite(h) and 0 < h <= r0 / 4):
        raise ParameterError("spacing", h, f"a length in (0, r0/4 = {r0 / 4:g}] m")
    phi_floor = v["phi"] if floor_friction is None else floor_friction
    walls = column_walls(geometry, phi_floor)
    if geometry == "axisymmetric":
        x, h_lat = half_section_lattice(r0, h0, h)
    else:
        x, h_lat = quarter_cylinder_lattice(r0, h0, h)
    graded = None
    if band is not None:
        x, graded = graded_column(x, h_lat, r0, h0, band * h_lat)
    mesher = AlphaShapeMesher(h_lat, v["alpha"], walls=walls, spacing=graded)
    particles = column_particles(
        x,
        mesher,
        geometry=geometry,
        rho=v["rho"],
        gravity=v["gravity"],
        height=h0,
        K0=v["K0"],
        n_walls=len(walls),
    )
    model = column_model(
        x.shape[1],
        v,
        walls,
        material=material,
        match=match,
        solver=solver,
        axisymmetric=geometry == "axisymmetric",
    )
    return ColumnSetup(geometry, particles, model, mesher, h_lat, v["dt"], v)


def column_model(
    dim: int,
    v: dict[str, Any],
    walls: list[RigidWall],
    *,
    material: str = "drucker-prager",
    match: str = "compression",
    solver: SolverOptions | None = None,
    axisymmetric: bool = False,
) -> Model:
    """The dynamic model of a column: the soil of ``v`` (keys of :data:`SEED`).

    ``material="mohr-coulomb"`` is exact Mohr-Coulomb with the hoop stress
    (:class:`~skfem_npfem.mesh.axisymmetric.AxisymmetricMohrCoulomb`, three cones)
    and exists only in axisymmetry: in 3D Mohr-Coulomb is not a second-order
    cone.  Drucker-Prager takes the fit ``match`` to Mohr-Coulomb.
    """
    strength = {"c": v["c"], "phi": v["phi"], "psi": v["psi"], "tension_cutoff": True}
    if material == "mohr-coulomb" and axisymmetric:
        mat = AxisymmetricMohrCoulomb(v["E"], v["nu"], v["rho"], **strength)
    elif material == "drucker-prager":
        mat = DruckerPrager(v["E"], v["nu"], v["rho"], match=match, **strength)
    else:
        raise ParameterError(
            "material",
            material,
            "drucker-prager, or mohr-coulomb in axisymmetry (3D Mohr-Coulomb is "
            "not a second-order cone)",
        )
    return Model(
        dim=dim,
        materials=[mat],
        gravity=v["gravity"],
        mode="dynamic",
        theta1=v["theta1"],
        theta2=v["theta2"],
        walls=walls,
        kh=model_kh(v) if "kh" in v else 0.0,
        solver=solver or SolverOptions(),
        axisymmetric=axisymmetric,
    )


def mass_quantile(coord: np.ndarray, mass: np.ndarray, q: float) -> float:
    """Coordinate below which a fraction ``q`` of the mass lies.

    The particles are sorted by ``coord``; each counts half of its mass at its
    own position (midpoint rule), and the quantile is interpolated linearly.

    Examples
    --------
    >>> mass_quantile(np.array([2.0, 1.0]), np.array([1.0, 1.0]), 0.5)
    1.5
    """
    order = np.argsort(coord)
    cum = np.cumsum(mass[order]) - 0.5 * mass[order]
    return float(np.interp(q * mass.sum(), cum, coord[order]))


def radial_front(x: np.ndarray, mass: np.ndarray, q: float = 0.99) -> float:
    """Radius below which a fraction ``q`` of the mass lies (99 % mass front).

    ``x`` holds ``(r, z)`` positions (axisymmetric, masses of the full ring) or
    ``(x, y, z)`` positions (3D); the radius is ``r`` or ``hypot(x, y)``.

    Examples
    --------
    >>> radial_front(np.array([[1.0, 0.0], [2.0, 0.0]]), np.array([1.0, 1.0]), 0.5)
    1.5
    """
    r = x[:, 0] if x.shape[1] == 2 else np.hypot(x[:, 0], x[:, 1])
    return mass_quantile(r, mass, q)
