"""Muscles: Hill-type fibres with the paper's force model (Eq. 8-9).

A muscle is a set of parallel fibres; a fibre is a chain of nodes from its
origin to its insertion and carries one tension along every segment (a
via-point muscle: a curved fibre also pushes on the nodes it bends around).
The tension of fibre f with strain e = L/L0 - 1 is

    T_f = s_f u fL(e / w) / fL(0)                  active (Eq. 9), u in dyn
        + A_f (k1(e) e + sigma2_f)                 passive parallel spring and Maxwell branch

with fL the fourth-order force-length polynomial of Eq. (9), zero outside
-0.185 < e / w < 0.49, and w the config's ``muscles.force_length_width`` (1: the
paper's curve); k1 = 0.05 k0 e for e > 0 (stretch only); the Maxwell
branch sigma2' / k2 + sigma2 / b2 = e' with k2 = 2 k0, b2 = b / 10, advanced
with the implicit step.  ``u`` is the muscle force in newtons at rest length
(the paper's activation input); s_f the fibre's share of it; A_f the fibre's
"thickness" (cm^2), which scales the passive parts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..jit import compiled, njit
from .term import Evaluation, ForceTerm

FL_COEFFS = (22.5, 3.498, -14.718, 1.98, 0.858)  # Eq. (9), highest power first
FL_RANGE = (-0.185, 0.49)
FL_SLOPE_COEFFS = tuple(float(c) for c in np.polyder(FL_COEFFS))
_FL = np.array(FL_COEFFS)


def _polyval(coeffs, e: np.ndarray) -> np.ndarray:
    out = np.full_like(e, coeffs[0])
    for c in coeffs[1:]:
        out = out * e + c
    return out


def force_length(strain: np.ndarray, width: float = 1.0) -> np.ndarray:
    """Eq. (9) normalised to 1 at rest length; zero outside its validity range.

    ``width`` stretches the curve along the strain axis: fL(e / width) (1 is Eq. 9 as printed).
    """
    strain = strain / width
    f = _polyval(FL_COEFFS, strain) / FL_COEFFS[-1]
    return np.where((strain > FL_RANGE[0]) & (strain < FL_RANGE[1]), np.maximum(f, 0.0), 0.0)


def force_length_slope(strain: np.ndarray, width: float = 1.0) -> np.ndarray:
    """d fL / d strain of :func:`force_length` (zero where fL is zero)."""
    slope = _polyval(FL_SLOPE_COEFFS, strain / width) / (FL_COEFFS[-1] * width)
    return np.where(force_length(strain, width) > 0, slope, 0.0)


@dataclass(frozen=True)
class MuscleSet:
    names: tuple[str, ...]
    seg_i: np.ndarray  # (S,) first node of each segment
    seg_j: np.ndarray  # (S,)
    seg_fibre: np.ndarray  # (S,)
    fibre_muscle: np.ndarray  # (F,)
    fibre_share: np.ndarray  # (F,) share of the muscle's force
    fibre_area: np.ndarray  # (F,) thickness, cm^2
    fibre_l0: np.ndarray  # (F,) rest length, cm
    seg_l0: np.ndarray  # (S,) rest length of each segment, cm
    k1: float  # passive stiffness coefficient, dyn/cm^2 (k1 = k1 * e)
    k2: float  # Maxwell spring, dyn/cm^2
    b2: float  # Maxwell dashpot, dyn s/cm^2
    fl_width: float  # force-length width: Eq. (9) evaluated at strain / fl_width (1: as printed)
    diff: sp.csr_matrix  # (S, N) segment vectors
    seg_sum: sp.csr_matrix  # (F, S) sums segment lengths per fibre
    scatter: sp.csr_matrix  # (N, S) node force from segment force vectors

    @property
    def n_fibres(self) -> int:
        return len(self.fibre_l0)

    def index(self, name: str) -> int:
        return self.names.index(name)


def muscle_set(names, fibres: dict[str, list[np.ndarray]], shares: dict[str, np.ndarray],
               thickness: dict[str, float], nodes: np.ndarray, k1: float, k2: float, b2: float,
               fl_width: float = 1.0) -> MuscleSet:
    seg_i, seg_j, seg_f, f_m, f_share, f_area, f_l0 = [], [], [], [], [], [], []
    for m, name in enumerate(names):
        for fibre, share in zip(fibres[name], shares[name]):
            f = len(f_m)
            seg_i.extend(fibre[:-1])
            seg_j.extend(fibre[1:])
            seg_f.extend([f] * (len(fibre) - 1))
            f_m.append(m)
            f_share.append(share)
            f_area.append(thickness[name] * share)
            f_l0.append(np.linalg.norm(np.diff(nodes[fibre], axis=0), axis=1).sum())
    seg_i, seg_j, seg_f = (np.array(a, dtype=np.int64) for a in (seg_i, seg_j, seg_f))
    s, n = len(seg_i), len(nodes)
    diff = sp.csr_matrix((np.r_[-np.ones(s), np.ones(s)], (np.r_[np.arange(s), np.arange(s)], np.r_[seg_i, seg_j])),
                         shape=(s, n))
    seg_sum = sp.csr_matrix((np.ones(s), (seg_f, np.arange(s))), shape=(len(f_m), s))
    scatter = sp.csr_matrix((np.r_[np.ones(s), -np.ones(s)], (np.r_[seg_i, seg_j], np.r_[np.arange(s), np.arange(s)])),
                            shape=(n, s))
    return MuscleSet(names=tuple(names), seg_i=seg_i, seg_j=seg_j, seg_fibre=seg_f, fibre_muscle=np.array(f_m),
                     fibre_share=np.array(f_share), fibre_area=np.array(f_area), fibre_l0=np.array(f_l0),
                     seg_l0=np.linalg.norm(nodes[seg_j] - nodes[seg_i], axis=1),
                     k1=k1, k2=k2, b2=b2, fl_width=fl_width, diff=diff, seg_sum=seg_sum, scatter=scatter)


@dataclass
class FibreState:
    n: np.ndarray  # (S,3) segment unit vectors
    seg_length: np.ndarray  # (S,)
    strain: np.ndarray  # (F,)
    tension: np.ndarray  # (F,) dyn
    sigma2: np.ndarray  # (F,) Maxwell stress at this state, dyn/cm^2


def fibre_state(ms: MuscleSet, x: np.ndarray, activation: np.ndarray, sigma2_prev: np.ndarray,
                strain_prev: np.ndarray, h: float) -> FibreState:
    """Tensions for positions ``x``, muscle forces ``activation`` (M,) in dyn, after a step ``h``."""
    if compiled():
        n, length, total = fibre_geometry(np.ascontiguousarray(x), ms.seg_i, ms.seg_j, ms.seg_fibre,
                                                  ms.n_fibres)
        strain, sigma2, tension = fibre_tensions(
            total, ms.fibre_l0, sigma2_prev, strain_prev, float(h), ms.k1, ms.k2, ms.b2,
            np.asarray(activation, dtype=float), ms.fibre_muscle, ms.fibre_share, ms.fibre_area, ms.fl_width,
            _FL, *FL_RANGE)
        return FibreState(n=n, seg_length=length, strain=strain, tension=tension, sigma2=sigma2)
    d = ms.diff @ x
    length = np.sqrt((d * d).sum(axis=1))
    n = d / length[:, None]
    total = ms.seg_sum @ length
    strain = total / ms.fibre_l0 - 1.0
    sigma2 = (sigma2_prev + ms.k2 * (strain - strain_prev)) / (1.0 + h * ms.k2 / ms.b2) if h > 0 else sigma2_prev
    passive = ms.k1 * np.maximum(strain, 0.0) * strain + sigma2
    active = activation[ms.fibre_muscle] * ms.fibre_share * force_length(strain, ms.fl_width)
    return FibreState(n=n, seg_length=length, strain=strain, tension=active + ms.fibre_area * passive, sigma2=sigma2)


def fibre_stiffness(ms: MuscleSet, fs: FibreState, activation: np.ndarray, h: float) -> np.ndarray:
    """(F,) dT/dL (dyn/cm) of each fibre along its own length, clipped at zero for the Newton tangent.

    dT/de = u s fL'(e) + A (2 k1 e+ + k2 / (1 + h k2 / b2)), and dL = L0 de.
    """
    e = fs.strain
    maxwell = ms.k2 / (1.0 + h * ms.k2 / ms.b2) if h > 0 else 0.0
    slope = (activation[ms.fibre_muscle] * ms.fibre_share * force_length_slope(e, ms.fl_width)
             + ms.fibre_area * (2.0 * ms.k1 * np.maximum(e, 0.0) + maxwell))
    return np.maximum(slope, 0.0) / ms.fibre_l0


def length_gradients(ms: MuscleSet, fs: FibreState, fibres: np.ndarray, n_nodes: int) -> np.ndarray:
    """(3N, len(fibres)) gradient of each chosen fibre's length with respect to the node positions."""
    col = np.full(ms.n_fibres, -1)
    col[fibres] = np.arange(len(fibres))
    if compiled():
        return fibre_gradients(fs.n, ms.seg_i, ms.seg_j, col[ms.seg_fibre], n_nodes,
                                       len(fibres)).reshape(3 * n_nodes, -1)
    g = np.zeros((n_nodes, 3, len(fibres)))
    seg = np.flatnonzero(col[ms.seg_fibre] >= 0)
    c = col[ms.seg_fibre[seg]]
    np.add.at(g, (ms.seg_j[seg], slice(None), c), fs.n[seg])
    np.add.at(g, (ms.seg_i[seg], slice(None), c), -fs.n[seg])
    return g.reshape(3 * n_nodes, -1)


