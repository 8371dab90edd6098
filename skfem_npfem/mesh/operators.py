"""The strain operator of a step's mesh: plane or axisymmetric nodal integration."""

from __future__ import annotations

import numpy as np
from skfem import Mesh

from .axisymmetric import axisymmetric_integration
from .smoothing import NodalIntegration, nodal_integration

__all__ = ["strain_operator"]


def strain_operator(
    mesh: Mesh, components: tuple[int, ...], axisymmetric: bool = False
) -> tuple[NodalIntegration, float]:
    """The step's strain operator on ``mesh`` and the particle spacing ``h``.

    Plane strain and 3D: :func:`~skfem_npfem.mesh.smoothing.nodal_integration`,
    ``h`` the mean cell volume to the power ``1/d``.  Axisymmetric meshes get
    the ``2 pi r``-weighted cells with the hoop strain
    (:mod:`skfem_npfem.mesh.axisymmetric`); their spacing comes from the
    planar cell areas, not from the (m^3) ring volumes.

    Parameters
    ----------
    mesh : skfem.Mesh
        The step's P1 mesh.
    components : tuple of int
        Full-Voigt stress components carried as cone variables
        (:attr:`~skfem_npfem.step.model.Model.components`).
    axisymmetric : bool
        The mesh is the ``(r, z)`` half-section of a body of revolution.
    """
    if axisymmetric:
        op = axisymmetric_integration(mesh, components)
        return op, op.length_scale
    op = nodal_integration(mesh, components)
    return op, float(np.mean(op.volumes)) ** (1.0 / mesh.p.shape[0])
