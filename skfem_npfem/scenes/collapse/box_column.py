"""The 3D box column: the plane-strain half column as a slab between smooth walls.

``geometry=box`` of the ``column-collapse`` scene models in 3D what the
plane-strain scene models in 2D: the channel experiments of Lube et al. (2005),
a column of half-width ``L0`` and height ``H0`` against the symmetry wall
``x = 0`` (or free-standing, ``-L0 <= x <= L0``), here as a slab of depth ``W``
between two frictionless walls ``y = 0`` and ``y = W``.  A frictionless wall is
a symmetry plane, so the slab is one period of an infinitely deep column: its
exact solution is the plane-strain one (``u_y = 0``, ``eps_yy = 0``), and the
box checks the 3D discretisation (tetrahedra, six stress components, SOC(6)
cones, friction cones on the floor) against the 2D one on the same section.
Mohr-Coulomb is not a second-order cone in 3D, so the soil is Drucker-Prager
with the plane-strain match (the fit whose plane-strain collapse loads are
Mohr-Coulomb's); the plane-strain scene with ``material=drucker-prager`` is its
2D twin.  (A square column's quarter with two symmetry planes would be a second
3D geometry with no 2D or experimental reference to check it against.)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...boundary import RigidWall, floor, wall_x
from ...errors import ParameterError
from ...mesh.sources import AlphaShapeMesher
from ...step.solver import SolverOptions
from .cylinder import ColumnSetup, column_model, column_particles

__all__ = ["DEPTH_SPACINGS", "box_column", "box_lattice", "box_walls"]

#: Default slab depth, in particle spacings (five particle layers: three of
#: them off the walls, so the slab has an interior).
DEPTH_SPACINGS = 4


def box_lattice(
    length: float, height: float, depth: float, spacing: float, symmetric: bool
) -> tuple[np.ndarray, float]:
    """Cubic lattice of the slab ``[0 or -L0, L0] x [0, W] x [0, H0]``.

    Returns the positions (N, 3) and the lattice spacing along ``x``.

    Examples
    --------
    >>> x, h = box_lattice(0.2, 0.4, 0.04, 0.02, True)
    >>> x.shape[0], round(h, 12)
    (693, 0.02)
    """
    x0 = 0.0 if symmetric else -length
    nx = max(1, round((length - x0) / spacing))
    ny = max(1, round(depth / spacing))
    nz = max(1, round(height / spacing))
    X, Y, Z = np.meshgrid(
        np.linspace(x0, length, nx + 1),
        np.linspace(0.0, depth, ny + 1),
        np.linspace(0.0, height, nz + 1),
        indexing="ij",
    )
    return np.column_stack([X.ravel(), Y.ravel(), Z.ravel()]), (length - x0) / nx


def box_walls(depth: float, floor_friction: float, symmetric: bool) -> list[RigidWall]:
    """Walls of the box: floor (wall 0), ``y = 0``, ``y = W`` and ``x = 0``.

    The floor has friction ``floor_friction`` (degrees); the other walls are
    frictionless, and ``x = 0`` is there only when ``symmetric``.
    """
    walls = [
        floor(3, floor_friction),
        RigidWall([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.0, "y=0"),
        RigidWall([0.0, depth, 0.0], [0.0, -1.0, 0.0], 0.0, "y=W"),
    ]
    if symmetric:
        w = wall_x(3, 0.0, facing=1, friction_angle=0.0)
        walls.append(RigidWall(w.point, w.normal, 0.0, "x=0"))
    return walls


def box_column(
    v: dict[str, Any],
    *,
    length: float,
    height: float,
    depth: float,
    spacing: float,
    symmetric: bool = True,
    floor_friction: float | None = None,
    match: str = "plane-strain",
    solver: SolverOptions | None = None,
) -> ColumnSetup:
    """The box column as particles, model and remesher.

    Parameters
    ----------
    v : dict
        Soil, time-step and lattice values (the keys of
        :data:`~skfem_npfem.scenes.collapse.cylinder.SEED`).
    length, height, depth, spacing : float
        ``L0``, ``H0``, ``W`` and the lattice spacing, m.
    symmetric : bool
        Half column against the wall ``x = 0`` (else free-standing).
    floor_friction : float, optional
        Floor friction angle, degrees (default ``phi``).
    match : str
        Drucker-Prager fit to Mohr-Coulomb (default plane strain, see the
        module notes).
    solver : SolverOptions, optional
        Clarabel settings.

    Returns
    -------
    ColumnSetup
    """
    if depth < spacing * (1 - 1e-9):
        raise ParameterError("depth", depth, f"at least one spacing ({spacing:g} m)")
    phi_floor = v["phi"] if floor_friction is None else floor_friction
    walls = box_walls(depth, phi_floor, symmetric)
    x, h = box_lattice(length, height, depth, spacing, symmetric)
    mesher = AlphaShapeMesher(h, v["alpha"], walls=walls)
    particles = column_particles(
        x,
        mesher,
        geometry="box",
        rho=v["rho"],
        gravity=v["gravity"],
        height=height,
        K0=v["K0"],
        n_walls=len(walls),
    )
    model = column_model(3, v, walls, match=match, solver=solver)
    return ColumnSetup("box", particles, model, mesher, h, v["dt"], v)
