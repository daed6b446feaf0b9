"""The condyle guide: nodes held on lines (the condyles on the articular eminence), with a one-sided stop.

A guided node x is pulled back onto its line by -k sum_m ((x - x0) . m) m over the line's normals m.  With a
``path`` (the line's forward direction) the line ends at x0: a node behind it (s = (x - x0) . path < 0, the
condyle pressed into the back of the glenoid fossa) is pushed forward with k ramp(-s) path, the penalty of
:mod:`.penalty` with a smoothed onset over ``onset`` cm.  The lines' stiffness is constant: it enters the
Newton matrix once, in the band's flat storage; the stop enters as rank-one terms while it acts.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .penalty import ramp
from .term import Evaluation, ForceTerm, nodal_columns


@dataclass(frozen=True)
class Guide:
    """Nodes held on lines (see the module)."""

    nodes: np.ndarray  # (G,)
    origin: np.ndarray  # (G,3)
    normals: np.ndarray  # (G,m,3) the lines' normals (2: a line; 3: a point)
    stiffness: float  # dyn/cm
    path: np.ndarray | None = None  # (G,3) forward unit vectors: a one-sided stop at the origin
    onset: float = 0.0  # cm over which the stop's force rises smoothly
    flat: np.ndarray | None = None  # the lines' constant stiffness in the layout's flat storage


def with_flat(guide: Guide, pattern) -> Guide:
    """The guide with its constant stiffness k sum_m m m^T laid out in ``pattern``'s flat storage."""
    blocks = guide.stiffness * np.einsum("gmi,gmj->gij", guide.normals, guide.normals)
    return replace(guide, flat=pattern.diagonal_operator(guide.nodes) @ blocks.ravel())


def guide_stop(gd: Guide | None, x: np.ndarray) -> np.ndarray:
    """(G,) which guided nodes press on the back stop of their line."""
    if gd is None or gd.path is None:
        return np.zeros(0 if gd is None else len(gd.nodes), dtype=bool)
    return ((x[gd.nodes] - gd.origin) * gd.path).sum(axis=1) < 0.0


def guide_forces(gd: Guide, x: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """(G, 3) the guide's forces (dyn) on its nodes; ``stop``: which press on their back stop."""
    d = x[gd.nodes] - gd.origin
    off = (d[:, None, :] * gd.normals).sum(axis=2)  # (G, m)
    fg = -gd.stiffness * (off[:, :, None] * gd.normals).sum(axis=1)
    if stop.any():
        push, _ = ramp(-(d * gd.path).sum(axis=1), gd.onset)
        fg += gd.stiffness * push[:, None] * gd.path
    return fg


class GuideTerm(ForceTerm):
    """The condyle guide (or a held jaw's frame, :mod:`.jaw_hold`): lines in the flat storage, the stop as
    rank-one terms."""

    name = "guide"

    def present(self, model) -> bool:
        return model.guide is not None

    def forces(self, model, ev: Evaluation, f: np.ndarray) -> None:
        gd = model.guide
        stop = guide_stop(gd, ev.x)
        ev.parts[self.name] = stop
        f[gd.nodes] += guide_forces(gd, ev.x, stop)

    def flat(self, model) -> np.ndarray | None:
        return model.guide.flat

    def rank_one(self, model, ev: Evaluation):
        stop = ev.parts[self.name]
        if not stop.any():
            return None
        gd = model.guide
        _, slope = ramp(-((ev.x[gd.nodes[stop]] - gd.origin[stop]) * gd.path[stop]).sum(axis=1), gd.onset)
        return nodal_columns(model.n_nodes, gd.nodes[stop], gd.path[stop]), gd.stiffness * slope

    def key(self, model, ev: Evaluation) -> tuple:
        return tuple(ev.parts[self.name])