def fibre_twins(ms: MuscleSet, image: np.ndarray) -> np.ndarray | None:
    """(F,) each fibre's mirror twin (the fibre of the same muscle along the mirror images of its nodes, in
    either direction; itself on the midline or across it), or None if some fibre has no twin."""
    chains = {}
    for f in range(ms.n_fibres):
        seg = np.flatnonzero(ms.seg_fibre == f)
        chains[f] = (int(ms.fibre_muscle[f]), tuple(ms.seg_i[seg]) + (int(ms.seg_j[seg[-1]]),))
    where = {c: f for f, c in chains.items()}
    twin = np.empty(ms.n_fibres, dtype=np.int64)
    for f, (m, chain) in chains.items():
        mirrored = tuple(int(i) for i in image[list(chain)])
        t = where.get((m, mirrored), where.get((m, mirrored[::-1])))
        if t is None:
            return None
        twin[f] = t
    return twin


def muscle_forces(ms: MuscleSet, fs: FibreState) -> np.ndarray:
    """(N,3) nodal forces of all fibres."""
    if compiled():
        return fibre_forces(fs.n, fs.tension, ms.seg_i, ms.seg_j, ms.seg_fibre, ms.scatter.shape[0])
    return ms.scatter @ (fs.tension[ms.seg_fibre][:, None] * fs.n)


