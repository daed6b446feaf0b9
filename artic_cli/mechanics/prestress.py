"""The drawn rest tongue as a shape under gravity: cylinder rest lengths that carry the tongue's weight.

A speaker's rest outline (MRI, or the default speaker's drawing) is the tongue as it hangs in the head, its
weight already carried by the tissue.  Taken as stress-free, gravity sags it again before any muscle acts.
``weight_carrying`` shortens (or lengthens) each carrying cylinder (the tongue's, and in the articulator
the floor's links to the hyoid) so that at the drawn positions their tensions balance every free node's
weight exactly; the supports (the nodes the mandible carries, the hyoid) pass the weight on.  Among all
such tension sets it takes the one of least elastic energy, sum t^2 / k: the tensions a linear truss
develops when the load is applied to it, t = K A^T (A K A^T)^-1 b, with A the nodes' equilibrium operator
and K the cylinders' axial stiffnesses.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ArticError
from .elements import CylinderSet, youngs_modulus


def equilibrium_operator(cyl: CylinderSet, x: np.ndarray) -> sp.csr_matrix:
    """(3N, C): the nodal forces of unit tensions (a tension pulls node i toward j and j toward i)."""
    d = x[cyl.j] - x[cyl.i]
    n = d / np.linalg.norm(d, axis=1)[:, None]
    c = np.arange(len(cyl.i))
    rows = np.concatenate([3 * cyl.i[:, None] + np.arange(3), 3 * cyl.j[:, None] + np.arange(3)]).ravel()
    cols = np.concatenate([np.repeat(c, 3), np.repeat(c, 3)])
    vals = np.concatenate([n, -n]).ravel()
    return sp.csr_matrix((vals, (rows, cols)), shape=(3 * cyl.n_nodes, len(c)))


def carrying_tensions(cyl: CylinderSet, x: np.ndarray, load: np.ndarray, free: np.ndarray) -> np.ndarray:
    """(C,) tensions in dyn whose nodal forces cancel ``load`` (N,3) at the ``free`` nodes, least energy."""
    a = equilibrium_operator(cyl, x)
    dofs = (3 * np.asarray(free)[:, None] + np.arange(3)).ravel()
    a = a[dofs]
    k = cyl.youngs * cyl.area0 / cyl.l0  # axial stiffness at rest, dyn/cm
    stiffness = (a @ sp.diags(k) @ a.T).tocsc()
    u = spla.spsolve(stiffness, -load[free].ravel())
    return k * (a.T @ u)


def rest_lengths_for(cyl: CylinderSet, x: np.ndarray, tension: np.ndarray, iters: int = 20) -> np.ndarray:
    """(C,) rest lengths at which each cylinder, at the positions ``x``, holds ``tension`` (dyn) exactly."""
    length = np.linalg.norm(x[cyl.j] - x[cyl.i], axis=1)
    strain = tension / (cyl.youngs * cyl.area0)
    for _ in range(iters):  # Newton on T(e) = E(e) e A (1 - nu e)^2 = tension, at fixed length
        shrink = 1.0 - cyl.poisson * strain
        e, de = youngs_modulus(cyl, strain)
        t = e * strain * cyl.area0 * shrink * shrink
        dt = cyl.area0 * ((e + de * strain) * shrink * shrink - 2.0 * cyl.poisson * e * strain * shrink)
        strain = strain - (t - tension) / dt
    if not np.all(np.abs(t - tension) <= 1e-9 * np.maximum(np.abs(tension), 1.0)):
        raise ArticError("the tongue cannot carry its weight at the drawn shape (a cylinder's prestrain does not "
                         "converge); raise materials.tongue.youngs_modulus_kpa or set rest_under_gravity: false")
    return length / (1.0 + strain)


def weight_carrying(cyl: CylinderSet, x: np.ndarray, node_mass: np.ndarray, gravity: np.ndarray,
                    free: np.ndarray, carriers: np.ndarray) -> CylinderSet:
    """``cyl`` with the rest lengths of its ``carriers`` (bool (C,)) set to carry the weight (masses
    ``node_mass`` in g, ``gravity`` (3,) in cm/s^2) of the ``free`` nodes at the positions ``x`` (cm); the
    other nodes are the supports, the other cylinders keep their rest lengths."""
    sub = replace(cyl, **{f: getattr(cyl, f)[carriers] for f in
                          ("i", "j", "l0", "area0", "youngs", "viscosity", "poisson", "knee", "rate")},
                  slack=None)
    tension = carrying_tensions(sub, x, node_mass[:, None] * gravity[None, :], free)
    l0 = cyl.l0.copy()
    l0[carriers] = rest_lengths_for(sub, x, tension)
    return replace(cyl, l0=l0)
