"""The wall's closest points: exact candidate grids of triangles, and for every contact node its closest wall
point, the wall's normal there and the signed gap, with the mandible's part of the wall moving rigidly with
the jaw (closest points found in the jaw's rest frame, Kabsch).  The compiled loops below give the numpy
path's numbers."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import cKDTree

from ..jit import compiled, njit

if TYPE_CHECKING:  # the contact model carries the grids this module searches
    from .contact import ContactModel


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
    if compiled():
        offsets, cands = grid_candidates(centres, tris, np.ascontiguousarray(corners), slack + 1e-9)
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


FEATURE_EPS = 1e-6  # cm: closer to the wall than this, a point takes its closest triangle's own normal


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
    far = length > FEATURE_EPS
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


def wall_query(cm: ContactModel, x: np.ndarray, nodes: np.ndarray | None = None):
    """Closest wall point, normal and signed gap (> 0: beyond the wall) for contact nodes."""
    nodes = cm.nodes if nodes is None else nodes
    p = x[nodes]
    if compiled():
        r, t = rigid_motion_compiled(cm.jaw_rest, np.ascontiguousarray(x[cm.jaw_nodes]))
        return wall_nearest(p, (p - t) @ r, cm.fixed_grid.as_tuple(), cm.jaw_grid.as_tuple(), cm.corners,
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


# --- compiled loops (numba): the same numbers as the numpy path above ---------------------------------

@njit(cache=True, fastmath=False)
def _dot(a0, a1, a2, b0, b1, b2):
    return a0 * b0 + a1 * b1 + a2 * b2


@njit(cache=True, fastmath=False)
def _closest_on_triangle(p, t):
    """Closest point on triangle t (3,3) to p (3,) (Ericson, Real-Time Collision Detection 5.1.5)."""
    ab0, ab1, ab2 = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
    ac0, ac1, ac2 = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
    ap0, ap1, ap2 = p[0] - t[0, 0], p[1] - t[0, 1], p[2] - t[0, 2]
    d1 = _dot(ab0, ab1, ab2, ap0, ap1, ap2)
    d2 = _dot(ac0, ac1, ac2, ap0, ap1, ap2)
    if d1 <= 0.0 and d2 <= 0.0:
        return t[0, 0], t[0, 1], t[0, 2]
    bp0, bp1, bp2 = p[0] - t[1, 0], p[1] - t[1, 1], p[2] - t[1, 2]
    d3 = _dot(ab0, ab1, ab2, bp0, bp1, bp2)
    d4 = _dot(ac0, ac1, ac2, bp0, bp1, bp2)
    if d3 >= 0.0 and d4 <= d3:
        return t[1, 0], t[1, 1], t[1, 2]
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return t[0, 0] + v * ab0, t[0, 1] + v * ab1, t[0, 2] + v * ab2
    cp0, cp1, cp2 = p[0] - t[2, 0], p[1] - t[2, 1], p[2] - t[2, 2]
    d5 = _dot(ab0, ab1, ab2, cp0, cp1, cp2)
    d6 = _dot(ac0, ac1, ac2, cp0, cp1, cp2)
    if d6 >= 0.0 and d5 <= d6:
        return t[2, 0], t[2, 1], t[2, 2]
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return t[0, 0] + w * ac0, t[0, 1] + w * ac1, t[0, 2] + w * ac2
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return (t[1, 0] + w * (t[2, 0] - t[1, 0]), t[1, 1] + w * (t[2, 1] - t[1, 1]),
                t[1, 2] + w * (t[2, 2] - t[1, 2]))
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    return (t[0, 0] + v * ab0 + w * ac0, t[0, 1] + v * ab1 + w * ac1, t[0, 2] + v * ab2 + w * ac2)


@njit(cache=True, fastmath=False)
def grid_candidates(centres, tris, corners, slack):
    """For each voxel centre (V,3): the triangles of ``tris`` within ``slack`` of its smallest distance to
    them (see :class:`..contact.CandidateGrid`).  Returns offsets (V+1,) and triangle indices.

    Bounding spheres skip most exact distances: d(c, T) >= |c - centre_T| - reach_T."""
    nt = len(tris)
    mid = np.empty((nt, 3))
    reach = np.empty(nt)
    for k in range(nt):
        for a in range(3):
            mid[k, a] = (corners[tris[k], 0, a] + corners[tris[k], 1, a] + corners[tris[k], 2, a]) / 3.0
        r = 0.0
        for v in range(3):
            d = 0.0
            for a in range(3):
                d += (corners[tris[k], v, a] - mid[k, a]) ** 2
            r = max(r, np.sqrt(d))
        reach[k] = r
    nv = centres.shape[0]
    offsets = np.zeros(nv + 1, dtype=np.int64)
    out = np.empty(nv * 8, dtype=np.int64)
    lower = np.empty(nt)
    exact = np.empty(nt)
    used = 0
    for v in range(nv):
        c = centres[v]
        nearest, best = 0, np.inf
        for k in range(nt):
            d = np.sqrt((c[0] - mid[k, 0]) ** 2 + (c[1] - mid[k, 1]) ** 2 + (c[2] - mid[k, 2]) ** 2)
            lower[k] = d - reach[k]
            if d < best:
                nearest, best = k, d
        q0, q1, q2 = _closest_on_triangle(c, corners[tris[nearest]])
        upper = np.sqrt((c[0] - q0) ** 2 + (c[1] - q1) ** 2 + (c[2] - q2) ** 2)  # >= the smallest distance
        dmin = np.inf
        for k in range(nt):
            exact[k] = np.inf
            if lower[k] <= upper:
                q0, q1, q2 = _closest_on_triangle(c, corners[tris[k]])
                exact[k] = np.sqrt((c[0] - q0) ** 2 + (c[1] - q1) ** 2 + (c[2] - q2) ** 2)
                dmin = min(dmin, exact[k])
        for k in range(nt):
            if lower[k] <= dmin + slack:
                if exact[k] == np.inf:
                    q0, q1, q2 = _closest_on_triangle(c, corners[tris[k]])
                    exact[k] = np.sqrt((c[0] - q0) ** 2 + (c[1] - q1) ** 2 + (c[2] - q2) ** 2)
                if exact[k] <= dmin + slack:
                    if used == len(out):
                        grown = np.empty(2 * len(out), dtype=np.int64)
                        grown[:used] = out[:used]
                        out = grown
                    out[used] = tris[k]
                    used += 1
        offsets[v + 1] = used
    return offsets, out[:used].copy()


@njit(cache=True, fastmath=False)
def _nearest_in_grid(p, grid, corners, normals, q, n):
    """Closest point q (3,) to p (3,) over the candidate triangles of p's voxel (all triangles outside the
    grid; ``grid`` = :meth:`..contact.CandidateGrid.as_tuple`), and the wall's normal n (3,) there: the
    direction from q to p, turned to the triangle normal's side (:func:`..contact.feature_normal`)."""
    lo, spacing, dims, offsets, cands, tris = grid
    cell = 0
    inside = True
    for a in range(3):
        c = int(np.floor((p[a] - lo[a]) / spacing))
        if c < 0 or c >= dims[a]:
            inside = False
        cell = cell * dims[a] + c
    ids = cands[offsets[cell]: offsets[cell + 1]] if inside else tris
    best = np.inf
    for m in range(len(ids)):
        t = ids[m]
        q0, q1, q2 = _closest_on_triangle(p, corners[t])
        d = (p[0] - q0) ** 2 + (p[1] - q1) ** 2 + (p[2] - q2) ** 2
        if d < best:
            best = d
            q[0], q[1], q[2] = q0, q1, q2
            n[0], n[1], n[2] = normals[t, 0], normals[t, 1], normals[t, 2]
    d = np.sqrt(best)
    if d > FEATURE_EPS:
        s = (p[0] - q[0]) * n[0] + (p[1] - q[1]) * n[1] + (p[2] - q[2]) * n[2]
        sign = 1.0 if s >= 0.0 else -1.0
        for a in range(3):
            n[a] = sign * (p[a] - q[a]) / d


