"""Compiled inner loops (numba) of a time step, each the same numbers as its numpy counterpart (tests compare).

* cylinders and links: state (length, strain, modulus), nodal forces, and the tangent's 3x3 blocks per node
  pair (``cylinder_state``, ``cylinder_forces``, ``node_blocks``);
* bricks: volume and inversion-guard terms with their gradients (``brick_terms``);
* the wall: exact candidate grids and the closest triangle of each point, and the mandible's rigid motion
  (``grid_candidates``, ``wall_nearest``, ``rigid_motion``);
* muscle fibres: segment geometry, nodal forces and length gradients (``fibre_geometry``, ``fibre_forces``,
  ``fibre_gradients``).

Without numba the functions run as plain Python (slowly); numba is a dependency.
"""

from __future__ import annotations

import numpy as np

try:  # pragma: no cover - exercised whenever numba is installed (a dependency)
    from numba import njit

    AVAILABLE = True
except ImportError:  # pragma: no cover
    AVAILABLE = False

    def njit(*args, **kwargs):
        def wrap(fn):
            return fn
        return wrap(args[0]) if args and callable(args[0]) else wrap

FEATURE_EPS = 1e-6  # cm: closer to the wall than this, a point takes its closest triangle's own normal


@njit(cache=True, fastmath=False)
def cylinder_state(x, ci, cj, l0, area0, youngs, poisson, knee, rate, slack):
    """Per cylinder: unit axis n (C,3), length, strain, shrink, E, dE/de, elastic tension (the slack law
    as elements.youngs_modulus)."""
    c = len(ci)
    n = np.empty((c, 3))
    length = np.empty(c)
    strain = np.empty(c)
    shrink = np.empty(c)
    e = np.empty(c)
    de = np.empty(c)
    elastic = np.empty(c)
    for k in range(c):
        a, b = ci[k], cj[k]
        d0 = x[b, 0] - x[a, 0]
        d1 = x[b, 1] - x[a, 1]
        d2 = x[b, 2] - x[a, 2]
        ln = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        length[k] = ln
        n[k, 0] = d0 / ln
        n[k, 1] = d1 / ln
        n[k, 2] = d2 / ln
        s = ln / l0[k] - 1.0
        strain[k] = s
        sh = 1.0 - poisson[k] * s
        if sh < 0.05:
            sh = 0.05
        shrink[k] = sh
        over = s - knee[k]
        if abs(slack[k]) < np.inf and s * slack[k] > 0.0:  # the side the link gives way on
            if s / slack[k] >= 1.0:
                e[k] = youngs[k] * slack[k] / (2.0 * s)
                de[k] = -youngs[k] * slack[k] / (2.0 * s * s)
            else:
                e[k] = youngs[k] * (1.0 - s / (2.0 * slack[k]))
                de[k] = -youngs[k] / (2.0 * slack[k])
        elif over > 0.0:
            g = min(rate[k] * over, 50.0)
            ek = youngs[k] * np.exp(g)
            e[k] = ek
            de[k] = rate[k] * ek
        else:
            e[k] = youngs[k]
            de[k] = 0.0
        elastic[k] = e[k] * s * area0[k] * sh * sh
    return n, length, strain, shrink, e, de, elastic


@njit(cache=True, fastmath=False)
def cylinder_forces(n, elastic, ci, cj, frame_n, frame_c, v, n_nodes, with_damping):
    """Nodal forces (N,3) of the cylinders: elastic tension along n, dashpot along the step's frame."""
    f = np.zeros((n_nodes, 3))
    for k in range(len(ci)):
        a, b = ci[k], cj[k]
        t = elastic[k]
        g0 = t * n[k, 0]
        g1 = t * n[k, 1]
        g2 = t * n[k, 2]
        if with_damping:
            r = (frame_n[k, 0] * (v[b, 0] - v[a, 0]) + frame_n[k, 1] * (v[b, 1] - v[a, 1])
                 + frame_n[k, 2] * (v[b, 2] - v[a, 2])) * frame_c[k]
            g0 += r * frame_n[k, 0]
            g1 += r * frame_n[k, 1]
            g2 += r * frame_n[k, 2]
        f[a, 0] += g0
        f[a, 1] += g1
        f[a, 2] += g2
        f[b, 0] -= g0
        f[b, 1] -= g1
        f[b, 2] -= g2
    return f


