"""Calibrating the cylinder lattice to the continuum it stands for.

A truss of cylinders that exactly fills a volume is softer than the solid:
only the cylinders along a load carry it fully, the others carry a
cos^4-weighted share, and a pure truss has a Poisson ratio near 1/4.  We
therefore homogenise once: a block of 4 x 4 x 4 unit cubes (symmetry rollers
on three faces, uniform traction on the fourth) is solved in linear
elasticity for cylinder modulus 1 and brick bulk penalty ``r``, giving the
lattice's apparent Young modulus E(r) and Poisson ratio nu(r).  ``r`` is set
so that nu(r) is the material's Poisson ratio, and the cylinder modulus
(and viscosity) is scaled by 1/E(r) so that the lattice's Young modulus is
the material's.  The cuboid validation then checks the result on another
geometry, at finite strain.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.sparse.linalg as spla
from scipy.optimize import brentq

from ..geometry.hexahedra import volume_gradients
from ..geometry.mesh import cuboid_mesh, face_weights
from .assembly import pair_blocks, sparse_blocks
from .isotropy import isotropic_areas

_CELLS = 4


def lattice_response(bulk_ratio: float, isotropic: bool = True, cells: int = _CELLS) -> tuple[float, float]:
    """Apparent (E, nu) of a cube lattice with unit cylinder modulus."""
    mesh = cuboid_mesh([float(cells)] * 3, [cells] * 3)
    areas = isotropic_areas(mesh.nodes, mesh.bricks)[0] if isotropic else mesh.areas
    x = mesh.nodes
    ci, cj = mesh.cylinders[:, 0], mesh.cylinders[:, 1]
    d = x[cj] - x[ci]
    l0 = np.linalg.norm(d, axis=1)
    n = d / l0[:, None]
    k = (areas / l0)[:, None, None] * np.einsum("ci,cj->cij", n, n)
    kmat = sparse_blocks(mesh.cylinders, pair_blocks(k), len(x))
    if bulk_ratio > 0:
        vol, grad = volume_gradients(x, mesh.bricks)
        g = grad.reshape(len(vol), 24)
        kmat = kmat + sparse_blocks(mesh.bricks, bulk_ratio / vol[:, None, None] * g[:, :, None] * g[:, None, :], len(x))
    fixed = np.zeros((len(x), 3), dtype=bool)
    for axis in range(3):
        fixed[np.isclose(x[:, axis], 0.0), axis] = True
    free = np.flatnonzero(~fixed.ravel())
    f = np.zeros((len(x), 3))
    far = np.isclose(x[:, 0], cells)
    face = np.flatnonzero(far)
    f[face, 0] = cells * cells * face_weights(x, face)  # a uniform unit traction on the far face
    u = np.zeros(3 * len(x))
    u[free] = spla.spsolve(kmat[free][:, free].tocsc(), f.ravel()[free])
    u = u.reshape(-1, 3)
    ex = u[far, 0].mean() / cells
    ey = u[np.isclose(x[:, 1], cells), 1].mean() / cells
    ez = u[np.isclose(x[:, 2], cells), 2].mean() / cells
    return 1.0 / ex, -0.5 * (ey + ez) / ex


@lru_cache(maxsize=16)
def calibrate(poisson: float, isotropic: bool = True, gain: float = 1.0) -> tuple[float, float]:
    """(modulus_scale, bulk_ratio): cylinder E = scale * E0, brick bulk = ratio * scale * E0.

    ``gain`` multiplies the bulk penalty found for ``poisson`` (the paper's
    alpha, Eq. 7: how tightly volume is held); the modulus scale is then
    recomputed so that the lattice's Young modulus stays E0."""
    nu0 = lattice_response(0.0, isotropic)[1]
    if poisson <= nu0:
        ratio = 0.0
    else:
        ratio = float(np.exp(brentq(lambda s: lattice_response(np.exp(s), isotropic)[1] - poisson,
                                    -8.0, 12.0, xtol=1e-10)))
    ratio *= gain
    e_eff = lattice_response(ratio, isotropic)[0]
    return 1.0 / e_eff, ratio


def effective_poisson(poisson: float, isotropic: bool = True, gain: float = 1.0) -> float:
    """Small-strain Poisson ratio of the calibrated lattice with the constraint's gain."""
    return lattice_response(calibrate(poisson, isotropic, gain)[1], isotropic)[1]