@njit(cache=True, fastmath=False)
def wall_nearest(p, pj, fixed_grid, jaw_grid, corners, normals, r, t):
    """:func:`..contact.wall_query` for points p (P,3) (and pj, the same points in the jaw's rest frame):
    the closer of the nearest skull point and the nearest mandible point (found in the rest frame, mapped
    by x -> r x + t).  Returns closest points (P,3), normals (P,3), signed gaps (P,) and whether the
    mandible won (P,)."""
    npt = p.shape[0]
    q = np.empty((npt, 3))
    n = np.empty((npt, 3))
    g = np.empty(npt)
    use_jaw = np.zeros(npt, dtype=np.bool_)
    q1 = np.empty(3)
    n1 = np.empty(3)
    q2 = np.empty(3)
    n2 = np.empty(3)
    qw = np.empty(3)
    nw = np.empty(3)
    for i in range(npt):
        _nearest_in_grid(p[i], fixed_grid, corners, normals, q1, n1)
        _nearest_in_grid(pj[i], jaw_grid, corners, normals, q2, n2)
        g1 = (p[i, 0] - q1[0]) * n1[0] + (p[i, 1] - q1[1]) * n1[1] + (p[i, 2] - q1[2]) * n1[2]
        g2 = (pj[i, 0] - q2[0]) * n2[0] + (pj[i, 1] - q2[1]) * n2[1] + (pj[i, 2] - q2[2]) * n2[2]
        for a in range(3):
            qw[a] = q2[0] * r[a, 0] + q2[1] * r[a, 1] + q2[2] * r[a, 2] + t[a]
            nw[a] = n2[0] * r[a, 0] + n2[1] * r[a, 1] + n2[2] * r[a, 2]
        d1 = np.sqrt((p[i, 0] - q1[0]) ** 2 + (p[i, 1] - q1[1]) ** 2 + (p[i, 2] - q1[2]) ** 2)
        d2 = np.sqrt((p[i, 0] - qw[0]) ** 2 + (p[i, 1] - qw[1]) ** 2 + (p[i, 2] - qw[2]) ** 2)
        if d2 < d1:
            use_jaw[i] = True
            for a in range(3):
                q[i, a], n[i, a] = qw[a], nw[a]
            g[i] = g2
        else:
            for a in range(3):
                q[i, a], n[i, a] = q1[a], n1[a]
            g[i] = g1
    return q, n, g, use_jaw


@njit(cache=True, fastmath=False)
def rigid_motion_compiled(rest, now):
    """R, t with now ~ rest @ R.T + t (Kabsch), as :func:`..contact.rigid_motion`."""
    m = rest.shape[0]
    cr = np.zeros(3)
    cn = np.zeros(3)
    for i in range(m):
        for a in range(3):
            cr[a] += rest[i, a] / m
            cn[a] += now[i, a] / m
    h = np.zeros((3, 3))
    for i in range(m):
        for a in range(3):
            for b in range(3):
                h[a, b] += (rest[i, a] - cr[a]) * (now[i, b] - cn[b])
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    for a in range(3):
        vt[2, a] *= d
    r = vt.T @ u.T
    t = cn - r @ cr
    return r, t
