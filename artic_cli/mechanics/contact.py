"""Tongue-wall contact: a penalty inside the implicit step, with a guarantee.

The paper (section III.D) finds where a node's path crossed the wall,
computes a bounding force from the cylinders (Eq. 10-11) and applies it at
the *next* step.  We instead put the wall inside the step: at the start of a
step every tongue contact node near the wall gets the tangent plane of its
closest wall triangle (the plane of Eq. 11), and within the Newton iteration
a node beyond that plane feels a stiff penalty force -k g n (g = penetration)
whose tangent k n n^T enters the Jacobian, so the contact force and the
tissue response are solved together, not one step late.  After the step,
any node still beyond the true surface by more than the tolerance is
projected back onto it and loses its outward normal speed: no node ever ends
a step more than ``tolerance`` outside the wall.

The mandible's part of the wall moves with the jaw: closest points are
found in the jaw's rest frame (inverse of the rigid motion of the mandible
nodes, Kabsch), where that part is fixed.  Closest triangles come from
voxel grids built once, whose candidate lists are exact (see
:class:`CandidateGrid`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..geometry.wall import PARTS, WallSurface
from .term import Evaluation, ForceTerm
from .wall_query import CandidateGrid, candidate_grid, wall_query



@dataclass(frozen=True)
class ContactModel:
    nodes: np.ndarray  # (P,) tongue nodes that may touch the wall
    wall: WallSurface
    fixed_grid: CandidateGrid  # the skull's wall parts
    jaw_grid: CandidateGrid  # the mandible part, in the jaw's rest frame
    jaw_nodes: np.ndarray  # mandible nodes defining the jaw's rigid motion
    jaw_rest: np.ndarray  # their rest positions
    stiffness: float  # dyn/cm
    tolerance: float  # cm
    margin: float = 0.5  # cm: nodes closer than this get a plane for the step

    @cached_property
    def corners(self) -> np.ndarray:
        """(T,3,3) the wall triangles' corner coordinates."""
        return np.ascontiguousarray(self.wall.vertices[self.wall.triangles])


GRID_REACH = 1.5  # cm: the candidate grids cover the contact nodes' rest positions and this much around them


def contact_model(wall: WallSurface, nodes: np.ndarray, points: np.ndarray, jaw_nodes: np.ndarray,
                  jaw_rest: np.ndarray, stiffness: float, tolerance: float) -> ContactModel:
    """Contact of the tongue nodes ``nodes`` (rest positions ``points``) with the wall."""
    corners = wall.vertices[wall.triangles]
    jaw = np.flatnonzero(wall.part == PARTS.index("mandible"))
    fixed = np.flatnonzero(wall.part != PARTS.index("mandible"))
    # the grids cover where the contact nodes can be: around their rest positions, inside the wall's box
    lo = np.maximum(points.min(axis=0) - GRID_REACH, wall.vertices.min(axis=0))
    hi = np.minimum(points.max(axis=0) + GRID_REACH, wall.vertices.max(axis=0))
    return ContactModel(nodes=np.asarray(nodes), wall=wall, fixed_grid=candidate_grid(corners, fixed, lo, hi),
                        jaw_grid=candidate_grid(corners, jaw, lo, hi), jaw_nodes=jaw_nodes,
                        jaw_rest=jaw_rest, stiffness=stiffness, tolerance=tolerance)


@dataclass(frozen=True)
class ContactPlanes:
    """Per-step linearised wall: node i may not go beyond the plane (q_i, n_i).

    Planes on the mandible translate with the mean of the jaw frame nodes
    within the step, and the contact force's reaction acts on those nodes."""

    nodes: np.ndarray  # (K,)
    q: np.ndarray  # (K,3)
    n: np.ndarray  # (K,3)
    jaw: np.ndarray  # (K,) bool: plane on the mandible
    jaw_nodes: np.ndarray  # (J,) frame nodes carrying the mandible's planes
    jaw_ref: np.ndarray  # (3,) their mean position at the start of the step

    def gaps(self, x: np.ndarray) -> np.ndarray:
        shift = np.where(self.jaw[:, None], x[self.jaw_nodes].mean(axis=0) - self.jaw_ref, 0.0)
        return ((x[self.nodes] - self.q - shift) * self.n).sum(axis=1)


def farthest_beyond_wall(cm: ContactModel, frames) -> float:
    """The largest signed gap (cm, > 0: beyond the wall) of any contact node over the positions ``frames``."""
    return max(float(wall_query(cm, x)[2].max()) for x in frames)


