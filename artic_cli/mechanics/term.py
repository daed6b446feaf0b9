"""The seam of the integrator: a force term, and what one Newton iterate knows.

Each force on the nodes is one term (as Warp's ``eval_spring_forces``, ``eval_muscle_forces``, ...): the
cylinders and links (:mod:`.elements`), the bricks' volume and inversion guard (:mod:`.volume`), the
condyle guide (:mod:`.guide`), the muscles (:mod:`.muscles`), the wall (:mod:`.contact`), loads and gravity
(:mod:`.external`).  A term implements, once, beside its physics and its compiled loops:

* ``forces``: its nodal forces (dyn) at the iterate, added into ``f``;
* ``blocks`` / ``flat``: its part of the Newton matrix, as node-level 3x3 blocks or as a constant in the
  band's flat storage;
* ``rank_one``: stiff or changing parts as columns k v v^T (updated into the factor by Woodbury);
* ``key``: which of its constraints are active (a change redoes the rank-one part of the factor).

and, if it needs them, ``prepare`` (once a step: what the step freezes), ``constrain`` (after the step: a
projection of the positions) and ``advance`` (after the step: its internal state).  ``Model.force_terms``
lists a model's terms; :func:`artic_cli.mechanics.integrator.step` sums them.  A term keeps no data of its
own between calls: what it computes for an iterate goes into ``ev.parts[name]``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Evaluation:
    """One Newton iterate of a step: the positions and velocities tried, the step's size and velocity
    coefficient (v = c_v x + v*), the state the step starts from, its control, what each term prepared for
    the step (``step``) and what each term computed of this iterate (``parts``), both by term name."""

    x: np.ndarray  # (N, 3) cm
    v: np.ndarray  # (N, 3) cm/s
    h: float  # s
    c_v: float  # 1/s
    state: object  # the step's start (mechanics.model.State)
    control: object  # mechanics.model.Control
    step: dict = field(default_factory=dict)
    parts: dict = field(default_factory=dict)


class ForceTerm:
    """A force on the nodes; every method's default is "nothing": a term overrides what it has."""

    name = "term"
    varies = True  # depends on the positions; False: evaluated once a step and summed as an external force

    def present(self, model) -> bool:
        """Whether the model has this term's physics (e.g. a wall, muscles)."""
        return True

    def prepare(self, model, state, control, h: float):
        """What the step freezes (stored in ``ev.step[name]``)."""
        return None

    def forces(self, model, ev: Evaluation, f: np.ndarray) -> None:
        """Add the term's nodal forces (dyn) at ``ev.x`` into ``f`` (N, 3)."""

    def blocks(self, model, ev: Evaluation, out: np.ndarray, signed: bool = True) -> None:
        """Add the term's tangent as node-level 3x3 blocks into ``out`` (P + N, 3, 3): node pairs of the
        model's layout first, then the diagonals (``signed=False``: drop indefinite geometric parts)."""

    def flat(self, model) -> np.ndarray | None:
        """The term's constant tangent in the band's flat storage, if it has one."""
        return None

    def rank_one(self, model, ev: Evaluation) -> tuple[np.ndarray, np.ndarray] | None:
        """Columns V (3N, r) and stiffnesses k (r,) of tangent terms k v v^T, if any."""
        return None

    def key(self, model, ev: Evaluation) -> tuple:
        """Which of its constraints are active at the iterate (compared between iterates)."""
        return ()

    def constrain(self, model, ev: Evaluation, x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict]:
        """After the step: positions and velocities made admissible, and state fields to record."""
        return x, v, {}

    def advance(self, model, ev: Evaluation, x: np.ndarray) -> dict:
        """After the step: the term's internal state at the step's end positions ``x`` (state fields)."""
        return {}


def nodal_columns(n_nodes: int, nodes: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(3N, K) columns with ``directions[k]`` (3,) at node ``nodes[k]`` (a penalty's rank-one vectors)."""
    v = np.zeros((n_nodes, 3, len(nodes)))
    v[nodes, :, np.arange(len(nodes))] = directions
    return v.reshape(3 * n_nodes, -1)
