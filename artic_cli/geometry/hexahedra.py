"""Measures of trilinear eight-node bricks (VTK corner order), vectorised.

Corner ``a`` sits at reference coordinates ``REF[a]`` in [-1, 1]^3.  The volume
of a trilinear brick is integrated exactly by the 2x2x2 Gauss rule (det J is
of degree <= 2 in each reference coordinate), so ``volumes`` and its gradient
are exact, not approximations.
"""

from __future__ import annotations

import numpy as np

REF = np.array(
    [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
     [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)

_G = 1.0 / np.sqrt(3.0)
GAUSS = REF * _G  # 8 Gauss points, unit weights


def shape_gradients(points: np.ndarray) -> np.ndarray:
    """dN_a/dxi_l at reference points: array (P, 8, 3)."""
    p = np.asarray(points, dtype=float)[:, None, :]  # (P,1,3)
    f = 1.0 + REF[None] * p  # (P,8,3) factors (1 + xi_a,i xi_i)
    out = np.empty((p.shape[0], 8, 3))
    out[..., 0] = REF[None, :, 0] * f[..., 1] * f[..., 2]
    out[..., 1] = REF[None, :, 1] * f[..., 0] * f[..., 2]
    out[..., 2] = REF[None, :, 2] * f[..., 0] * f[..., 1]
    return out / 8.0


_DN_GAUSS = shape_gradients(GAUSS)  # (8 gauss, 8 corners, 3)
_DN_CORNER = shape_gradients(REF)


def _jacobian_columns(x: np.ndarray, bricks: np.ndarray, dn: np.ndarray) -> np.ndarray:
    """J[b, g, :, l] = sum_a x[brick a] dN_a/dxi_l (g): (B, G, 3, 3)."""
    xe = x[bricks]  # (B,8,3)
    return np.einsum("bai,gal->bgil", xe, dn)


def _det(j: np.ndarray) -> np.ndarray:
    c1, c2, c3 = j[..., 0], j[..., 1], j[..., 2]
    return np.einsum("...i,...i->...", c1, np.cross(c2, c3))


def volumes(x: np.ndarray, bricks: np.ndarray) -> np.ndarray:
    """Exact volume of every brick (B,)."""
    return _det(_jacobian_columns(x, bricks, _DN_GAUSS)).sum(axis=1)


def volume_gradients(x: np.ndarray, bricks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Volumes (B,) and dV/dx of each corner (B, 8, 3)."""
    j = _jacobian_columns(x, bricks, _DN_GAUSS)
    c1, c2, c3 = j[..., 0], j[..., 1], j[..., 2]
    cof = np.stack([np.cross(c2, c3), np.cross(c3, c1), np.cross(c1, c2)], axis=-1)  # (B,G,3,3)
    vol = np.einsum("bgi,bgi->b", c1, cof[..., 0])
    grad = np.einsum("bgil,gal->bai", cof, _DN_GAUSS)
    return vol, grad


def corner_jacobians(x: np.ndarray, bricks: np.ndarray) -> np.ndarray:
    """det J at the eight corners (B, 8); a brick is inverted where any is <= 0."""
    return _det(_jacobian_columns(x, bricks, _DN_CORNER))


def inverted_bricks(x: np.ndarray, bricks: np.ndarray) -> np.ndarray:
    """Indices of bricks turned inside out (a non-positive corner Jacobian)."""
    return np.flatnonzero((corner_jacobians(x, bricks) <= 0.0).any(axis=1))