def contact_planes(cm: ContactModel, x: np.ndarray, query=None) -> ContactPlanes:
    """The step's planes for the nodes within ``margin`` of the wall (``query``: a wall_query at x)."""
    q, n, g, jaw = wall_query(cm, x) if query is None else query
    near = g > -cm.margin
    return ContactPlanes(nodes=cm.nodes[near], q=q[near], n=n[near], jaw=jaw[near], jaw_nodes=cm.jaw_nodes,
                         jaw_ref=x[cm.jaw_nodes].mean(axis=0))


def enforce(cm: ContactModel, x: np.ndarray, v: np.ndarray):
    """Project nodes beyond the wall by more than the tolerance back onto it.

    Returns x, v, the number of projected nodes and the wall query at the returned x when no node
    moved (the next step's planes come from it), else None."""
    query = wall_query(cm, x)
    q, n, g, _ = query
    bad = g > cm.tolerance
    if not bad.any():
        return x, v, 0, query
    x = x.copy()
    v = v.copy()
    idx = cm.nodes[bad]
    x[idx] = x[idx] - (g[bad] - 0.5 * cm.tolerance)[:, None] * n[bad]
    vn = (v[idx] * n[bad]).sum(axis=1)
    v[idx] -= np.maximum(vn, 0.0)[:, None] * n[bad]
    return x, v, int(bad.sum()), None


def contact_forces(cm: ContactModel, x: np.ndarray, planes: ContactPlanes | None):
    """Penalty forces (N, 3) of the nodes beyond their step's wall planes, which are active, and their
    magnitudes (dyn); the reaction of the mandible's planes acts on its frame nodes."""
    f = np.zeros_like(x)
    if planes is None or len(planes.nodes) == 0:
        return f, np.zeros(0, dtype=bool), np.zeros(0)
    g = planes.gaps(x)
    active = g > 0
    mag = cm.stiffness * np.where(active, g, 0.0)
    push = mag[:, None] * planes.n
    np.add.at(f, planes.nodes, -push)
    on_jaw = planes.jaw & active
    if on_jaw.any():  # the reaction acts on the mandible
        f[planes.jaw_nodes] += push[on_jaw].sum(axis=0) / len(planes.jaw_nodes)
    return f, active, mag


class ContactTerm(ForceTerm):
    """The wall: each step's tangent planes, a stiff penalty beyond them inside Newton (active contacts as
    rank-one terms, so a change of the contact set does not refactor the band), and after the step the
    guarantee: nodes still beyond the true surface are projected back onto it."""

    name = "contact"

    def present(self, model) -> bool:
        return model.contact is not None

    def prepare(self, model, state, control, h: float) -> ContactPlanes:
        cached = state.wall_cache is not None and state.wall_cache[0] is state.x
        return contact_planes(model.contact, state.x, state.wall_cache[1] if cached else None)

    def forces(self, model, ev: Evaluation, f: np.ndarray) -> None:
        fc, active, _ = contact_forces(model.contact, ev.x, ev.step[self.name])
        ev.parts[self.name] = active
        f += fc

    def rank_one(self, model, ev: Evaluation):
        planes, active = ev.step[self.name], ev.parts[self.name]
        if not active.any():
            return None
        nodes, n = planes.nodes[active], planes.n[active]
        v = np.zeros((model.n_nodes, 3, len(nodes)))
        v[nodes, :, np.arange(len(nodes))] = n
        for c in np.flatnonzero(planes.jaw[active]):  # the reaction on the mandible's frame
            v[planes.jaw_nodes, :, c] -= n[c] / len(planes.jaw_nodes)
        return v.reshape(3 * model.n_nodes, -1), np.full(len(nodes), model.contact.stiffness)

    def key(self, model, ev: Evaluation) -> tuple:
        return tuple(ev.step[self.name].nodes[ev.parts[self.name]])

    def constrain(self, model, ev: Evaluation, x: np.ndarray, v: np.ndarray):
        """The contact forces at the step's end, then nodes beyond the wall by more than the tolerance put back
        on it (a mirrored node has no dofs: a projection of its own would stay with it for good, so the
        mirror images are set again)."""
        _, active, mag = contact_forces(model.contact, x, ev.step[self.name])
        record = {"contact_nodes": ev.step[self.name].nodes[active], "contact_force": mag[active]}
        x, v, projected, query = enforce(model.contact, x, v)
        model.mirror(x)
        model.mirror(v)
        return x, v, dict(record, projected=projected, wall_cache=None if query is None else (x, query))
