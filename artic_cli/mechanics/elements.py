"""Viscoelastic cylinders (Voigt, Eq. 5a) with the radius law of Eq. (4).

A cylinder of rest length l0 and rest cross-section A0 stretched to length l
has strain e = l/l0 - 1, radius r = r0 (1 - nu e) (Eq. 4), hence area
A = A0 (1 - nu e)^2, and carries the axial tension

    T = (E(e) e + eta de/dt) A,

where E(e) = E0 below the stiffening strain and E0 exp(rate (e - e_s)) above
it (Duck 1990, as the paper uses).  All functions take and return arrays over
every cylinder at once, in CGS units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CylinderSet:
    """Static description of C cylinders (CGS)."""

    i: np.ndarray  # (C,) first node
    j: np.ndarray  # (C,) second node
    l0: np.ndarray  # rest length, cm
    area0: np.ndarray  # rest cross-section, cm^2
    youngs: np.ndarray  # E0, dyn/cm^2
    viscosity: np.ndarray  # eta, dyn s/cm^2
    poisson: np.ndarray  # nu of the radius law
    knee: np.ndarray  # stiffening strain
    rate: np.ndarray  # stiffening rate

    def __len__(self) -> int:
        return len(self.i)


@dataclass
class CylinderState:
    """Everything the forces and the tangent need, computed once per evaluation."""

    n: np.ndarray  # (C,3) unit axis i -> j
    length: np.ndarray
    strain: np.ndarray
    tension: np.ndarray  # total (elastic + viscous), dyn
    elastic: np.ndarray  # elastic part, dyn
    k_axial: np.ndarray  # dT_elastic/dl, dyn/cm
    c_axial: np.ndarray  # dT/d(dl/dt), dyn s/cm


def youngs_modulus(cyl: CylinderSet, strain: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """E(e) and dE/de."""
    over = np.maximum(strain - cyl.knee, 0.0)
    growth = np.exp(np.minimum(cyl.rate * over, 50.0))
    e = cyl.youngs * growth
    de = np.where(strain > cyl.knee, cyl.rate * e, 0.0)
    return e, de


def evaluate(cyl: CylinderSet, x: np.ndarray, v: np.ndarray | None) -> CylinderState:
    d = x[cyl.j] - x[cyl.i]
    length = np.sqrt(np.einsum("ij,ij->i", d, d))
    n = d / length[:, None]
    strain = length / cyl.l0 - 1.0
    shrink = np.maximum(1.0 - cyl.poisson * strain, 0.05)
    area = cyl.area0 * shrink * shrink
    e, de = youngs_modulus(cyl, strain)
    elastic = e * strain * area
    c_axial = cyl.viscosity * area / cyl.l0
    if v is not None:
        rate = np.einsum("ij,ij->i", n, v[cyl.j] - v[cyl.i])
        tension = elastic + c_axial * rate
    else:
        tension = elastic
    dsig = (e + de * strain) * shrink * shrink - 2.0 * cyl.poisson * e * strain * shrink
    k_axial = cyl.area0 * dsig / cyl.l0
    return CylinderState(n=n, length=length, strain=strain, tension=tension, elastic=elastic,
                         k_axial=k_axial, c_axial=c_axial)


def strain_energy(cyl: CylinderSet, strain: np.ndarray, points: int = 8) -> np.ndarray:
    """Elastic energy stored in each cylinder, erg (Gauss-Legendre in strain)."""
    s, w = np.polynomial.legendre.leggauss(points)
    e = 0.5 * (s[:, None] + 1.0) * strain[None, :]  # (P,C)
    shrink = np.maximum(1.0 - cyl.poisson * e, 0.05)
    over = np.maximum(e - cyl.knee, 0.0)
    stress = cyl.youngs * np.exp(np.minimum(cyl.rate * over, 50.0)) * e * shrink * shrink
    return cyl.area0 * cyl.l0 * 0.5 * strain * (w[:, None] * stress).sum(axis=0)
