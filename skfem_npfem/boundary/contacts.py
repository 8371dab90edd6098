"""Contact candidates of one step: nodes against rigid walls and bodies.

:class:`Contacts` is what every boundary hands the cone program
(:class:`~skfem_npfem.step.program.ConeInput`): one row per candidate, with
its normal, gap and friction bound, in the order the boundaries gave them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError

__all__ = ["Contacts"]


@dataclass
class Contacts:
    """Contact candidates of one step (node against a rigid plane or body).

    Attributes
    ----------
    node : ndarray (nc,) int
        Local node index.
    normal : ndarray (nc, d)
        Unit wall normal pointing into the body.
    gap : ndarray (nc,)
        Current gap (>= 0), m, plus ``normal . du_prescribed`` for a node with
        prescribed dofs (the program only sees the free dofs; non-penetration is
        ``gap + normal . du_free >= 0``).
    mu_lambda : ndarray (nc,)
        Friction bound ``mu * lambda_bar_n`` (N) from the previous step, or an
        adhesion bound that does not depend on the normal force (a
        :class:`RigidBody` with ``adhesion``); values <= 0 mean frictionless
        (no tangential variable).
    slip_offset : ndarray (nc, d-1) or None
        Tangential motion of the contact surface that the node's slip is
        measured against: ``t_k . (du_prescribed - du_surface)`` for a moving
        :class:`RigidBody` (the tangential counterpart of what ``gap`` holds
        along the normal).  None (fixed walls): zero.
    partner : ndarray (nc,) int or None
        Second node of a candidate that is a point of a boundary edge rather
        than a node (a :class:`RigidBody` corner against the soil's outline),
        -1 for node candidates.  None: all are node candidates.
    share : ndarray (nc,) or None
        Weight of ``partner`` in the candidate's point: its displacement is
        ``(1 - share) du_node + share du_partner`` and its force goes to the
        two nodes in the same proportions (0 for node candidates).

    Raises
    ------
    ParameterError
        If the array sizes disagree or ``gap``/``mu_lambda`` are not finite.

    Notes
    -----
    Sign conventions (docs/theory.md, "The mixed step"): the wall pushes on the body, so
    the equilibrium rows read ``G s + r - N lambda_n - T lambda_t = f~`` with
    ``lambda_n >= 0``; the normal dual gives ``gap + n . du >= 0`` and is zero
    where ``lambda_n > 0``.  Tangential forces ``lambda_t`` act along
    :func:`~skfem_npfem.mesh.geometry.tangents` of the normal and oppose the
    slip ``t . du``.
    """

    node: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    mu_lambda: np.ndarray
    slip_offset: np.ndarray | None = None
    partner: np.ndarray | None = None
    share: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.node = np.asarray(self.node, dtype=np.int64).reshape(-1)
        nc = self.node.size
        self.normal = np.asarray(self.normal, dtype=float)
        self.gap = np.asarray(self.gap, dtype=float).reshape(-1)
        self.mu_lambda = np.asarray(self.mu_lambda, dtype=float).reshape(-1)
        if (
            self.normal.ndim != 2
            or self.normal.shape[0] != nc
            or self.gap.size != nc
            or self.mu_lambda.size != nc
        ):
            raise ParameterError(
                "contacts",
                (nc, self.normal.shape, self.gap.size, self.mu_lambda.size),
                "node (nc,), normal (nc, d), gap (nc,) and mu_lambda (nc,)",
            )
        if not (np.all(np.isfinite(self.gap)) and np.all(np.isfinite(self.mu_lambda))):
            raise ParameterError(
                "contacts", "non-finite values", "finite gap, mu_lambda"
            )
        if self.slip_offset is not None:
            d = self.normal.shape[1]
            self.slip_offset = np.asarray(self.slip_offset, float).reshape(nc, d - 1)
        if (self.partner is None) != (self.share is None):
            raise ParameterError(
                "contacts",
                "partner without share",
                "both partner and share, or neither",
            )
        if self.partner is not None:
            self.partner = np.asarray(self.partner, dtype=np.int64).reshape(nc)
            self.share = np.asarray(self.share, dtype=float).reshape(nc)
            self.share = np.where(self.partner >= 0, self.share, 0.0)

    @classmethod
    def empty(cls, dim: int) -> Contacts:
        """No contacts."""
        return cls(np.zeros(0, int), np.zeros((0, dim)), np.zeros(0), np.zeros(0))

    @property
    def size(self) -> int:
        """Number of candidates."""
        return int(self.node.shape[0])

    def weights(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each candidate's nodes and their weights, as pairs.

        Returns
        -------
        nodes : ndarray (nc, 2) int
            ``node`` and ``partner`` (``node`` again for node candidates).
        weights : ndarray (nc, 2)
            ``1 - share`` and ``share`` (1 and 0 for node candidates).
        used : ndarray (nc, 2) bool
            Which of the two weights are non-zero.
        """
        if self.partner is None:
            nodes = np.stack([self.node, self.node], axis=1)
            w = np.zeros((self.size, 2))
            w[:, 0] = 1.0
        else:
            nodes = np.stack(
                [self.node, np.where(self.partner >= 0, self.partner, self.node)],
                axis=1,
            )
            w = np.stack([1.0 - self.share, self.share], axis=1)
        return nodes, w, w != 0.0

    def points(self, x: np.ndarray) -> np.ndarray:
        """Positions (nc, d) of the candidates' points, from node positions ``x``."""
        nodes, w, _ = self.weights()
        return np.einsum("ck,ckd->cd", w, x[nodes])

    def subset(self, sel: np.ndarray) -> Contacts:
        """The candidates ``sel`` (boolean or index array)."""
        return Contacts(
            node=self.node[sel],
            normal=self.normal[sel],
            gap=self.gap[sel],
            mu_lambda=self.mu_lambda[sel],
            slip_offset=None if self.slip_offset is None else self.slip_offset[sel],
            partner=None if self.partner is None else self.partner[sel],
            share=None if self.share is None else self.share[sel],
        )

    @classmethod
    def concat(cls, parts: Sequence[Contacts]) -> Contacts:
        """The candidates of several sources, in order (``slip_offset`` zero-filled)."""
        d = parts[0].normal.shape[1]
        partner = share = None
        if any(c.partner is not None for c in parts):
            partner = np.concatenate(
                [np.full(c.size, -1) if c.partner is None else c.partner for c in parts]
            )
            share = np.concatenate(
                [np.zeros(c.size) if c.share is None else c.share for c in parts]
            )
        offset = None
        if any(c.slip_offset is not None for c in parts):
            offset = np.concatenate(
                [
                    np.zeros((c.size, d - 1))
                    if c.slip_offset is None
                    else c.slip_offset
                    for c in parts
                ]
            )
        return cls(
            node=np.concatenate([c.node for c in parts]),
            normal=np.concatenate([c.normal for c in parts]),
            gap=np.concatenate([c.gap for c in parts]),
            mu_lambda=np.concatenate([c.mu_lambda for c in parts]),
            slip_offset=offset,
            partner=partner,
            share=share,
        )