@njit(cache=True, fastmath=False)
def node_blocks(n, length, elastic, axial, frame_n, frame_c, c_v, signed, ci, cj, cyl_pair,
                bricks, brick_pair, grad, brick_w, seg_i, seg_j, seg_pair, seg_k, n_pairs, n_nodes):
    """Node-level tangent blocks (P + N, 3, 3): node pairs (i < j), then diagonals.

    Cylinders: k = (K_ax - T/l) n n^T + T/l I + c_v c n0 n0^T on both diagonals, -k on their pair.
    Bricks: w g_a g_b^T for every corner pair (Gauss-Newton volume tangent, ``grad`` (B,8,3), may be
    empty).  Fibre segments: their own 3x3 ``seg_k`` like cylinders."""
    out = np.zeros((n_pairs + n_nodes, 3, 3))
    k3 = np.empty((3, 3))
    for k in range(len(length)):
        t = elastic[k] if signed else max(elastic[k], 0.0)
        kg = t / length[k]
        kn = max(axial[k], 0.0) - kg
        cv = c_v * frame_c[k]
        for p in range(3):
            for q in range(3):
                k3[p, q] = kn * n[k, p] * n[k, q] + cv * frame_n[k, p] * frame_n[k, q]
            k3[p, p] += kg
        a, b, m = n_pairs + ci[k], n_pairs + cj[k], cyl_pair[k]
        for p in range(3):
            for q in range(3):
                out[a, p, q] += k3[p, q]
                out[b, p, q] += k3[p, q]
                out[m, p, q] -= k3[p, q]
    for e in range(grad.shape[0]):
        w = brick_w[e]
        for a in range(8):
            na = bricks[e, a]
            for b in range(8):
                nb = bricks[e, b]
                if na < nb:
                    m = brick_pair[e, a, b]
                elif a == b:
                    m = n_pairs + na
                else:
                    continue
                for p in range(3):
                    wp = w * grad[e, a, p]
                    for q in range(3):
                        out[m, p, q] += wp * grad[e, b, q]
    for k in range(len(seg_pair)):
        a, b, m = n_pairs + seg_i[k], n_pairs + seg_j[k], seg_pair[k]
        for p in range(3):
            for q in range(3):
                v = seg_k[k, p, q]
                out[a, p, q] += v
                out[b, p, q] += v
                out[m, p, q] -= v
    return out


@njit(cache=True, fastmath=False)
def _jacobian_det(xl, dn, jac, cof):
    """det of a brick's Jacobian at one reference point (corner coordinates ``xl`` (8,3), shape gradients
    ``dn`` (8,3)); fills ``jac`` (its columns, jac[l, i]) and ``cof`` (d det / d column l = cross of the
    other two columns)."""
    for l in range(3):
        j0 = 0.0
        j1 = 0.0
        j2 = 0.0
        for a in range(8):
            d = dn[a, l]
            if d != 0.0:  # at a corner only 2 of 8 shape gradients are non-zero per direction
                j0 += xl[a, 0] * d
                j1 += xl[a, 1] * d
                j2 += xl[a, 2] * d
        jac[l, 0] = j0
        jac[l, 1] = j1
        jac[l, 2] = j2
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        cof[0, i] = jac[1, i1] * jac[2, i2] - jac[1, i2] * jac[2, i1]
        cof[1, i] = jac[2, i1] * jac[0, i2] - jac[2, i2] * jac[0, i1]
        cof[2, i] = jac[0, i1] * jac[1, i2] - jac[0, i2] * jac[1, i1]
    return jac[0, 0] * cof[0, 0] + jac[0, 1] * cof[0, 1] + jac[0, 2] * cof[0, 2]


