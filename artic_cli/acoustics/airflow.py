"""The air through the tract in time: the pressure in the cavity behind the narrowest place as a state.

The lungs push at P_s through the glottis (area A_g) into the cavity behind the tract's narrowest place
(area A_c); air leaves it through that place and, with the velopharyngeal port open, through the nose (the
port A_p and the nasal valve in series).  Each orifice passes U = A sgn(dp) sqrt(2 |dp| / rho) (Bernoulli,
no pressure recovery).  The cavity stores air in two ways: the air's own compliance V / (rho c^2) (V: the
volume behind the constriction) and its yielding walls, a surface S (the perimeter times the length behind
the constriction) of the same mass, resistance and stiffness per unit area as the acoustic line's walls
(m x'' + r x' + k x = P), taking S x' of the flow (Rothenberg 1968, Westbury 1983: the walls' expansion is
what lets voicing go on behind a closure; Stevens 1998, ch. 2.1-2.2, for the model):

    V / (rho c^2) dP/dt = U_g - U_c - U_n - S x' - dV_a/dt,

V_a the cavity's active enlargement (a voiced obstruent's lowered larynx and advanced tongue root:
Kent & Moll 1969, Westbury 1983), a control input.

Each step is backward Euler for P (Newton inside a bisection bracket: the right side falls as P rises, so one root) with the
wall's velocity solved with it; the step is a few of the line's samples (the cavity's time constant at a
release is about a millisecond).  With the constriction closed, P rises toward P_s and the flow through the
glottis, and with it the voice, dies away; at the release P drives a burst of flow through the opening.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..jit import njit


@dataclass
class Cavity:
    """Per frame: the narrowest place behind the lips and what lies behind it."""

    index: np.ndarray  # (F,) int: the narrowest section
    area_cm2: np.ndarray  # (F,) its area
    at_cm: np.ndarray  # (F,) its downstream end, from the glottis
    volume_cm3: np.ndarray  # (F,) the air behind it
    wall_cm2: np.ndarray  # (F,) the wall surface behind it
    end: np.ndarray  # (F,) int: the constriction's last section (from the narrowest, the run within 1.5 x its area)


def cavities(length_cm: np.ndarray, area_cm2: np.ndarray) -> Cavity:
    """The cavity behind each frame's narrowest section (frames x sections, glottis first)."""
    L, A = np.asarray(length_cm, float), np.asarray(area_cm2, float)
    k = np.argmin(A, axis=1)
    rows = np.arange(len(A))
    behind = np.arange(A.shape[1])[None, :] < k[:, None]
    volume = np.sum(np.where(behind, L * A, 0.0), axis=1)
    wall = np.sum(np.where(behind, L * 2.0 * np.sqrt(np.pi * np.maximum(A, 0.0)), 0.0), axis=1)
    narrow = (A <= 1.5 * A[rows, k][:, None] + 1e-4) | behind
    end = np.where(narrow.all(axis=1), A.shape[1] - 1, np.argmin(narrow, axis=1) - 1)
    return Cavity(index=k, area_cm2=A[rows, k], at_cm=np.cumsum(L, axis=1)[rows, k], volume_cm3=volume,
                  wall_cm2=wall, end=np.maximum(end, k))


@njit(cache=True)
def _line_cavities(frame_areas, section_cm, frame_index):  # pragma: no cover - compiled
    steps, (F, n) = frame_index.shape[0], frame_areas.shape
    index, end = np.zeros(steps, np.int64), np.zeros(steps, np.int64)
    area, volume, wall = np.zeros(steps), np.zeros(steps), np.zeros(steps)
    a = np.zeros(n)
    for s in range(steps):
        k0 = min(int(frame_index[s]), max(F - 2, 0))
        w = frame_index[s] - k0 if F > 1 else 0.0
        for j in range(n):
            a[j] = (1.0 - w) * frame_areas[k0, j] + (w * frame_areas[k0 + 1, j] if F > 1 else 0.0)
        k = 0
        for j in range(1, n):
            if a[j] < a[k]:
                k = j
        v, surface = 0.0, 0.0
        for j in range(k):
            v += section_cm * a[j]
            surface += section_cm * 2.0 * np.sqrt(np.pi * max(a[j], 0.0))
        e = k
        while e + 1 < n and a[e + 1] <= 1.5 * a[k] + 1e-4:
            e += 1
        index[s], end[s], area[s], volume[s], wall[s] = k, e, a[k], v, surface
    return index, end, area, volume, wall


def line_cavities(frame_areas: np.ndarray, section_cm: float, frame_index: np.ndarray) -> Cavity:
    """The cavity at each of the air's steps from the line's own areas (frames x equal sections of
    ``section_cm``), interpolated between frames at fractional ``frame_index`` as the line does: the narrowest
    place moves with the areas, not from one frame's to the next's (the same numbers as :func:`cavities` on
    the interpolated areas; a test compares)."""
    index, end, area, volume, wall = _line_cavities(np.ascontiguousarray(frame_areas, dtype=float), float(section_cm),
                                                    np.ascontiguousarray(frame_index, dtype=float))
    return Cavity(index=index, area_cm2=area, at_cm=(index + 1) * section_cm, volume_cm3=volume, wall_cm2=wall,
                  end=end)


