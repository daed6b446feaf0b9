"""A held jaw: the mandible kept where a state has it while tongue muscles act.

The jaw's eight frame nodes (condyle, coronoid, gonion and symphysis, left and
right) are tied to their positions in the state by stiff springs in x, y and
z -- the condyle guide's kind of term, at the guide's stiffness -- in place of
the guide (a held condyle needs no eminence line).  Everything the mandible
carries (incisor, muscle origins, the GG tendon) follows its frame, so the
jaw's height, opening and rotation stay those of the jaw position.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .guide import Guide, with_flat
from .model import Model, State

FRAME = ("condyle", "coronoid", "gonion", "symphysis")


def jaw_frame_nodes(model: Model) -> np.ndarray:
    """(8,) the mandible's frame nodes, left and right."""
    return np.array([model.names[f"{part}_{side}"] for part in FRAME for side in "lr"], dtype=np.int64)


def hold_jaw(model: Model, x: np.ndarray) -> Model:
    """The model with its mandible held at positions ``x`` (N, 3) cm."""
    if model.guide is None or not model.names:
        raise ValueError("hold_jaw needs the articulator (a model with a jaw)")
    nodes = jaw_frame_nodes(model)
    normals = np.broadcast_to(np.eye(3), (len(nodes), 3, 3)).copy()
    k = model.guide.stiffness
    guide = Guide(nodes=nodes, origin=np.asarray(x, dtype=float)[nodes].copy(), normals=normals, stiffness=k,
                  path=None, onset=model.guide.onset)
    return dataclasses.replace(model, guide=with_flat(guide, model.layout.pattern))


def fresh_start(state: State) -> State:
    """The state without its scratch factorisation (it belongs to the model that made it)."""
    return dataclasses.replace(state, factor=None, wall_cache=None)
