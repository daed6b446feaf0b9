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
SHAPE_GRADIENTS_GAUSS = _DN_GAUSS  # (gauss point, corner, reference axis)
SHAPE_GRADIENTS_CORNER = _DN_CORNER  # (at corner, corner, reference axis)
# dN as matrices for BLAS: (8 corners, 3 * G) with column l * G + g
_D_GAUSS = _DN_GAUSS.transpose(1, 2, 0).reshape(8, -1)
_D_CORNER = _DN_CORNER.transpose(1, 2, 0).reshape(8, -1)


def _jacobians(x: np.ndarray, bricks: np.ndarray, d: np.ndarray) -> np.ndarray:
    """J[l, i, b, g] = sum_a x[brick b corner a, i] dN_a/dxi_l (point g), contiguous in (b, g)."""
    b = len(bricks)
    xs = x.T[:, bricks].reshape(3 * b, 8)  # rows (i, b)
    j = (xs @ d).reshape(3, b, 3, -1)  # (i, b, l, g)
    return np.ascontiguousarray(j.transpose(2, 0, 1, 3))


def _cross(a, b) -> list:
    """Cross product of two 3-lists of equally shaped arrays."""
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dets(j: np.ndarray) -> np.ndarray:
    c = _cross(j[1], j[2])
    return j[0][0] * c[0] + j[0][1] * c[1] + j[0][2] * c[2]  # (B, G)


def volumes(x: np.ndarray, bricks: np.ndarray) -> np.ndarray:
    """Exact volume of every brick (B,)."""
    return _dets(_jacobians(x, bricks, _D_GAUSS)).sum(axis=1)


def volume_gradients(x: np.ndarray, bricks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Volumes (B,) and dV/dx of each corner (B, 8, 3).

    det J = c1 . (c2 x c3) with c_l the Jacobian's columns, so
    d det / d c1 = c2 x c3 (and cyclically): the cofactor columns."""
    j = _jacobians(x, bricks, _D_GAUSS)
    cof = np.array([_cross(j[1], j[2]), _cross(j[2], j[0]), _cross(j[0], j[1])])  # (l, i, B, G)
    vol = (j[0] * cof[0]).sum(axis=(0, 2))
    b = len(bricks)
    g = cof.shape[-1]
    grad = (cof.transpose(1, 2, 0, 3).reshape(3 * b, 3 * g) @ _D_GAUSS.T).reshape(3, b, 8)
    return vol, grad.transpose(1, 2, 0)


def corner_jacobians(x: np.ndarray, bricks: np.ndarray) -> np.ndarray:
    """det J at the eight corners (B, 8); a brick is inverted where any is <= 0."""
    return _dets(_jacobians(x, bricks, _D_CORNER))


def corner_jacobians_at(x: np.ndarray, bricks: np.ndarray, which_brick: np.ndarray, which_corner: np.ndarray,
                        ) -> tuple[np.ndarray, np.ndarray]:
    """det J at chosen (brick, corner) pairs (K,) and its gradient with respect to the brick's nodes (K,8,3)."""
    j = _jacobians(x, bricks[which_brick], _D_CORNER)  # (l, i, K, corner)
    k = np.arange(len(which_brick))
    jj = j[:, :, k, which_corner]  # (l, i, K)
    cof = np.array([_cross(jj[1], jj[2]), _cross(jj[2], jj[0]), _cross(jj[0], jj[1])])  # (l, i, K)
    det = (jj[0] * cof[0]).sum(axis=0)
    grad = np.einsum("lik,kal->kai", cof, _DN_CORNER[which_corner])
    return det, grad


def inverted_bricks(x: np.ndarray, bricks: np.ndarray) -> np.ndarray:
    """Indices of bricks turned inside out (a non-positive corner Jacobian)."""
    return np.flatnonzero((corner_jacobians(x, bricks) <= 0.0).any(axis=1))
