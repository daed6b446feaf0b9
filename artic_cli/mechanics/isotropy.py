"""Making each brick's cylinder truss mechanically isotropic.

With the paper's weighting rule a brick's cylinders fill its volume, but
their stiffness is anisotropic as soon as the brick is not a cube: in a
brick twice as long as wide, more cylinder volume lies along the long axis
and the truss is stiffer that way (a 6 x 3 x 2 cm block of 3 x 3 x 2 bricks
elongates 62 % less than F L / (E A) under a pull).  The small-strain
stiffness of a truss is the fourth-order tensor

    C = (1 / V) sum_c E s_c n_c (x) n_c (x) n_c (x) n_c,

with s_c the cylinder's stiffness volume.  For every brick we choose the
stiffness volumes of its 28 cylinders, non-negative and as close as possible
to the paper's volumes, so that this tensor is the isotropic one of a random
fibre network, (E / 15)(d_ij d_kl + d_ik d_jl + d_il d_jk), while no
cylinder drops below a quarter of its paper stiffness (so no brick becomes a
mechanism where full isotropy is out of reach).  The paper's
volumes still carry the mass and the volume bookkeeping; only stiffness and
viscosity use the corrected volumes.  Bounded least squares on the
augmented system [w G; I] s = [w t; s_paper].
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.optimize import lsq_linear

from ..geometry.hexahedra import volumes
from ..geometry.mesh import brick_cylinders

# the 15 distinct components of a fully symmetric 4th-order tensor in 3D
_EXPONENTS = np.array([e for e in itertools.product(range(5), repeat=3) if sum(e) == 4])
_ISO = np.array([1 / 5 if max(e) == 4 else (1 / 15 if sorted(e) == [0, 2, 2] else 0.0) for e in _EXPONENTS])
_FIT_WEIGHT = 30.0
_FLOOR = 0.25  # every cylinder keeps at least this share of its paper stiffness


def moment_matrix(n: np.ndarray) -> np.ndarray:
    """(15, C) monomials n_x^a n_y^b n_z^c of unit directions (C,3)."""
    return np.prod(n.T[None, :, :] ** _EXPONENTS[:, :, None], axis=1)


def isotropic_areas(nodes: np.ndarray, bricks: np.ndarray) -> tuple[np.ndarray, float]:
    """Stiffness cross-sections (C,) in the order of ``brick_cylinders`` and the
    worst relative misfit of a brick's tensor to isotropy."""
    cyl, share, owner = brick_cylinders(bricks)
    d = nodes[cyl[:, 1]] - nodes[cyl[:, 0]]
    length = np.linalg.norm(d, axis=1)
    n = d / length[:, None]
    vol = volumes(nodes, bricks)
    w = 1.0 / share
    eq_len = (length[owner] * w[owner]).sum(axis=1)
    area_m = vol / eq_len
    stiff_vol = np.zeros(len(cyl))
    worst = 0.0
    eye = np.eye(owner.shape[1])
    for m in range(len(bricks)):
        c = owner[m]
        paper = area_m[m] * w[c] * length[c] / vol[m]  # paper's volumes, as fractions of V_m
        g = moment_matrix(n[c])
        a = np.vstack([_FIT_WEIGHT * g, eye])
        b = np.concatenate([_FIT_WEIGHT * _ISO, paper])
        s = lsq_linear(a, b, bounds=(_FLOOR * paper, np.inf), method="bvls").x
        worst = max(worst, float(np.linalg.norm(g @ s - _ISO) / np.linalg.norm(_ISO)))
        stiff_vol[c] += s * vol[m]
    return stiff_vol / length, worst
