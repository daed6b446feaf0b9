"""Viscoelastic cylinders (Voigt, Eq. 5a) with the radius law of Eq. (4).

A cylinder of rest length l0 and rest cross-section A0 stretched to length l
has strain e = l/l0 - 1, radius r = r0 (1 - nu e) (Eq. 4), hence area
A = A0 (1 - nu e)^2, and carries the axial tension

    T = (E(e) e + eta de/dt) A,

where E(e) = E0 below the stiffening strain and E0 exp(rate (e - e_s)) above
it (Duck 1990, as the paper uses).  A link with a finite ``slack`` strain d
has its tension E0 A (e - e^2 / (2 d)) level off over the strains between
0 and d at E0 A d / 2 and stay there: with d > 0 it bears compression only
(the tongue floor resting on the hyoid: it pushes, it barely pulls), with
d < 0 tension only (a strap muscle: it pulls, it barely pushes); the tangent
stays continuous and >= 0.
All functions take and return arrays over every cylinder at once, in CGS
units.

Within one time step the dashpot acts along the cylinder's axis at the start
of the step, with that step's cross-section (``DampingFrame``).  The viscous
force is then linear in the new velocities, its tangent c n n^T is exact and
the Newton iteration stays robust when the tongue moves fast (the
rotation of the axis within one step, a few degrees at most, is neglected
for the dashpot only; it stays dissipative: power = c (n . dv)^2 >= 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

import scipy.sparse as sp

from ..jit import compiled, njit
from .term import Evaluation, ForceTerm


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
    n_nodes: int
    slack: np.ndarray | None = None  # (C,) strain over which tension levels off (inf or None: a full spring)

    @cached_property
    def slack_strain(self) -> np.ndarray:
        """(C,) the slack strain of every cylinder, inf where it bears tension fully."""
        return np.full(len(self.i), np.inf) if self.slack is None else np.asarray(self.slack, dtype=float)

    def __len__(self) -> int:
        return len(self.i)

    @cached_property
    def diff(self) -> sp.csr_matrix:
        """(C, N) difference operator: (diff @ x)[c] = x[j_c] - x[i_c]."""
        c, n = len(self.i), self.n_nodes
        return sp.csr_matrix((np.r_[-np.ones(c), np.ones(c)], (np.r_[np.arange(c), np.arange(c)],
                                                               np.r_[self.i, self.j])), shape=(c, n))


@dataclass
class CylinderState:
    """Everything the elastic forces and the tangent need, computed once per evaluation."""

    n: np.ndarray  # (C,3) unit axis i -> j
    length: np.ndarray
    strain: np.ndarray
    elastic: np.ndarray  # elastic tension, dyn
    shrink: np.ndarray  # r / r0 (Eq. 4)
    e: np.ndarray  # Young's modulus at this strain
    de: np.ndarray  # its derivative


@dataclass(frozen=True)
class DampingFrame:
    """Dashpot axes and coefficients, frozen over one time step."""

    n: np.ndarray  # (C,3)
    c: np.ndarray  # (C,) eta A / l0, dyn s/cm


def gives_way(slack: np.ndarray, strain: np.ndarray) -> np.ndarray:
    """(C,) the links strained on the side their finite slack strain lies (where the slack law holds)."""
    out = np.isfinite(slack)
    out[out] = strain[out] * slack[out] > 0.0
    return out


def youngs_modulus(cyl: CylinderSet, strain: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """E(e) and dE/de (the secant modulus: tension = E(e) e A)."""
    over = strain - cyl.knee
    e, de = cyl.youngs, np.zeros_like(strain)
    if (over > 0).any():
        growth = np.exp(np.minimum(cyl.rate * np.maximum(over, 0.0), 50.0))
        e = cyl.youngs * growth
        de = np.where(over > 0, cyl.rate * e, 0.0)
    slack = gives_way(cyl.slack_strain, strain)
    if slack.any():
        e, de = np.array(e, dtype=float, copy=True), np.array(de, dtype=float, copy=True)
        e0, s, dd = np.broadcast_to(cyl.youngs, strain.shape)[slack], strain[slack], cyl.slack_strain[slack]
        level = s / dd >= 1.0  # tension held at E0 d / 2
        e[slack] = np.where(level, e0 * dd / (2.0 * s), e0 * (1.0 - s / (2.0 * dd)))
        de[slack] = np.where(level, -e0 * dd / (2.0 * s**2), -e0 / (2.0 * dd))
    return e, de


def evaluate(cyl: CylinderSet, x: np.ndarray) -> CylinderState:
    if compiled():
        n, length, strain, shrink, e, de, elastic = cylinder_state(
            np.ascontiguousarray(x), cyl.i, cyl.j, cyl.l0, cyl.area0, cyl.youngs, cyl.poisson, cyl.knee, cyl.rate,
            cyl.slack_strain)
        return CylinderState(n=n, length=length, strain=strain, elastic=elastic, shrink=shrink, e=e, de=de)
    return evaluate_numpy(cyl, x)


def evaluate_numpy(cyl: CylinderSet, x: np.ndarray) -> CylinderState:
    d = cyl.diff @ x
    length = np.sqrt((d * d).sum(axis=1))
    n = d / length[:, None]
    strain = length / cyl.l0 - 1.0
    shrink = np.maximum(1.0 - cyl.poisson * strain, 0.05)
    e, de = youngs_modulus(cyl, strain)
    elastic = e * strain * cyl.area0 * (shrink * shrink)
    return CylinderState(n=n, length=length, strain=strain, elastic=elastic, shrink=shrink, e=e, de=de)


def axial_stiffness(cyl: CylinderSet, cs: CylinderState) -> np.ndarray:
    """dT_elastic / dl of every cylinder, dyn/cm (needed only for the tangent)."""
    dsig = (cs.e + cs.de * cs.strain) * cs.shrink * cs.shrink - 2.0 * cyl.poisson * cs.e * cs.strain * cs.shrink
    return cyl.area0 * dsig / cyl.l0


def damping_frame(cyl: CylinderSet, x: np.ndarray) -> DampingFrame:
    """The step's dashpot axes and coefficients.  A link on the side it gives way (its slack law) damps as
    it stiffens, in proportion to its tangent, 1 - e / d (0 past d): its relaxation time stays the same."""
    cs = evaluate(cyl, x)
    c = cyl.viscosity * cyl.area0 * cs.shrink * cs.shrink / cyl.l0
    slack = gives_way(cyl.slack_strain, cs.strain)
    if slack.any():
        c = c.copy()
        c[slack] *= np.clip(1.0 - cs.strain[slack] / cyl.slack_strain[slack], 0.0, 1.0)
    return DampingFrame(n=cs.n, c=c)


def nodal_forces(cyl: CylinderSet, cs: CylinderState, frame: DampingFrame | None, v: np.ndarray | None,
                 scatter) -> np.ndarray:
    """(N,3) nodal forces of all cylinders (elastic, plus the dashpots along ``frame`` at velocities ``v``)."""
    if compiled():
        damped = frame is not None and v is not None
        return cylinder_forces(cs.n, cs.elastic, cyl.i, cyl.j, frame.n if damped else cs.n,
                                       frame.c if damped else cs.length, np.ascontiguousarray(v) if damped else cs.n,
                                       cyl.n_nodes, damped)
    return scatter @ axial_forces(cyl, cs, frame, v)


def axial_forces(cyl: CylinderSet, cs: CylinderState, frame: DampingFrame | None, v: np.ndarray | None) -> np.ndarray:
    """(C,3) force vector each cylinder exerts on its first node (the second gets minus it)."""
    f = cs.elastic[:, None] * cs.n
    if frame is not None and v is not None:
        rate = (frame.n * (cyl.diff @ v)).sum(axis=1)
        f += (frame.c * rate)[:, None] * frame.n
    return f


@lru_cache(maxsize=4)
def _gauss_legendre(points: int) -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(points)


def strain_energy(cyl: CylinderSet, strain: np.ndarray, points: int = 8) -> np.ndarray:
    """Elastic energy stored in each cylinder, erg (Gauss-Legendre in strain)."""
    s, w = _gauss_legendre(points)
    e = 0.5 * (s[:, None] + 1.0) * strain[None, :]  # (P,C)
    shrink = np.maximum(1.0 - cyl.poisson * e, 0.05)
    over = np.maximum(e - cyl.knee, 0.0)
    stress = cyl.youngs * np.exp(np.minimum(cyl.rate * over, 50.0)) * e * shrink * shrink
    energy = cyl.area0 * cyl.l0 * 0.5 * strain * (w[:, None] * stress).sum(axis=0)
    d = cyl.slack_strain
    slack = gives_way(d, strain)
    if slack.any():  # the slack law in closed form (its links have no radius law: poisson 0)
        st, dd = strain[slack], d[slack]
        density = np.where(st / dd < 1.0, st**2 / 2.0 - st**3 / (6.0 * dd), dd**2 / 3.0 + dd * (st - dd) / 2.0)
        energy[slack] = (cyl.area0 * cyl.l0 * np.broadcast_to(cyl.youngs, strain.shape))[slack] * density
    return energy


# --- the term ----------------------------------------------------------------------------------------------

class CylinderTerm(ForceTerm):
    """Every Voigt element of the model (tongue cylinders, bone links, the floor, jaw springs): elastic
    tension and the step's dashpots; tangent (K_ax - T/l) n n^T + T/l I + c_v c n0 n0^T per element."""

    name = "cylinders"

    def prepare(self, model, state, control, h: float) -> DampingFrame:
        return damping_frame(model.springs, state.x)

    def forces(self, model, ev: Evaluation, f: np.ndarray) -> None:
        cs = evaluate(model.springs, ev.x)
        ev.parts[self.name] = cs
        f += nodal_forces(model.springs, cs, ev.step[self.name], ev.v, model.layout.scatter)

    def blocks(self, model, ev: Evaluation, out: np.ndarray, signed: bool = True) -> None:
        cyl, cs, frame, asm = model.springs, ev.parts[self.name], ev.step[self.name], model.layout.assembly
        axial = axial_stiffness(cyl, cs)
        if compiled():
            cylinder_blocks(out, cs.n, cs.length, cs.elastic, axial, frame.n, frame.c, ev.c_v, signed, cyl.i, cyl.j,
                            asm.cyl_pair, asm.n_pairs)
            return
        k_geo = (cs.elastic if signed else np.maximum(cs.elastic, 0.0)) / cs.length
        k_nn = np.maximum(axial, 0.0) - k_geo
        k3 = (k_nn[:, None, None] * (cs.n[:, :, None] * cs.n[:, None, :]) + k_geo[:, None, None] * np.eye(3)
              + (ev.c_v * frame.c)[:, None, None] * (frame.n[:, :, None] * frame.n[:, None, :]))
        asm.add_pairs(out, cyl.i, cyl.j, asm.cyl_pair, k3)



# --- compiled loops (numba): the same numbers as the numpy path above ---------------------------------

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
def cylinder_blocks(out, n, length, elastic, axial, frame_n, frame_c, c_v, signed, ci, cj, cyl_pair, n_pairs):
    """Adds each cylinder's tangent to the node-level blocks ``out`` (P + N, 3, 3; pairs i < j, then the
    diagonals): k = (K_ax - T/l) n n^T + T/l I + c_v c n0 n0^T on both diagonals, -k on their pair."""
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
    return out
