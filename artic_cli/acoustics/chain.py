"""The frequency-domain tube model: chain (ABCD) matrices of lossy cylindrical sections, after Sondhi &
Schroeter (1987), vectorised over frequencies.

A section of length l and area A at angular frequency w has, per unit length, a series impedance
Z = R + jw rho/A (R: viscous boundary layer, (S/A^2) sqrt(w rho mu / 2), S = 2 sqrt(pi A) the perimeter)
and a shunt admittance Y = G + jw A/(rho c^2) + S / (Rw + jw Mw + Kw/(jw)) (G: heat conduction,
S (eta - 1)/(rho c^2) sqrt(lambda w / (2 cp rho)); the last term: yielding walls, per unit area mass Mw,
resistance Rw and stiffness Kw).  Its chain matrix is [[cosh gl, Z0 sinh gl], [sinh gl / Z0, cosh gl]] with
g = sqrt(Z Y), Z0 = sqrt(Z / Y); [P, U] at the glottis side = K [P, U] at the lips side.  A side branch
(the nasal tract behind the velopharyngeal port, the piriform fossae) is a shunt admittance 1 / Z_in at its
junction.  The lips radiate into a parallel R-L load (a piston in an infinite baffle, Flanagan 1972):
R = 128 rho c / (9 pi^2 A), L = 8 rho / (3 pi sqrt(pi A)).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

# The frequency loop runs on numba's OpenMP threads.  OpenMP's threads spin while they wait by default: beside
# another busy process (make -j2, pytest -n 2) a loop's threads then wait for each other's time slices, and the
# acoustic map took 85 s instead of 40 s beside one busy core (27 s alone either way).  Read when OpenMP
# loads, at the first parallel loop.
os.environ.setdefault("OMP_WAIT_POLICY", "passive")

from ..jit import AVAILABLE, njit

if AVAILABLE:  # pragma: no cover - numba is a dependency
    from numba import prange
else:  # pragma: no cover
    prange = range

MIN_AREA_CM2 = 1e-4  # a closure: 0.01 mm^2 keeps the matrices finite (the flow through it is negligible)


@dataclass(frozen=True)
class Air:
    """Air, walls and which losses act (CGS); see configs/default.yaml, section acoustics."""

    c: float = 35000.0  # speed of sound, cm/s
    rho: float = 1.14e-3  # density, g/cm^3
    mu: float = 1.86e-4  # viscosity, dyn s/cm^2
    kappa: float = 5.5e-5  # heat conduction, cal/(cm s degC)
    cp: float = 0.24  # specific heat, cal/(g degC)
    eta: float = 1.4  # adiabatic constant
    wall_mass: float = 1.5  # g/cm^2
    wall_resistance: float = 1600.0  # dyn s/cm^3
    wall_stiffness: float = 3.0e5  # dyn/cm^3
    viscous: bool = True
    heat: bool = True
    walls: bool = True
    radiation: bool = True  # False: an ideal open end (pressure 0 at the lips)


LOSSLESS = Air(viscous=False, heat=False, walls=False, radiation=False)


def _line_parameters(length_cm: np.ndarray, area_cm2: np.ndarray, w: np.ndarray, air: Air):
    """(n, F) cosh(g l), Z0 sinh(g l), sinh(g l) / Z0 of n sections at angular frequencies ``w`` (F,)."""
    a = np.maximum(np.asarray(area_cm2, dtype=float), MIN_AREA_CM2)[:, None]
    ln = np.asarray(length_cm, dtype=float)[:, None]
    w = np.asarray(w, dtype=float)[None, :]
    perim = 2.0 * np.sqrt(np.pi * a)
    z = 1j * w * air.rho / a
    y = 1j * w * a / (air.rho * air.c ** 2)
    if air.viscous:
        z = z + perim / a ** 2 * np.sqrt(w * air.rho * air.mu / 2.0)
    if air.heat:
        y = y + perim * (air.eta - 1.0) / (air.rho * air.c ** 2) * np.sqrt(air.kappa * w / (2.0 * air.cp * air.rho))
    if air.walls:
        y = y + perim / (air.wall_resistance + 1j * w * air.wall_mass + air.wall_stiffness / (1j * w))
    g = np.sqrt(z * y) * ln
    z0 = np.sqrt(z / y)
    e = np.exp(g)
    ei = 1.0 / e
    ch, sh = 0.5 * (e + ei), 0.5 * (e - ei)
    return ch, z0 * sh, sh / z0


def section_matrices(length_cm: np.ndarray, area_cm2: np.ndarray, w: np.ndarray, air: Air) -> np.ndarray:
    """(n, F, 2, 2) chain matrices of n sections at angular frequencies ``w`` (F,)."""
    ch, b, c = _line_parameters(length_cm, area_cm2, w, air)
    k = np.empty(ch.shape + (2, 2), dtype=complex)
    k[..., 0, 0] = ch
    k[..., 0, 1] = b
    k[..., 1, 0] = c
    k[..., 1, 1] = ch
    return k


def _chain_loop(length, area, w, c, rho, mu, kappa, cp, eta, wall_m, wall_r, wall_k, viscous, heat, walls
                  ):  # pragma: no cover - compiled; the same numbers as section_matrices (a test compares)
    nf, n = w.shape[0], length.shape[0]
    out = np.empty((nf, 4), dtype=np.complex128)
    rc2 = rho * c * c
    visc = np.sqrt(rho * mu / 2.0) if viscous else 0.0
    cond = (eta - 1.0) / rc2 * np.sqrt(kappa / (2.0 * cp * rho)) if heat else 0.0
    # what depends on the section only: inertance, compliance, and the loss terms' area factors
    inert, compl, z_loss, y_loss, perim = (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n))
    for k in range(n):
        ak = area[k] if area[k] > MIN_AREA_CM2 else MIN_AREA_CM2
        perim[k] = 2.0 * np.sqrt(np.pi * ak)
        inert[k] = rho / ak
        compl[k] = ak / rc2
        z_loss[k] = perim[k] / (ak * ak) * visc
        y_loss[k] = perim[k] * cond
    for i in prange(nf):
        wi = w[i]
        sw = np.sqrt(wi)
        wall = 1.0 / (wall_r + 1j * (wi * wall_m - wall_k / wi)) if walls else 0j
        a_, b_, c_, d_ = 1.0 + 0j, 0j, 0j, 1.0 + 0j
        for k in range(n):
            z = z_loss[k] * sw + 1j * wi * inert[k]
            y = y_loss[k] * sw + 1j * wi * compl[k] + perim[k] * wall
            root = np.sqrt(z * y)  # the propagation constant per cm
            z0 = z / root  # sqrt(z / y)
            e = np.exp(root * length[k])
            ei = 1.0 / e
            ch = 0.5 * (e + ei)
            sh = 0.5 * (e - ei)
            x, yy, zz = ch, z0 * sh, sh / z0
            a_, b_, c_, d_ = a_ * x + b_ * zz, a_ * yy + b_ * x, c_ * x + d_ * zz, c_ * yy + d_ * x
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = a_, b_, c_, d_
    return out


_chain_serial = njit(cache=True)(_chain_loop)
_chain_parallel = njit(cache=True, parallel=True)(_chain_loop)
PARALLEL_FROM = 256  # frequencies; below this, starting the threads costs more than they save


def chain(length_cm: np.ndarray, area_cm2: np.ndarray, w: np.ndarray, air: Air) -> np.ndarray:
    """(F, 2, 2) product of the sections' matrices, first section first (a compiled loop over frequencies
    and sections, threaded over frequencies for long spectra)."""
    kernel = _chain_parallel if np.size(w) >= PARALLEL_FROM else _chain_serial
    k = kernel(np.ascontiguousarray(length_cm, dtype=float), np.ascontiguousarray(area_cm2, dtype=float),
                      np.ascontiguousarray(w, dtype=float), air.c, air.rho, air.mu, air.kappa, air.cp, air.eta,
                      air.wall_mass, air.wall_resistance, air.wall_stiffness, air.viscous, air.heat, air.walls)
    return k.reshape(-1, 2, 2)


def chain_numpy(length_cm: np.ndarray, area_cm2: np.ndarray, w: np.ndarray, air: Air) -> np.ndarray:
    """The same product in numpy (four entries multiplied as arrays over frequencies): the reference the
    compiled :func:`chain` is tested against."""
    ch, bb, cc = _line_parameters(length_cm, area_cm2, w, air)
    a, b, c, d = ch[0], bb[0], cc[0], ch[0]
    for k in range(1, ch.shape[0]):
        x, y, z = ch[k], bb[k], cc[k]
        a, b, c, d = a * x + b * z, a * y + b * x, c * x + d * z, c * y + d * x
    out = np.empty(a.shape + (2, 2), dtype=complex)
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = a, b, c, d
    return out


def radiation_impedance(area_cm2: float, w: np.ndarray, air: Air) -> np.ndarray:
    """(F,) acoustic impedance of an opening of ``area_cm2`` radiating into free space (0: ideal open end)."""
    if not air.radiation:
        return np.zeros_like(np.asarray(w, dtype=float), dtype=complex)
    a = max(float(area_cm2), MIN_AREA_CM2)
    r = 128.0 * air.rho * air.c / (9.0 * np.pi ** 2 * a)
    lr = 8.0 * air.rho / (3.0 * np.pi * np.sqrt(np.pi * a))
    jwl = 1j * np.asarray(w, dtype=float) * lr
    return jwl * r / (r + jwl)


def input_impedance(k: np.ndarray, load: np.ndarray | None) -> np.ndarray:
    """(F,) impedance looking into a chain ``k`` (F, 2, 2) ended by ``load`` (F,; None: a closed end)."""
    if load is None:  # U = 0 at the far end: Z = A / C
        return k[:, 0, 0] / k[:, 1, 0]
    return (k[:, 0, 0] * load + k[:, 0, 1]) / (k[:, 1, 0] * load + k[:, 1, 1])


def shunt(admittance: np.ndarray) -> np.ndarray:
    """(F, 2, 2) the chain matrix of a side branch of ``admittance`` (F,) at a junction."""
    s = np.zeros((len(admittance), 2, 2), dtype=complex)
    s[:, 0, 0] = s[:, 1, 1] = 1.0
    s[:, 1, 0] = admittance
    return s
