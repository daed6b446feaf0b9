"""A simulation as its file records it, read back: times, positions by part, control points, muscles,
contacts and the run's settings (what plots, tracts and checks need of a run)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import Model


def node_parts(model: Model) -> dict[str, np.ndarray]:
    """Which nodes are the tongue, the mandible and the hyoid (the rest are fixed or carried points)."""
    parts = {"tongue": np.arange(model.n_tongue)}
    for name in ("mandible", "hyoid"):
        if name in model.node_sets:
            parts[name] = np.asarray(model.node_sets[name])
    return parts


@dataclass
class Contacts:
    count: np.ndarray  # (T,) tongue nodes on the wall
    total_force_n: np.ndarray  # (T,) N
    nodes: list  # per frame: node indices
    force_n: list  # per frame: N per node


@dataclass
class Simulation:
    """A simulation file, read back whole: times (s), positions (cm) of every node and by part, control
    points, muscle forces (N) and lengths (cm), contacts, volume and the run's settings."""

    time_s: np.ndarray
    positions_cm: np.ndarray  # (T, N, 3)
    rest_cm: np.ndarray | None  # (N, 3) the model's rest (the frame bones' motions are measured from)
    velocities_cm_s: np.ndarray
    parts: dict[str, np.ndarray]  # part -> node indices
    control_points: dict[str, np.ndarray]  # name -> (T, 3) cm
    volume_change: np.ndarray
    inverted_bricks: np.ndarray
    muscle_names: list[str]
    muscle_force_n: np.ndarray | None
    muscle_length_cm: np.ndarray | None
    contacts: Contacts | None
    attrs: dict

    def part(self, name: str) -> np.ndarray:
        """(T, n, 3) positions of one part (tongue, mandible, hyoid), cm."""
        return self.positions_cm[:, self.parts[name]]
