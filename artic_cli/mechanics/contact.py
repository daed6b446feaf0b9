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
nodes, Kabsch), where that part is fixed, so both KD-trees are built once.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from ..geometry.wall import PARTS, WallSurface
from . import elements, kernels


@dataclass(frozen=True)
class ContactModel:
    nodes: np.ndarray  # (P,) tongue nodes that may touch the wall
    wall: WallSurface
    fixed_tris: np.ndarray  # triangles of the skull's wall parts
    jaw_tris: np.ndarray  # triangles of the mandible part
    fixed_tree: cKDTree
    jaw_tree: cKDTree
    jaw_nodes: np.ndarray  # mandible nodes defining the jaw's rigid motion
    jaw_rest: np.ndarray  # their rest positions
    stiffness: float  # dyn/cm
    tolerance: float  # cm
    margin: float = 0.5  # cm: nodes closer than this get a plane for the step
    neighbours: int = 6

    @cached_property
    def corners(self) -> np.ndarray:
        """(T,3,3) the wall triangles' corner coordinates."""
        return np.ascontiguousarray(self.wall.vertices[self.wall.triangles])


def contact_model(wall: WallSurface, nodes: np.ndarray, jaw_nodes: np.ndarray, jaw_rest: np.ndarray,
                  stiffness: float, tolerance: float) -> ContactModel:
    centre = wall.vertices[wall.triangles].mean(axis=1)
    jaw = np.flatnonzero(wall.part == PARTS.index("mandible"))
    fixed = np.flatnonzero(wall.part != PARTS.index("mandible"))
    return ContactModel(nodes=np.asarray(nodes), wall=wall, fixed_tris=fixed, jaw_tris=jaw,
                        fixed_tree=cKDTree(centre[fixed]), jaw_tree=cKDTree(centre[jaw]), jaw_nodes=jaw_nodes,
                        jaw_rest=jaw_rest, stiffness=stiffness, tolerance=tolerance)


def rigid_motion(rest: np.ndarray, now: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R, t with now ~ rest @ R.T + t (Kabsch)."""
    cr, cn = rest.mean(axis=0), now.mean(axis=0)
    h = (rest - cr).T @ (now - cn)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, cn - cr @ r.T


def closest_on_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Closest points on triangles (a, b, c) to points p, all (K,3) (Ericson's regions, vectorised)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = p - b
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = p - c
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(denom != 0, vb / denom, 0.0)
        w = np.where(denom != 0, vc / denom, 0.0)
        out = a + v[:, None] * ab + w[:, None] * ac  # interior
        # edges
        t_ab = np.clip(d1 / np.where(d1 - d3 != 0, d1 - d3, 1), 0, 1)
        t_ac = np.clip(d2 / np.where(d2 - d6 != 0, d2 - d6, 1), 0, 1)
        t_bc = np.clip((d4 - d3) / np.where((d4 - d3) + (d5 - d6) != 0, (d4 - d3) + (d5 - d6), 1), 0, 1)
    on_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    on_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    on_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    out = np.where(on_bc[:, None], b + t_bc[:, None] * (c - b), out)
    out = np.where(on_ac[:, None], a + t_ac[:, None] * ac, out)
    out = np.where(on_ab[:, None], a + t_ab[:, None] * ab, out)
    out = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, out)
    out = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, out)
    out = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, out)
    return out


def _nearest(cm: ContactModel, p: np.ndarray, tree: cKDTree, tris: np.ndarray):
    """Closest wall point, its triangle normal and the signed distance along it."""
    k = min(cm.neighbours, len(tris))
    _, idx = tree.query(p, k=k)
    idx = idx.reshape(len(p), k)
    if kernels.AVAILABLE and elements.USE_KERNELS:
        return kernels.nearest_on_triangles(np.ascontiguousarray(p), tris[idx], cm.corners, cm.wall.normals)
    t = cm.wall.triangles[tris[idx]]  # (P,k,3)
    v = cm.wall.vertices
    pp = np.repeat(p, k, axis=0)
    q = closest_on_triangles(pp, v[t[..., 0]].reshape(-1, 3), v[t[..., 1]].reshape(-1, 3),
                             v[t[..., 2]].reshape(-1, 3)).reshape(len(p), k, 3)
    dist = np.linalg.norm(q - p[:, None], axis=2)
    best = dist.argmin(axis=1)
    rows = np.arange(len(p))
    q = q[rows, best]
    n = cm.wall.normals[tris[idx[rows, best]]]
    g = ((p - q) * n).sum(axis=1)
    return q, n, g


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


def wall_query(cm: ContactModel, x: np.ndarray, nodes: np.ndarray | None = None):
    """Closest wall point, normal and signed gap (> 0: beyond the wall) for contact nodes."""
    nodes = cm.nodes if nodes is None else nodes
    p = x[nodes]
    q1, n1, g1 = _nearest(cm, p, cm.fixed_tree, cm.fixed_tris)
    r, t = rigid_motion(cm.jaw_rest, x[cm.jaw_nodes])
    pj = (p - t) @ r  # into the jaw's rest frame
    q2, n2, g2 = _nearest(cm, pj, cm.jaw_tree, cm.jaw_tris)
    q2, n2 = q2 @ r.T + t, n2 @ r.T
    d1 = np.linalg.norm(p - q1, axis=1)
    d2 = np.linalg.norm(p - q2, axis=1)
    use_jaw = d2 < d1
    q = np.where(use_jaw[:, None], q2, q1)
    n = np.where(use_jaw[:, None], n2, n1)
    g = np.where(use_jaw, g2, g1)
    return q, n, g, use_jaw


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