def fibre_lengths(ms: MuscleSet, x: np.ndarray) -> np.ndarray:
    """(F,) length of every fibre, cm."""
    if compiled():
        return fibre_geometry(np.ascontiguousarray(x), ms.seg_i, ms.seg_j, ms.seg_fibre, ms.n_fibres)[2]
    d = ms.diff @ x
    return ms.seg_sum @ np.sqrt((d * d).sum(axis=1))


def muscle_lengths(ms: MuscleSet, x: np.ndarray) -> np.ndarray:
    """(M,) mean fibre length of each muscle, cm."""
    fl = fibre_lengths(ms, x)
    return np.bincount(ms.fibre_muscle, weights=fl * ms.fibre_share, minlength=len(ms.names))


def muscle_tensions(ms: MuscleSet, x: np.ndarray, activation: np.ndarray, sigma2: np.ndarray) -> np.ndarray:
    """(M,) total force of each muscle (sum over its fibres), dyn, with the Maxwell state given."""
    strain = fibre_lengths(ms, x) / ms.fibre_l0 - 1.0
    passive = ms.k1 * np.maximum(strain, 0.0) * strain + sigma2
    t = activation[ms.fibre_muscle] * ms.fibre_share * force_length(strain, ms.fl_width) + ms.fibre_area * passive
    return np.bincount(ms.fibre_muscle, weights=t, minlength=len(ms.names))


# --- the term ----------------------------------------------------------------------------------------------

# Fibres stiffer than this along their length (dyn/cm; active muscles on the steep side of Eq. 9) enter the
# tangent exactly, as rank-one terms k g g^T solved by Woodbury; softer ones are split over their segments.
RANK_ONE_STIFFNESS = 2.0e4


def total_muscle_force(model, muscle_force: np.ndarray | None) -> np.ndarray | None:
    """The control's muscle forces plus the model's postural tone (dyn), or None without muscles."""
    if model.muscles is None:
        return None
    act = np.zeros(len(model.muscles.names)) if muscle_force is None else muscle_force
    return act + model.tone if model.tone is not None else act