@njit(cache=True, fastmath=False)
def brick_terms(x, bricks, dn_gauss, dn_corner, v0, kappa, j0, guard_w, fraction):
    """Volume penalty and inversion guard of every brick in one pass.

    Returns forces (N,3), volumes (B,), dV/dx (B,8,3), the guarded (brick, corner) pairs (K,2), their
    d(J/J0)/dx (K,8,3) and weights (K,).  Same formulas as :mod:`.volume` and :mod:`..geometry.hexahedra`.
    """
    nb = bricks.shape[0]
    f = np.zeros_like(x)
    vol = np.zeros(nb)
    grad = np.zeros((nb, 8, 3))
    gk = []
    gg = []
    gw = []
    jac = np.empty((3, 3))
    cof = np.empty((3, 3))
    xl = np.empty((8, 3))
    for b in range(nb):
        for a in range(8):
            for i in range(3):
                xl[a, i] = x[bricks[b, a], i]
        for g in range(dn_gauss.shape[0]):
            det = _jacobian_det(xl, dn_gauss[g], jac, cof)
            vol[b] += det
            for a in range(8):
                for i in range(3):
                    grad[b, a, i] += (cof[0, i] * dn_gauss[g, a, 0] + cof[1, i] * dn_gauss[g, a, 1]
                                      + cof[2, i] * dn_gauss[g, a, 2])
        scale = -kappa[b] * (vol[b] - v0[b]) / v0[b]
        if scale != 0.0:
            for a in range(8):
                for i in range(3):
                    f[bricks[b, a], i] += scale * grad[b, a, i]
        if guard_w.shape[0] == 0:
            continue
        for c in range(8):
            det = _jacobian_det(xl, dn_corner[c], jac, cof)
            ratio = det / j0[b, c]
            if ratio < fraction:
                gc = np.empty((8, 3))
                for a in range(8):
                    for i in range(3):
                        gc[a, i] = (cof[0, i] * dn_corner[c, a, 0] + cof[1, i] * dn_corner[c, a, 1]
                                    + cof[2, i] * dn_corner[c, a, 2]) / j0[b, c]
                w = guard_w[b]
                depth = fraction - ratio
                push = w * depth * depth / fraction
                for a in range(8):
                    for i in range(3):
                        f[bricks[b, a], i] += push * gc[a, i]
                gk.append((b, c))
                gg.append(gc)
                gw.append(2.0 * w * depth / fraction)
    k = len(gk)
    pairs = np.empty((k, 2), dtype=np.int64)
    gout = np.empty((k, 8, 3))
    wout = np.empty(k)
    for m in range(k):
        pairs[m, 0] = gk[m][0]
        pairs[m, 1] = gk[m][1]
        gout[m] = gg[m]
        wout[m] = gw[m]
    return f, vol, grad, pairs, gout, wout


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
def rigid_motion(rest, now):
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


@njit(cache=True, fastmath=False)
def fibre_geometry(x, seg_i, seg_j, seg_fibre, n_fibres):
    """Segment unit vectors (S,3), segment lengths (S,) and fibre lengths (F,)."""
    s = len(seg_i)
    n = np.empty((s, 3))
    length = np.empty(s)
    total = np.zeros(n_fibres)
    for k in range(s):
        a, b = seg_i[k], seg_j[k]
        d0 = x[b, 0] - x[a, 0]
        d1 = x[b, 1] - x[a, 1]
        d2 = x[b, 2] - x[a, 2]
        ln = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        length[k] = ln
        n[k, 0] = d0 / ln
        n[k, 1] = d1 / ln
        n[k, 2] = d2 / ln
        total[seg_fibre[k]] += ln
    return n, length, total


@njit(cache=True, fastmath=False)
def fibre_forces(n, tension, seg_i, seg_j, seg_fibre, n_nodes):
    """(N,3) nodal forces of fibres pulling with ``tension`` (F,) along their segments."""
    f = np.zeros((n_nodes, 3))
    for k in range(len(seg_i)):
        t = tension[seg_fibre[k]]
        for i in range(3):
            f[seg_i[k], i] += t * n[k, i]
            f[seg_j[k], i] -= t * n[k, i]
    return f


@njit(cache=True, fastmath=False)
def fibre_gradients(n, seg_i, seg_j, seg_col, n_nodes, r):
    """(N,3,r) gradient of fibre lengths: column ``seg_col[k]`` (-1: none) gets +n at seg_j, -n at seg_i."""
    g = np.zeros((n_nodes, 3, r))
    for k in range(len(seg_i)):
        c = seg_col[k]
        if c < 0:
            continue
        for i in range(3):
            g[seg_j[k], i, c] += n[k, i]
            g[seg_i[k], i, c] -= n[k, i]
    return g


@njit(cache=True, fastmath=False, error_model="numpy")
def fibre_tensions(total, l0, sigma2_prev, strain_prev, h, k1, k2, b2, activation, fibre_muscle, share, area,
                   width, coeffs, lo, hi):
    """Strain, Maxwell stress and tension of every fibre (:func:`..muscles.fibre_state`'s numbers) from its
    length ``total``; ``coeffs`` Eq. (9) highest power first, zero outside ``lo < e / width < hi``."""
    nf = len(total)
    strain = np.empty(nf)
    sigma2 = np.empty(nf)
    tension = np.empty(nf)
    relax = 1.0 + h * k2 / b2 if h > 0 else 1.0
    for f in range(nf):
        e = total[f] / l0[f] - 1.0
        s2 = (sigma2_prev[f] + k2 * (e - strain_prev[f])) / relax if h > 0 else sigma2_prev[f]
        passive = k1 * max(e, 0.0) * e + s2
        u = e / width
        fl = 0.0
        if lo < u < hi:
            p = coeffs[0]
            for c in coeffs[1:]:
                p = p * u + c
            fl = max(p / coeffs[-1], 0.0)
        strain[f] = e
        sigma2[f] = s2
        tension[f] = activation[fibre_muscle[f]] * share[f] * fl + area[f] * passive
    return strain, sigma2, tension