def outlet(index: np.ndarray, area_cm2: np.ndarray, constricted_cm2: float) -> np.ndarray:
    """The junction where the cavity's air leaves: after the constriction's last section while it is one
    (narrower than ``constricted_cm2``), and held there once it opens (its air still rushing out: a release
    leaves the burst where the closure was, not at the next narrowest place)."""
    held = np.where(np.asarray(area_cm2) < constricted_cm2, np.asarray(index), -1)
    fill = np.maximum.accumulate(np.where(held >= 0, np.arange(len(held)), -1))
    return np.where(fill >= 0, held[np.maximum(fill, 0)], np.asarray(index))


@njit(cache=True)
def _orifice(area, dp, rho):  # pragma: no cover - compiled
    """Bernoulli flow through an orifice (cm^3/s), its sign the pressure difference's."""
    if dp >= 0.0:
        return area * np.sqrt(2.0 * dp / rho)
    return -area * np.sqrt(-2.0 * dp / rho)


@njit(cache=True)
def _slope(area, dp, rho):  # pragma: no cover - compiled
    """d|U| / d|dp| of an orifice (large near dp = 0, where Bernoulli's flow is not smooth)."""
    return area / np.sqrt(2.0 * rho * max(abs(dp), 1e-3))


@njit(cache=True)
def _cavity_pressure(lung, glottis, constriction, nose, compliance, wall_area, expansion, wall_m, wall_r, wall_k,
                     rho, dt):  # pragma: no cover - compiled
    """(P, U_g, U_c, U_n) per step: P the cavity's pressure (dyn/cm^2), the flows cm^3/s."""
    n = glottis.shape[0]
    p_out, ug, uc, un = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    p, x, v = 0.0, 0.0, 0.0
    d = wall_m / dt + wall_r + wall_k * dt
    for s in range(n):
        a = ((wall_m / dt) * v - wall_k * x) / d  # the wall's new velocity is a + P / d
        c_dt = compliance[s] / dt
        lo = -2.0 * lung - abs(p)
        hi = 2.0 * lung + abs(p)
        x_ = p  # Newton from the last step's pressure, kept inside a bisection bracket (the residual rises with P)
        for _ in range(60):
            r = c_dt * (x_ - p) - (_orifice(glottis[s], lung - x_, rho) - _orifice(constriction[s], x_, rho)
                                   - _orifice(nose[s], x_, rho) - wall_area[s] * (a + x_ / d) - expansion[s])
            if r < 0.0:
                lo = x_
            else:
                hi = x_
            slope = c_dt + wall_area[s] / d + _slope(glottis[s], lung - x_, rho) + _slope(constriction[s], x_, rho) \
                + _slope(nose[s], x_, rho)
            step = x_ - r / slope
            if not (lo < step < hi):
                step = 0.5 * (lo + hi)
            if abs(step - x_) < 1e-6 * (1.0 + abs(x_)) or hi - lo < 1e-6:
                x_ = step
                break
            x_ = step
        p = x_
        v = a + p / d
        x += dt * v
        p_out[s] = p
        ug[s] = _orifice(glottis[s], lung - p, rho)
        uc[s] = _orifice(constriction[s], p, rho)
        un[s] = _orifice(nose[s], p, rho)
    return p_out, ug, uc, un


@dataclass
class Airflow:
    """The air per step of ``time_s`` (s): pressures dyn/cm^2, flows cm^3/s, areas cm^2."""

    time_s: np.ndarray
    oral_pressure: np.ndarray  # the cavity behind the narrowest place
    glottal_flow: np.ndarray
    constriction_flow: np.ndarray
    nasal_flow: np.ndarray
    glottis_cm2: np.ndarray
    constriction_cm2: np.ndarray


def airflow(time_s: np.ndarray, lung_pressure: float, glottis_cm2: np.ndarray, constriction_cm2: np.ndarray,
            nose_cm2: np.ndarray, volume_cm3: np.ndarray, wall_cm2: np.ndarray, ac,
            expansion_cm3_s: np.ndarray | float = 0.0) -> Airflow:
    """The cavity's pressure and the flows at each of ``time_s`` (evenly spaced), the inputs given there
    (``ac``: the config's acoustics section: air and walls; ``expansion_cm3_s``: the cavity's active
    enlargement, the rate its volume grows by the speaker's own doing)."""
    t = np.asarray(time_s, float)
    dt = float(t[1] - t[0]) if len(t) > 1 else 1e-4
    rho, c = ac.air_density_g_cm3, ac.sound_speed_cm_s
    compliance = np.maximum(np.asarray(volume_cm3, float), 1e-3) / (rho * c * c)
    walls = np.asarray(wall_cm2, float) if ac.yielding_walls else np.zeros(len(t))
    arrays = [np.ascontiguousarray(np.broadcast_to(np.asarray(v, float), t.shape)) for v in
              (glottis_cm2, constriction_cm2, nose_cm2, compliance, walls, expansion_cm3_s)]
    so = ac.sources
    p, ug, uc, un = _cavity_pressure(float(lung_pressure), *arrays, ac.wall_mass_g_cm2,
                                     so.cavity_wall_resistance_dyn_s_cm3, ac.wall_stiffness_dyn_cm3, rho, dt)
    return Airflow(time_s=t, oral_pressure=p, glottal_flow=ug, constriction_flow=uc, nasal_flow=un,
                   glottis_cm2=arrays[0], constriction_cm2=arrays[1])
