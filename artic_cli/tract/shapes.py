"""What the tract needs of the articulators, frame by frame: the tongue's surface and the mandible's motion."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ArticError
from ..mechanics.wall_query import rigid_motion
from ..mechanics.model import Model
from ..mechanics.simulate import settle


@dataclass
class Shapes:
    """What the tract needs of the articulators, frame by frame (cm)."""

    time_s: np.ndarray  # (F,)
    tongue_cm: np.ndarray  # (F, n, 2) the tongue's midsagittal surface, tip first
    jaw_rotation: np.ndarray  # (F, 3, 3) the mandible's rigid motion from its rest
    jaw_translation: np.ndarray  # (F, 3)
    tongue_lateral_cm: np.ndarray | None = None  # (F, n, 2) the surface in the parasagittal plane at +lateral_z_cm
    lateral_z_cm: float = 0.0
    root_shift_cm: np.ndarray | None = None  # (F, 2) the root's lowest surface node (the vallecula) from its rest


def surface_nodes(mesh) -> tuple[np.ndarray, np.ndarray]:
    """The tongue's surface nodes, tip first: in the midsagittal plane and in the left (+z) plane."""
    rows = np.asarray(mesh.node_sets["surface"]).reshape(-1, 3)  # (radial lines, planes -z / 0 / +z)
    return rows[:, 1], rows[:, 2]


def shapes_of(positions: np.ndarray, time_s: np.ndarray, mesh, rest: np.ndarray | None,
              mandible: np.ndarray | None) -> Shapes:
    """Shapes from node positions (F, N, 3): the surface nodes (tip first) in the midsagittal and the left
    plane, the root's lowest node and the mandible's nodes against their rest (no rest: the mesh's nodes;
    no mandible: the jaw stays at rest)."""
    mid, lateral = surface_nodes(mesh)
    f = len(positions)
    rot = np.broadcast_to(np.eye(3), (f, 3, 3)).copy()
    tr = np.zeros((f, 3))
    ref = np.asarray(mesh.nodes if rest is None else rest, float)
    if mandible is not None and len(mandible) >= 3 and rest is not None:
        for k in range(f):
            rot[k], tr[k] = rigid_motion(rest[mandible], positions[k, mandible])
    return Shapes(time_s=np.asarray(time_s, float), tongue_cm=positions[:, mid, :2].copy(), jaw_rotation=rot,
                  jaw_translation=tr, tongue_lateral_cm=positions[:, lateral, :2].copy(),
                  lateral_z_cm=float(np.mean(mesh.nodes[lateral, 2])),
                  root_shift_cm=positions[:, mid[-1], :2] - ref[mid[-1], :2])


def shapes_of_model(model: Model, x: np.ndarray, time_s: np.ndarray) -> Shapes:
    """Shapes of the articulator ``model``'s node positions ``x`` (F, N, 3), its mandible against its rest."""
    return shapes_of(x, time_s, model.mesh, model.rest, np.asarray(model.node_sets["mandible"]))


def shapes_of_simulation(sim, mesh) -> Shapes:
    """Shapes of every frame of a simulation record (its positions, rest and parts)."""
    mandible = sim.parts.get("mandible")
    if mandible is not None and sim.rest_cm is None:
        raise ArticError("the simulation file records no rest positions (an older artic wrote it); rerun "
                         "'artic simulate'")
    return shapes_of(sim.positions_cm, sim.time_s, mesh, sim.rest_cm, mandible)


def rest_shapes(model: Model) -> Shapes:
    """The rest posture: the articulator settled under gravity (what every simulation starts from)."""
    return shapes_of_model(model, settle(model).x[None], np.zeros(1))
