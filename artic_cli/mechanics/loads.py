"""External loads on named node sets and muscle forces, switched on and off in time."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import units
from ..errors import ArticError
from ..geometry.mirror import MIRROR
from ..schedule import Schedule
from .model import Control, Model


@dataclass(frozen=True)
class LoadProgram:
    """Piecewise-constant inputs: load k acts on ``nodes[k]`` in [on, off); muscle entry m adds
    ``muscle_force[m] * muscle_share[m]`` to the muscle forces in [m_on, m_off)."""

    nodes: tuple[np.ndarray, ...]
    force: np.ndarray  # (K,3) per-node force, dyn
    on: np.ndarray  # (K,) s
    off: np.ndarray  # (K,) s
    n_nodes: int
    muscle_share: np.ndarray  # (E, M) how each muscle entry spreads over the model's muscles
    muscle_force: np.ndarray  # (E,) dyn
    m_on: np.ndarray
    m_off: np.ndarray

    def control_at(self, t: float) -> Control:
        f = np.zeros((self.n_nodes, 3))
        eps = 1e-12
        for k in np.flatnonzero((self.on <= t + eps) & (t + eps < self.off)):
            np.add.at(f, self.nodes[k], self.force[k])
        live = (self.m_on <= t + eps) & (t + eps < self.m_off)
        act = (self.muscle_force * live) @ self.muscle_share if len(self.muscle_force) else self.muscle_share.sum(0)
        return Control(node_force=f, muscle_force=act)


def muscle_force_vector(model: Model, forces_n: dict[str, float]) -> np.ndarray:
    """Each muscle unit's force (dyn) from {muscle or group: force in N}."""
    act = np.zeros(len(model.muscle_names))
    for name, fn in forces_n.items():
        act += units.newton_to_dyn(fn) * muscle_shares(model, name)
    return act


def muscle_shares(model: Model, name: str) -> np.ndarray:
    share = np.zeros(len(model.muscle_names))
    if name in model.groups:
        for m, w in model.groups[name].items():
            share[model.muscle_names.index(m)] += w
    else:
        share[model.muscle_names.index(name)] = 1.0
    return share


def check_symmetric(model: Model, f: np.ndarray, what: str) -> None:
    """A model solved by halves takes only left-right symmetric node forces (``f`` (N,3), dyn)."""
    if model.image is not None and not np.allclose(f[model.image] * MIRROR, f, atol=1e-9 * np.abs(f).max()):
        raise ArticError(f"{what} is not left-right symmetric, and the articulator is solved by halves; set "
                         "simulation.mirror_symmetry: false in the config")


def load_program(model: Model, schedule: Schedule, source: str = "schedule") -> LoadProgram:
    if schedule.muscles:
        if model.muscles is None:
            raise ArticError(f"{source}: muscles need the whole articulator; drop --tongue-only")
        schedule.check_muscles(model.drivable(), source)
    nodes, force, on, off = [], [], [], []
    for e in schedule.loads:
        idx = model.node_set(e.nodes)
        nodes.append(idx)
        force.append(units.newton_to_dyn(np.asarray(e.force_n, dtype=float)) / len(idx))
        f = np.zeros((model.n_nodes, 3))
        f[idx] = force[-1]
        check_symmetric(model, f, f"{source}: the load on '{e.nodes}'")
        on.append(units.ms_to_s(e.onset_ms))
        off.append(units.ms_to_s(e.onset_ms + e.duration_ms))
    m = len(model.muscle_names)
    share = np.zeros((len(schedule.muscles), m))
    for k, e in enumerate(schedule.muscles):
        share[k] = muscle_shares(model, e.muscle)
    return LoadProgram(nodes=tuple(nodes), force=np.array(force).reshape(-1, 3), on=np.array(on),
                       off=np.array(off), n_nodes=model.n_nodes, muscle_share=share,
                       muscle_force=np.array([units.newton_to_dyn(e.force_n) for e in schedule.muscles]),
                       m_on=np.array([units.ms_to_s(e.onset_ms) for e in schedule.muscles]),
                       m_off=np.array([units.ms_to_s(e.onset_ms + e.duration_ms) for e in schedule.muscles]))


def control_from_newtons(model: Model, muscles_n: dict[str, float] | None = None,
                         loads_n: dict[str, tuple[float, float, float]] | None = None) -> Control:
    """A step's control from muscle (or group) forces in N and loads in N on named node sets, each load
    shared equally by its set's nodes."""
    f = np.zeros((model.n_nodes, 3))
    for name, total in (loads_n or {}).items():
        idx = model.node_set(name)
        f[idx] += units.newton_to_dyn(np.asarray(total, dtype=float)) / len(idx)
    check_symmetric(model, f, "a load")
    return Control(node_force=f, muscle_force=muscle_force_vector(model, muscles_n or {})
                   if model.muscles is not None else None)
