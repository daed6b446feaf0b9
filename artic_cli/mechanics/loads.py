"""External loads on named node sets, switched on and off in time."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import units
from ..schedule import Schedule
from .model import Control, Model


@dataclass(frozen=True)
class LoadProgram:
    """Piecewise-constant nodal forces: entry k acts on ``nodes[k]`` in [on, off)."""

    nodes: tuple[np.ndarray, ...]
    force: np.ndarray  # (K,3) per-node force, dyn
    on: np.ndarray  # (K,) s
    off: np.ndarray  # (K,) s
    n_nodes: int

    def control_at(self, t: float) -> Control:
        f = np.zeros((self.n_nodes, 3))
        eps = 1e-12
        for k in np.flatnonzero((self.on <= t + eps) & (t + eps < self.off)):
            np.add.at(f, self.nodes[k], self.force[k])
        return Control(force=f)


def load_program(model: Model, schedule: Schedule) -> LoadProgram:
    nodes, force, on, off = [], [], [], []
    for e in schedule.loads:
        idx = model.node_set(e.nodes)
        nodes.append(idx)
        force.append(units.newton_to_dyn(np.asarray(e.force_n, dtype=float)) / len(idx))
        on.append(units.ms_to_s(e.onset_ms))
        off.append(units.ms_to_s(e.onset_ms + e.duration_ms))
    return LoadProgram(nodes=tuple(nodes), force=np.array(force).reshape(-1, 3), on=np.array(on),
                       off=np.array(off), n_nodes=model.n_nodes)
