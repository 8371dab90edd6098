"""What a model is told about the water (:class:`Water`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from .seepage import Seepage
from .table import WaterTable

__all__ = ["DRAINAGE", "Water"]

#: Drainage modes of a model with water (``dry`` is a model without one).
DRAINAGE = ("drained", "undrained", "coupled")


@dataclass
class Water:
    """The pore water of a model.

    Parameters
    ----------
    drainage : {"drained", "undrained", "coupled"}
        ``"drained"``: the pore pressure is the static field (the water
        table's hydrostatic pressure) at every step, whatever the soil does.
        ``"undrained"``: no water leaves a particle's cell within a step, so
        the mixture keeps its volume; the excess pore pressure over the
        static field is the multiplier of that constraint in the step's cone
        program, and it is carried by the particles from step to step.
        ``"coupled"``: consolidation: the excess pore pressure is a variable
        as in an undrained step, and water flows by Darcy's law within the
        step (backward Euler), drained at the free surface; needs
        ``permeability`` (docs/theory.md, "Water: consolidation").
    table : WaterTable, optional
        The phreatic surface; None: no static pore pressure (an undrained
        soil without a water table).
    rho_w : float
        Density of the water, kg/m^3.
    projection : float
        Factor ``tau >= 0`` of the pressure-projection stabilisation of the
        excess pore pressure in undrained steps (docs/theory.md, "Water:
        undrained steps"); 0 switches it off.
    seepage : Seepage, optional
        A steady flow through the soil instead of a table: the static pore
        pressure is ``rho_w g (h - z)`` (no suction) with the head ``h`` of
        Darcy's problem solved on every step's mesh, heads fixed on its
        water boundaries (:mod:`skfem_npfem.water.seepage`; plane sections).
        Free water over a head boundary needs no table: the boundary's
        pressure already loads the surface.  Exclusive with ``table``.

    permeability : float or sequence of float, optional
        Hydraulic conductivity ``k`` of the soil, m/s (one, or one per
        material): Darcy's flow of a ``coupled`` step.
    storage : float
        Storage coefficient ``n / K_w`` of the pore fluid, 1/Pa (porosity over
        the water's bulk modulus; 0: incompressible, the default).
        Coupled and undrained steps.

    Examples
    --------
    >>> w = Water("drained", WaterTable(level=1.0))
    >>> w.static_pressure(np.array([[0.0, 0.0]]), gravity=10.0)
    array([10000.])
    """

    drainage: str = "drained"
    table: WaterTable | None = None
    rho_w: float = 1000.0
    projection: float = 1.0
    seepage: Seepage | None = None
    permeability: float | Sequence[float] | None = None
    storage: float = 0.0

    def __post_init__(self) -> None:
        if self.drainage not in DRAINAGE:
            raise ParameterError(
                "drainage", self.drainage, f"one of {', '.join(DRAINAGE)} (or no water)"
            )
        if self.table is not None and not isinstance(self.table, WaterTable):
            raise ParameterError("table", self.table, "a WaterTable or None")
        if self.seepage is not None:
            if not isinstance(self.seepage, Seepage):
                raise ParameterError("seepage", self.seepage, "a Seepage or None")
            if self.table is not None:
                raise ParameterError(
                    "water",
                    "a table and a seepage",
                    "one of a water table and a seepage (the seepage's head "
                    "boundaries stand for the free water)",
                )
        for name, what in (
            ("rho_w", "a density > 0 (kg/m^3)"),
            ("projection", "a number >= 0"),
            ("storage", "a storage coefficient n / K_w >= 0 (1/Pa)"),
        ):
            v = getattr(self, name)
            ok = isinstance(v, int | float) and not isinstance(v, bool)
            ok = ok and math.isfinite(v) and (v > 0 if name == "rho_w" else v >= 0)
            if not ok:
                raise ParameterError(name, v, what)
        if self.drainage == "drained" and self.table is None and self.seepage is None:
            raise ParameterError(
                "water",
                "drained without a water table",
                "a water table (level or line) or a seepage for drained water",
            )

        self._check_permeability()

    def _check_permeability(self) -> None:
        """``coupled`` needs a permeability > 0 (m/s), one or one per material."""
        k = self.permeability
        if k is None:
            if self.drainage == "coupled":
                raise ParameterError(
                    "permeability",
                    None,
                    "a hydraulic conductivity k > 0 (m/s), or one per material, "
                    "for coupled drainage",
                )
            return
        ks = [k] if isinstance(k, int | float) else k
        try:
            ks = [float(v) for v in ks if not isinstance(v, bool)]
        except (TypeError, ValueError):
            ks = []
        if not ks or not all(math.isfinite(v) and v > 0 for v in ks):
            raise ParameterError(
                "permeability",
                k,
                "a hydraulic conductivity > 0 (m/s) or one per material",
            )
        self.permeability = ks[0] if isinstance(k, int | float) else tuple(ks)

    @property
    def undrained(self) -> bool:
        """The excess pore pressure is a variable of the step (undrained, coupled)."""
        return self.drainage in ("undrained", "coupled")

    def conductivity(self, material: np.ndarray) -> np.ndarray:
        """Hydraulic conductivity at particles of the given material ids, m/s."""
        material = np.asarray(material, int)
        k = self.permeability
        if isinstance(k, float):
            return np.full(material.shape, k)
        ks = np.asarray(k, float)
        if material.size and material.max() >= ks.size:
            raise ParameterError(
                "permeability",
                list(ks),
                f"one conductivity per material ({int(material.max()) + 1} or more)",
            )
        return ks[material]

    def static_pressure(
        self,
        x: np.ndarray,
        gravity: float,
        t: np.ndarray | None = None,
        material: np.ndarray | None = None,
    ) -> np.ndarray:
        """The static pore pressure at positions ``x`` (N, d), Pa.

        A seepage is solved on the mesh ``t`` (3, ne) whose nodes are ``x``,
        with the nodes' material ids ``material`` (N,) for its conductivity;
        a table needs neither.
        """
        x = np.asarray(x, float)
        if self.seepage is not None:
            if t is None:
                raise ParameterError(
                    "t", None, "the step's mesh (a seepage is solved on it)"
                )
            return self.seepage.pressure(x, t, material, self.rho_w, gravity)
        if self.table is None:
            return np.zeros(x.shape[0])
        return self.table.pressure(x, self.rho_w, gravity)