def model_fibre_stiffness(model, fs: FibreState, act: np.ndarray, h: float) -> np.ndarray:
    """(F,) the fibres' stiffness along their length (:func:`fibre_stiffness`); a mirrored model's twins get
    their mean, so that both fall on the same side of the rank-one threshold."""
    kf = fibre_stiffness(model.muscles, fs, act, h)
    return kf if model.fibre_twin is None else 0.5 * (kf + kf[model.fibre_twin])


class MuscleTerm(ForceTerm):
    """The muscles' fibres: tension along their segments; in the tangent each segment's own block (its
    tension sideways, a soft fibre's stiffness split in series) and stiff fibres whole as rank-one terms; the
    Maxwell stress advanced after the step."""

    name = "muscles"

    def present(self, model) -> bool:
        return model.muscles is not None

    def prepare(self, model, state, control, h: float) -> np.ndarray:
        return total_muscle_force(model, control.muscle_force)

    def forces(self, model, ev: Evaluation, f: np.ndarray) -> None:
        fs = fibre_state(model.muscles, ev.x, ev.step[self.name], ev.state.sigma2, ev.state.fibre_strain, ev.h)
        ev.parts[self.name] = {"fs": fs}
        f += muscle_forces(model.muscles, fs)

    def stiffness(self, model, ev: Evaluation) -> np.ndarray:
        part = ev.parts[self.name]
        if "kf" not in part:
            part["kf"] = model_fibre_stiffness(model, part["fs"], ev.step[self.name], ev.h)
        return part["kf"]

    def blocks(self, model, ev: Evaluation, out: np.ndarray, signed: bool = True) -> None:
        ms, fs, asm = model.muscles, ev.parts[self.name]["fs"], model.layout.assembly
        kf = self.stiffness(model, ev)
        t = np.maximum(fs.tension[ms.seg_fibre], 0.0) / fs.seg_length
        nn = fs.n[:, :, None] * fs.n[:, None, :]
        soft = np.where(kf < RANK_ONE_STIFFNESS, kf * ms.fibre_l0, 0.0)  # split in series
        k_seg = t[:, None, None] * (np.eye(3) - nn) + (soft[ms.seg_fibre] / ms.seg_l0)[:, None, None] * nn
        if compiled():
            segment_blocks(out, ms.seg_i, ms.seg_j, asm.seg_pair, k_seg, asm.n_pairs)
        else:
            asm.add_pairs(out, ms.seg_i, ms.seg_j, asm.seg_pair, k_seg)

    def rank_one(self, model, ev: Evaluation):
        """Stiff fibres along their whole length; in a mirrored model a fibre and its twin have one folded
        gradient: they enter as one term of twice the stiffness (fewer Woodbury columns)."""
        kf = self.stiffness(model, ev)
        stiff = np.flatnonzero(kf >= RANK_ONE_STIFFNESS)
        k = kf[stiff]
        if model.fibre_twin is not None:  # twins' gradients fold onto the same column: one, twice as stiff
            twin = model.fibre_twin[stiff]
            keep = twin >= stiff
            stiff, k = stiff[keep], np.where(twin[keep] == stiff[keep], 1.0, 2.0) * k[keep]
        if not len(stiff):
            return None
        return length_gradients(model.muscles, ev.parts[self.name]["fs"], stiff, model.n_nodes), k

    def advance(self, model, ev: Evaluation, x: np.ndarray) -> dict:
        fs = fibre_state(model.muscles, x, ev.step[self.name], ev.state.sigma2, ev.state.fibre_strain, ev.h)
        return {"sigma2": fs.sigma2, "fibre_strain": fs.strain}


# --- compiled loops (numba): the same numbers as the numpy path above ---------------------------------

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


@njit(cache=True, fastmath=False)
def segment_blocks(out, seg_i, seg_j, seg_pair, seg_k, n_pairs):
    """Adds each fibre segment's own 3x3 block ``seg_k`` to the node-level blocks ``out`` (P + N, 3, 3), as
    a cylinder's: on both diagonals, minus on its pair."""
    for k in range(len(seg_pair)):
        a, b, m = n_pairs + seg_i[k], n_pairs + seg_j[k], seg_pair[k]
        for p in range(3):
            for q in range(3):
                v = seg_k[k, p, q]
                out[a, p, q] += v
                out[b, p, q] += v
                out[m, p, q] -= v
    return out
