"""Volume constraint: a per-brick penalty on volume change.

The paper's Eq. (6)-(7) penalises the change of each cylinder's volume under
the radius law; with nu = 0.49 that change is only (1 - 2 nu) e = 2 % of the
cylinder strain, so it hardly constrains anything.  We penalise what we want
to keep instead, the volume of every brick:

    U = sum_m  kappa_m / 2 * (V_m - V0_m)^2 / V0_m,

i.e. a bulk modulus kappa acting on each brick, with exact brick volumes and
gradients.  Its Gauss-Newton tangent kappa/V0 g g^T is positive semidefinite
and lives inside the cylinder sparsity pattern (every brick's node pairs are
cylinders), so it adds no fill-in.  kappa is calibrated so that the lattice
has the Table I Poisson ratio (see :mod:`artic_cli.mechanics.calibration`).
"""

from __future__ import annotations

import numpy as np

from ..geometry.hexahedra import (SHAPE_GRADIENTS_CORNER, SHAPE_GRADIENTS_GAUSS, corner_jacobians, corner_jacobians_at,
                                  volume_gradients, volumes)
from ..jit import compiled, njit
from .term import Evaluation, ForceTerm

# Inversion guard: a corner whose Jacobian falls below this fraction f of its rest value is pushed back by
# U = w / (3 f) (f - J / J0)^3, w = bulk modulus x V0 / 8 (one eighth of the brick per corner).  Cubic, so
# its stiffness grows from zero at the threshold (a quadratic guard's stiffness jumps there, and Newton
# chattered on and off it when a corner came to rest on the threshold); at J = 0 it pushes as hard (w f).
# It is zero in ordinary motion and keeps bricks from turning inside out under extreme shear
# (7 N antagonists pulling the midsagittal and parasagittal planes apart).
GUARD_FRACTION = 0.25


def volume_forces(x: np.ndarray, bricks: np.ndarray, v0: np.ndarray, kappa: np.ndarray):
    """Nodal forces (N,3), brick volumes (B,), gradients (B,8,3)."""
    vol, grad = volume_gradients(x, bricks)
    scale = -kappa * (vol - v0) / v0  # (B,)
    contrib = scale[:, None, None] * grad  # (B,8,3)
    n = x.shape[0]
    flat = bricks.ravel()
    f = np.column_stack([np.bincount(flat, weights=contrib[..., k].ravel(), minlength=n) for k in range(3)])
    return f, vol, grad


def volume_energy(x: np.ndarray, bricks: np.ndarray, v0: np.ndarray, kappa: np.ndarray) -> float:
    vol = volumes(x, bricks)
    return float((0.5 * kappa * (vol - v0) ** 2 / v0).sum())


def corner_guard(x: np.ndarray, bricks: np.ndarray, j0: np.ndarray, weight: np.ndarray):
    """Guard forces (N,3) and, for the tangent, the active corners' (bricks (K,), d(J/J0)/dx (K,8,3), w (K,)).

    ``None`` for the second item when no corner is near inversion."""
    f = np.zeros_like(x)
    ratio = corner_jacobians(x, bricks) / j0
    b, c = np.nonzero(ratio < GUARD_FRACTION)
    if len(b) == 0:
        return f, None
    _, grad = corner_jacobians_at(x, bricks, b, c)
    g = grad / j0[b, c][:, None, None]
    depth = GUARD_FRACTION - ratio[b, c]
    contrib = (weight[b] * depth**2 / GUARD_FRACTION)[:, None, None] * g  # -dU/dx
    np.add.at(f, bricks[b], contrib)
    return f, (b, c, g, 2.0 * weight[b] * depth / GUARD_FRACTION)


# --- the term ----------------------------------------------------------------------------------------------

class VolumeTerm(ForceTerm):
    """The bricks: the volume penalty (when the constraint is on; Gauss-Newton tangent kappa/V0 g g^T in the
    band) and the inversion guard (its active corners as rank-one terms)."""

    name = "volume"

    def forces(self, model, ev: Evaluation, f: np.ndarray) -> None:
        nt, on = model.n_tongue, model.volume_constraint
        grad = guard = None
        if compiled() and model.corner_j0 is not None:
            kappa = model.kappa if on else np.zeros_like(model.kappa)
            fb, _, grad, pairs, g, w = brick_terms(np.ascontiguousarray(ev.x[:nt]), model.bricks, SHAPE_GRADIENTS_GAUSS,
                                                   SHAPE_GRADIENTS_CORNER, model.brick_v0, kappa, model.corner_j0,
                                                   model.guard_weight, GUARD_FRACTION)
            f[:nt] += fb
            guard = (pairs[:, 0], pairs[:, 1], g, w) if len(pairs) else None
            grad = grad if on else None
        else:
            if on:
                fv, _, grad = volume_forces(ev.x[:nt], model.bricks, model.brick_v0, model.kappa)
                f[:nt] += fv
            if model.corner_j0 is not None:
                fg, guard = corner_guard(ev.x[:nt], model.bricks, model.corner_j0, model.guard_weight)
                f[:nt] += fg
        ev.parts[self.name] = (grad, guard)

    def blocks(self, model, ev: Evaluation, out: np.ndarray, signed: bool = True) -> None:
        grad = ev.parts[self.name][0]
        if grad is None:
            return
        asm = model.layout.assembly
        grad = grad.reshape(len(model.brick_v0), 8, 3)
        w = model.kappa / model.brick_v0
        if compiled():
            brick_blocks(out, model.bricks, asm.brick_pair, grad, w, asm.n_pairs)
        else:
            asm.add_bricks(out, model.bricks, grad, w)

    def rank_one(self, model, ev: Evaluation):
        guard = ev.parts[self.name][1]
        if guard is None:  # no corner near inversion
            return None
        b, _, g, w = guard
        v = np.zeros((model.n_nodes, 3, len(b)))
        np.add.at(v, (model.bricks[b], slice(None), np.arange(len(b))[:, None]), g)
        return v.reshape(3 * model.n_nodes, -1), w

    def key(self, model, ev: Evaluation) -> tuple:
        guard = ev.parts[self.name][1]
        return () if guard is None else tuple(zip(guard[0].tolist(), guard[1].tolist()))


# --- compiled loops (numba): the same numbers as the numpy path above ---------------------------------

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
def brick_blocks(out, bricks, brick_pair, grad, brick_w, n_pairs):
    """Adds w g_a g_b^T for every two corners of every brick (the Gauss-Newton volume tangent; ``grad``
    (B,8,3)) to the node-level blocks ``out`` (P + N, 3, 3)."""
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
    return out
