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

from ..geometry.hexahedra import corner_jacobians, corner_jacobians_at, volume_gradients, volumes

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
