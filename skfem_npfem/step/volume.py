"""Volume correction: a volumetric eigenstrain that returns remeshing losses.

Why
---
The particle masses of a PFEM body are exact, but the volume of its mesh is
not: every step moves the nodes by a linearised increment (whose second-order
area change is negative for stretching), and every remesh drops the simplices
that fail the alpha test, among them the ones that separating grains opened.
Nothing in the step remembers the volume a particle should fill, so a loss is
never returned: the cells around the particles simply become smaller, and with
node masses from the cells the density of the body rises.  In the default
column collapse the particles of the deposit end up 9 % closer packed
(docs/validation.md, "Area budget"), whatever alpha measures the final shape.

What
----
Each material's particles carry the reference volume ``V_ref = sum m / rho``
(their masses and the material density).  At the start of step ``n``, with
the current cell volumes ``V = sum V_i`` of that material's nodes, the deficit
is ``d_n = ln(V_ref / V)`` and the step prescribes at every node the isotropic
eigenstrain ("stress-free strain") ``e_n = x_n / n_v`` on each of the ``n_v``
normal components that carry volume (``n_v = 2`` in plane strain, 3 in 3D and
axisymmetry, where the hoop strain counts).  The volumetric strain ``x_n``
follows the deficit through a first-order filter,

    x_n = (1 - lam) x_{n-1} + lam g d_n,   g = kappa / (2 - kappa),
                                           lam = kappa (2 - kappa),

with ``kappa in [0, 1]`` the rate of the correction
(:attr:`~skfem_npfem.step.model.Model.volume_correction`).

Why the filter.  A free body expands by ``x_n`` (``d_{n+1} = d_n - x_n``),
so the pair is a second-order system; with these ``g`` and ``lam`` its two
poles coincide at ``1 - kappa``: the deficit decays as
``(1 + kappa n)(1 - kappa)^n``, as fast as a first-order return of ``kappa``
per step, without overshoot.  What the filter buys is smoothness: the mesh
volume of a flowing body jumps by a few per cent from step to step at coarse
resolution, as the alpha shape drops and re-admits front elements, and an
eigenstrain that follows those jumps (``x_n = kappa d_n``, the first version)
changes the body's expansion velocity abruptly.  The inertial forces of those
changes were of the order of the weight (the floor reaction of a 325-particle
column fell by 40 % in one step) and doubled the stress roughness maximum
(docs/validation.md).  Here the first response to a jump is ``kappa^2`` of it
instead of ``kappa``.  The state is one number per material, ``x_{n-1}``; each
step hands it to the next in its :class:`~skfem_npfem.step.records.StepState`
and writes it into the step record (``volume_correction_strain``), so
checkpoints carry it and a resumed run repeats the uninterrupted one.

In the cone program it is a linear term of the complementary energy,

    q_sigma = V_i e_i  on the stress increments of node i,

so that the optimality condition of the step reads
``Bbar du = C ds + d eps_p + e``: the smoothed strain of every node contains
the eigenstrain, which the material takes without stress where it is free to
expand and with (bounded, plastic) stress where it is confined.  Rows and
cones do not change, the step stays one cone program, and nothing is mapped
between meshes: ``V_ref`` is a sum of particle masses and the filter's state
is one number per material.

Properties (tests/step/test_volume_correction.py):

* **No deficit, no change.**  With ``V = V_ref`` the term is zero, and the
  step is the uncorrected one bit for bit.
* **Exact for a free body.**  A weightless elastic block on frictionless
  supports whose particles are 1 % too heavy for their cells expands by the
  uniform strain ``e`` with zero stress (an eigenstrain patch test), and its
  deficit decays as ``(1 + kappa n)(1 - kappa)^n``.
* **Vanishes with the discretisation error.**  The deficit is what the
  remeshing and the linearised kinematics lose, both of which vanish as the
  spacing and the time step go to zero; at rest, once the volume is back, the
  term is zero.

What it is not: it does not rescale volumes or masses, it does not move
particles outside the solve, and it does not choose *where* the volume comes
back (the solve does, through the material's response); a local, per-particle
version (``ln(m_i / (rho V_i))`` per node) was measured and rejected: the cell
volumes jump from remesh to remesh, and that noise went straight into the
stresses (docs/validation.md).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .program import Program, Term

__all__ = [
    "correction_gains",
    "eigenstrain_work",
    "volume_eigenstrain",
    "volume_ratio",
    "volume_strains",
]


def volume_ratio(
    mass: np.ndarray,
    material: np.ndarray,
    volumes: np.ndarray,
    densities: np.ndarray,
) -> np.ndarray:
    """``V_ref / V`` per material: particle masses over density, over the cells.

    Parameters
    ----------
    mass : ndarray (N,)
        Particle masses of the active nodes, kg.
    material : ndarray (N,) int
        Material index per node.
    volumes : ndarray (N,)
        Current cell volumes of the nodes (ring volumes in axisymmetry).
    densities : ndarray (n_materials,)
        Material densities, kg/m^3 (> 0 for every material present).

    Returns
    -------
    ndarray (n_materials,)
        The ratio per material (1 for materials without nodes).

    Examples
    --------
    >>> volume_ratio(np.array([1.0, 1.0]), np.array([0, 0]), np.array([0.5, 0.5]),
    ...              np.array([2.0]))
    array([1.])
    """
    n = densities.size
    ref = np.bincount(material, weights=mass, minlength=n)
    space = np.bincount(material, weights=volumes, minlength=n)
    present = space > 0
    ratio = np.ones(n)
    ratio[present] = ref[present] / densities[present] / space[present]
    return ratio


def correction_gains(kappa: float) -> tuple[float, float]:
    """Gain ``g`` and filter weight ``lam`` of the correction with rate ``kappa``.

    The volumetric strain of step ``n`` follows the deficit ``d_n`` through a
    first-order filter, ``x_n = (1 - lam) x_{n-1} + lam g d_n``; with
    ``g = kappa / (2 - kappa)`` and ``lam = kappa (2 - kappa)`` the deficit of a
    free body decays as ``(1 + kappa n)(1 - kappa)^n``: critically damped (no
    overshoot), at the rate ``1 - kappa`` per step (see the module notes).

    Examples
    --------
    >>> correction_gains(1.0)
    (1.0, 1.0)
    """
    k = float(kappa)
    return k / (2.0 - k), k * (2.0 - k)


def volume_strains(
    kappa: float,
    mass: np.ndarray,
    material: np.ndarray,
    volumes: np.ndarray,
    densities: np.ndarray,
    previous: Sequence[float] | None = None,
) -> np.ndarray | None:
    """Volumetric eigenstrain ``x = n_v e`` of this step, per material.

    Parameters
    ----------
    kappa : float
        Rate of the correction in [0, 1]: the deficit decays like
        ``(1 - kappa)^n`` (times ``1 + kappa n``).
    mass, material, volumes, densities
        As in :func:`volume_ratio`.
    previous : sequence of float (n_materials,) or None
        ``x`` of the previous step (None or zeros at the start of a run).

    Returns
    -------
    ndarray (n_materials,) or None
        None when ``kappa`` is 0.

    Notes
    -----
    ``densities`` must be > 0 for the materials present; :class:`Model`
    refuses a ``volume_correction`` with a material of zero density.
    """
    if not kappa:
        return None
    log_ratio = np.log(volume_ratio(mass, material, volumes, densities))
    # Round-off of the two sums (1e-15 for a body built with m = rho V) is no
    # deficit: such a step stays the uncorrected one bit for bit.
    log_ratio[np.abs(log_ratio) < 1e-12] = 0.0
    gain, lam = correction_gains(kappa)
    x = lam * gain * log_ratio
    if previous is not None:
        x = x + (1.0 - lam) * np.asarray(previous, float)
    return x


def volume_eigenstrain(
    strains: np.ndarray | None,
    material: np.ndarray,
    n_full: int,
    volumetric: tuple[int, ...],
) -> np.ndarray | None:
    """Full-Voigt eigenstrain of every node from the per-material strains.

    Parameters
    ----------
    strains : ndarray (n_materials,) or None
        Volumetric eigenstrain ``x`` per material (:func:`volume_strains`).
    material : ndarray (N,) int
        Material index per node.
    n_full : int
        Full-Voigt size of the stresses (4 in 2D, 6 in 3D).
    volumetric : tuple of int
        Full-Voigt components that carry volume: (0, 1) in plane strain,
        (0, 1, 2) in 3D and axisymmetry; each gets ``x / n_v``.

    Returns
    -------
    ndarray (N, n_full) or None
        None without strains.
    """
    if strains is None:
        return None
    eig = np.zeros((material.size, n_full))
    per_node = np.asarray(strains, float)[material] / len(volumetric)
    eig[:, list(volumetric)] = per_node[:, None]
    return eig


def eigenstrain_work(prog: Program) -> Term:
    """Objective term ``sum_i V_i e_i . ds_i`` (no term without an eigenstrain).

    With it the optimality condition of the step gains ``e`` in the smoothed
    strain: ``Bbar du = C ds + d eps_p + e`` (see the module notes).
    """
    eig = prog.data.eigenstrain
    if eig is None or not np.any(eig):
        return Term()
    op = prog.data.operator
    q = np.zeros(prog.nx)
    vals = np.asarray(op.volumes, float)[:, None] * eig[:, list(prog.comp)]
    q[prog.slice("sigma")] = vals.reshape(-1)
    return Term(q=q)
