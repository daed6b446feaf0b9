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
from scipy.spatial import cKDTree

from ..geometry.wall import PARTS, WallSurface
from . import elements, kernels


@dataclass(frozen=True)
class CandidateGrid:
    """A voxel grid that lists, for every voxel, each triangle that can hold the closest wall point of a
    point inside it.  Exact: with c the voxel's centre and r its half diagonal, the closest triangle T of
    any point p of the voxel has d(c, T) <= d(p, T) + r <= d(p, T*) + r <= d(c, T*) + 2 r for the triangle
    T* closest to c, so every triangle within 2 r of the smallest centre distance is listed.  Points
    outside the grid search all triangles."""

    lo: np.ndarray  # (3,) cm, the grid's lower corner
    spacing: float  # cm
    dims: np.ndarray  # (3,) voxels along x, y, z
    offsets: np.ndarray  # (V+1,) voxel v lists cands[offsets[v]:offsets[v + 1]]
    cands: np.ndarray  # triangle indices
    tris: np.ndarray  # all triangles of this part

    def as_tuple(self) -> tuple:
        return self.lo, float(self.spacing), self.dims, self.offsets, self.cands, self.tris

    def candidates(self, p: np.ndarray) -> np.ndarray:
        """Triangle indices to search for point p (3,)."""
        cell = np.floor((p - self.lo) / self.spacing).astype(np.int64)
        if (cell < 0).any() or (cell >= self.dims).any():
            return self.tris
        v = (cell[0] * self.dims[1] + cell[1]) * self.dims[2] + cell[2]
        return self.cands[self.offsets[v]: self.offsets[v + 1]]


def candidate_grid(corners: np.ndarray, tris: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                   spacing: float = 0.25) -> CandidateGrid:
    """The exact candidate lists of :class:`CandidateGrid` for triangles ``tris`` over the box [lo, hi]."""
    lo = np.asarray(lo, dtype=float)
    dims = np.maximum(np.ceil((np.asarray(hi) - lo) / spacing), 1).astype(np.int64)
    axes = [lo[a] + spacing * (np.arange(dims[a]) + 0.5) for a in range(3)]
    centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    slack = spacing * np.sqrt(3.0)  # the voxel's diameter, 2 r
    tris = np.asarray(tris, dtype=np.int64)
    if kernels.AVAILABLE and elements.USE_KERNELS:
        offsets, cands = kernels.grid_candidates(centres, tris, np.ascontiguousarray(corners), slack + 1e-9)
        return CandidateGrid(lo=lo, spacing=float(spacing), dims=dims, offsets=offsets, cands=cands, tris=tris)
    tri_centre = corners[tris].mean(axis=1)
    reach = float(np.linalg.norm(corners[tris] - tri_centre[:, None], axis=2).max())  # centre to farthest corner
    tree = cKDTree(tri_centre)
    _, near = tree.query(centres, k=min(4, len(tris)))
    near = near.reshape(len(centres), -1)
    upper = _distances(np.repeat(centres, near.shape[1], axis=0), tris[near.ravel()], corners)
    bound = upper.reshape(near.shape).min(axis=1)  # >= the smallest distance from each centre
    # every triangle within bound + 2 r of a centre has its own centre within bound + 2 r + reach of it
    ball = tree.query_ball_point(centres, bound + slack + reach)
    counts = np.array([len(b) for b in ball])
    point = np.repeat(np.arange(len(centres)), counts)
    tri = tris[np.concatenate([np.asarray(b, dtype=np.int64) for b in ball])]
    d = _distances(centres[point], tri, corners)
    starts = np.r_[0, np.cumsum(counts)[:-1]]
    keep = d <= np.minimum.reduceat(d, starts)[point] + slack + 1e-9
    point, tri = point[keep], tri[keep]
    order = np.lexsort((tri, point))
    offsets = np.r_[0, np.cumsum(np.bincount(point, minlength=len(centres)))]
    return CandidateGrid(lo=lo, spacing=float(spacing), dims=dims, offsets=offsets, cands=tri[order], tris=tris)


def _distances(p: np.ndarray, tri: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Distance from each point p (K,3) to its triangle tri (K,)."""
    c = corners[tri]
    q = closest_on_triangles(p, c[:, 0], c[:, 1], c[:, 2])
    return np.linalg.norm(p - q, axis=1)


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


def feature_normal(p: np.ndarray, q: np.ndarray, face: np.ndarray) -> np.ndarray:
    """The wall's normal at closest points ``q`` (P, 3) of points ``p``: the direction from q to p, turned to
    the side of the closest triangle's normal ``face`` (the same as it where q is inside the triangle).  Where
    q lies on an edge or a corner the triangles meeting there give one normal, which turns continuously
    as p moves round the edge; a triangle's own normal would jump between its neighbours', so that two
    mirror-image points on either side of a seam could be pushed in directions that are not mirror images.
    Points within FEATURE_EPS of the wall keep the triangle's normal."""
    d = p - q
    length = np.linalg.norm(d, axis=1)
    sign = np.where((d * face).sum(axis=1) >= 0.0, 1.0, -1.0)
    far = length > kernels.FEATURE_EPS
    out = face.copy()
    out[far] = sign[far, None] * d[far] / length[far, None]
    return out


def _nearest(cm: ContactModel, p: np.ndarray, grid: CandidateGrid):
    """Closest wall point, the wall's normal there and the signed distance along it (numpy)."""
    q, n = np.empty_like(p), np.empty_like(p)
    for i, pi in enumerate(p):
        tris = grid.candidates(pi)
        c = cm.corners[tris]
        near = closest_on_triangles(np.broadcast_to(pi, (len(tris), 3)), c[:, 0], c[:, 1], c[:, 2])
        best = np.argmin(((near - pi) ** 2).sum(axis=1))
        q[i], n[i] = near[best], cm.wall.normals[tris[best]]
    n = feature_normal(p, q, n)
    return q, n, ((p - q) * n).sum(axis=1)


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
    if kernels.AVAILABLE and elements.USE_KERNELS:
        r, t = kernels.rigid_motion(cm.jaw_rest, np.ascontiguousarray(x[cm.jaw_nodes]))
        return kernels.wall_nearest(p, (p - t) @ r, cm.fixed_grid.as_tuple(), cm.jaw_grid.as_tuple(), cm.corners,
                                    cm.wall.normals, r, t)
    q1, n1, g1 = _nearest(cm, p, cm.fixed_grid)
    r, t = rigid_motion(cm.jaw_rest, x[cm.jaw_nodes])
    pj = (p - t) @ r  # into the jaw's rest frame
    q2, n2, g2 = _nearest(cm, pj, cm.jaw_grid)
    q2, n2 = q2 @ r.T + t, n2 @ r.T
    d1 = np.linalg.norm(p - q1, axis=1)
    d2 = np.linalg.norm(p - q2, axis=1)
    use_jaw = d2 < d1
    q = np.where(use_jaw[:, None], q2, q1)
    n = np.where(use_jaw[:, None], n2, n1)
    g = np.where(use_jaw, g2, g1)
    return q, n, g, use_jaw


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
