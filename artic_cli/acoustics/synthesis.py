"""Sound from a tube in the time domain: a reflection-type line (Kelly & Lochbaum 1962) at twice the audio
rate, driven at the glottis by the LF flow derivative, radiating at the lips.

The tract is cut into N sections of equal length c / fs_internal, so that a wave crosses one section per
sample; area changes between frames are interpolated sample by sample.  Each junction has one pressure,
2 sum(A p_in) / sum(A) over the tubes that meet there, and each tube's outgoing wave is that pressure less
its incoming one: between two sections the scattering r = (A_k - A_k+1) / (A_k + A_k+1), |r| <= 1 for every
area, so a closure (area 0, held at 0.01 mm^2) reflects the wave whole and stays stable: silence behind it,
a release when it opens; a closed section's waves are cleared (it holds no air column), so a closure that
moves along the line leaves no trapped wave to click out when a section reopens.  A closed side branch (the
piriform fossae, as the transfer function has them) joins at a three-tube junction.  Yielding walls, as the
transfer function has them (mass, resistance and stiffness per unit area; Ishizaka et al. 1975's form): at
each two-tube junction a patch of wall, the perimeter 2 sqrt(pi A) times a section's length, moves under the
junction pressure and takes its volume velocity from the junction's flow (the wall's velocity and the
junction's pressure solved together, a backward-Euler step).  The glottis end reflects with
``glottal_reflection`` (nearly closed).  The lips reflect through the same radiation load as the
frequency-domain model (a piston in a baffle, parallel R-L), as a first-order filter (bilinear transform of
(Z - Zc) / (Z + Zc), Zc = rho c / A_lips): -1 at low frequencies, with the end correction that lowers the
formants of a wide mouth.  Each section passes ``1 - section_loss`` of a wave (boundary-layer losses
lumped).  Turbulence noise (frication, bursts) enters as a series pressure source at a junction, half its
pressure sent each way.  The radiated sound is the time derivative of the lips' volume velocity, brought to
the audio rate by a polyphase filter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..jit import njit
from .nasal import NasalLine

MIN_AREA_CM2 = 1e-4


@njit(cache=True)
def _leaky_integral(x, gain, keep):
    """y[n] = gain x[n] + keep y[n-1]: a first-order recursive filter (scipy.signal.lfilter([gain], [1, -keep])
    without importing scipy.signal, 2.6 s per process)."""
    y = np.empty_like(x)
    acc = 0.0
    for k in range(len(x)):
        acc = gain * x[k] + keep * acc
        y[k] = acc
    return y


@njit(cache=True)
def _areas_at(frame_areas, pos, area):  # pragma: no cover - compiled
    """The sections' areas at fractional frame ``pos`` (linear between frames, at least MIN_AREA_CM2)."""
    n = frame_areas.shape[1]
    k0 = int(pos)
    if k0 >= frame_areas.shape[0] - 1:
        k0 = frame_areas.shape[0] - 2 if frame_areas.shape[0] > 1 else 0
    w = pos - k0 if frame_areas.shape[0] > 1 else 0.0
    for j in range(n):
        a = (1.0 - w) * frame_areas[k0, j] + (w * frame_areas[k0 + 1, j] if frame_areas.shape[0] > 1 else 0.0)
        area[j] = a if a > MIN_AREA_CM2 else MIN_AREA_CM2


@njit(cache=True)
def _branch_step(branch_areas, bf, bb, new_bf, new_bb, keep):  # pragma: no cover - compiled
    """One sample of the side branch's own junctions (its far end closed), ``new_bf[0]`` set by the caller."""
    m = branch_areas.shape[0]
    for k in range(m - 1):
        r = (branch_areas[k] - branch_areas[k + 1]) / (branch_areas[k] + branch_areas[k + 1])
        new_bf[k + 1] = (1.0 + r) * bf[k] - r * bb[k + 1]
        new_bb[k] = r * bf[k] + (1.0 - r) * bb[k + 1]
    new_bb[m - 1] = bf[m - 1]  # its far end is closed
    for k in range(m):
        bf[k] = keep * new_bf[k]
        bb[k] = keep * new_bb[k]


@njit(cache=True)
def _radiation(a_l, rho, c, fs):  # pragma: no cover - compiled
    """(b0, b1, a0, a1): the reflection filter of an opening of area ``a_l`` into the radiation load, a
    parallel R-L (Flanagan), by the bilinear transform."""
    pi = np.pi
    zc = rho * c / a_l
    r_rad = 128.0 * rho * c / (9.0 * pi * pi * a_l)
    k_rad = 2.0 * fs * 8.0 * rho / (3.0 * pi * np.sqrt(pi * a_l))
    b0 = k_rad * (r_rad - zc) - zc * r_rad
    b1 = -k_rad * (r_rad - zc) - zc * r_rad
    a0 = k_rad * (r_rad + zc) + zc * r_rad
    a1 = -k_rad * (r_rad + zc) + zc * r_rad
    return b0, b1, a0, a1


@njit(cache=True)
def _lips_reflect(a_l, f_now, last_f, last_b, rho, c, fs):  # pragma: no cover - compiled
    """The wave reflected at the lips from the forward wave now and the last sample's two waves."""
    b0, b1, a0, a1 = _radiation(a_l, rho, c, fs)
    return (b0 * f_now + b1 * last_f - a1 * last_b) / a0


@njit(cache=True)
def _value_at(frame_values, pos):  # pragma: no cover - compiled
    """One value per frame at fractional frame ``pos`` (linear between frames)."""
    last = frame_values.shape[0] - 1
    if last <= 0:
        return frame_values[0]
    k0 = min(int(pos), last - 1)
    w = pos - k0
    return (1.0 - w) * frame_values[k0] + w * frame_values[k0 + 1]


@njit(cache=True, inline="always")
def _nasal_step(nl_areas, patch, sinus_at, sinus_m, sinus_k, sinus_a, nf, nb, new_nf, new_nb, sv, sx, wv, wx,
                wall, keep, dt, rho, c, rad):  # pragma: no cover - compiled
    """One sample of the nasal branch (``new_nf[0]`` set by the caller): its junctions with their yielding
    walls (``patch``: each junction's wall area) and sinuses, the nostrils radiating (``rad``: the filter's
    last two waves and its coefficients); returns the nostrils' volume velocity.  A junction's pressure and
    its shunts' velocities are solved together: each shunt (a wall patch, a sinus's neck) of area A moves at
    v = (c + p) / d (backward Euler on m dv/dt = p - r v - k x: c = m v / dt - k x, d = m / dt + r + k dt), so
    p = rho c (into - sum A c / d) / (sum of areas + rho c sum A / d)."""
    m = nl_areas.shape[0]
    rho_c = rho * c
    walls = wall[0] > 0.0
    inv_dw = 1.0 / (wall[0] / dt + wall[1] + wall[2] * dt) if walls else 0.0
    for k in range(m - 1):
        a_sum = nl_areas[k] + nl_areas[k + 1]
        num = 2.0 * (nl_areas[k] * nf[k] + nl_areas[k + 1] * nb[k + 1])
        den = a_sum
        cw = 0.0
        if walls:
            cw = (wall[0] / dt) * wv[k] - wall[2] * wx[k]
            num -= patch[k] * cw * inv_dw
            den += rho_c * patch[k] * inv_dw
        q = sinus_at[k]
        cs, inv_ds = 0.0, 0.0
        if q >= 0:
            cs = (sinus_m[q] / dt) * sv[q] - sinus_k[q] * sx[q]
            inv_ds = 1.0 / (sinus_m[q] / dt + sinus_k[q] * dt)
            num -= sinus_a[q] * cs * inv_ds
            den += rho_c * sinus_a[q] * inv_ds
        p = rho_c * num / den
        if walls:
            wv[k] = (cw + p) * inv_dw
            wx[k] += dt * wv[k]
        if q >= 0:
            sv[q] = (cs + p) * inv_ds
            sx[q] += dt * sv[q]
        pj = p / rho_c
        new_nf[k + 1] = pj - nb[k + 1]
        new_nb[k] = pj - nf[k]
    new_nb[m - 1] = (rad[2] * nf[m - 1] + rad[3] * rad[0] - rad[5] * rad[1]) / rad[4]  # the nostrils' radiation
    rad[0] = nf[m - 1]
    rad[1] = new_nb[m - 1]
    u = rad[6] * (nf[m - 1] - new_nb[m - 1])
    for k in range(m):
        nf[k] = keep * new_nf[k]
        nb[k] = keep * new_nb[k]
    return u


@njit(cache=True, inline="always")
def _junctions(area, fwd, bwd, new_f, new_b, wall_x, wall_v, wall, rho, c, dt, dx, branch_at, branch_areas, bb,
               new_bf, nasal_at, port, nb, new_nf, inject, inject_at):  # pragma: no cover - compiled
    """Each junction's pressure p / (rho c) = f + b from the flows U = A (f - b) into it, the side branches'
    (the fossa at ``branch_at``, the nasal tract through the port at ``nasal_at``, -1: shut) and an injected
    flow joining; the walls' patches solved with it.  Returns the walls' volume velocity."""
    n = area.shape[0]
    wall_m, wall_r, wall_k = wall[0], wall[1], wall[2]
    walls = wall_m > 0.0
    pi = np.pi
    skin = 0.0
    for j in range(n - 1):
        a_sum = area[j] + area[j + 1]
        into = 2.0 * (area[j] * fwd[j] + area[j + 1] * bwd[j + 1])
        if j == inject_at:  # the air leaving a constriction as it opens (a release's transient)
            into += inject
        main = a_sum
        if j == nasal_at:  # the port: the nasal branch's flow joins
            a_sum += port
            into += 2.0 * port * nb[0]
        if j == branch_at:  # three tubes meet: the side branch's flow joins
            a_sum += branch_areas[0]
            into += 2.0 * branch_areas[0] * bb[0]
        elif walls:  # less what the junction's wall patch takes; the wall's velocity and the pressure solved
            # together (backward Euler): stable for any area, a closure's slit included
            patch = 2.0 * np.sqrt(pi * 0.5 * main) * dx
            wall_v[j] = ((wall_m / dt) * wall_v[j] + rho * c * into / a_sum - wall_k * wall_x[j]) / (
                wall_m / dt + rho * c * patch / a_sum + wall_r + wall_k * dt)
            wall_x[j] += dt * wall_v[j]
            into -= patch * wall_v[j]
            skin += patch * wall_v[j]
        pj = into / a_sum
        new_f[j + 1] = pj - bwd[j + 1]
        new_b[j] = pj - fwd[j]
        if j == branch_at:
            new_bf[0] = pj - bb[0]
        if j == nasal_at:
            new_nf[0] = pj - nb[0]
    return skin


@njit(cache=True, inline="always")
def _pressure_source(new_f, new_b, p, k, rho, c):  # pragma: no cover - compiled
    """A series pressure source (dyn/cm^2) between sections k and k + 1: half its pressure sent each way."""
    half = 0.5 * p / (rho * c)
    new_f[k + 1] += half
    new_b[k] -= half


@njit(cache=True, inline="always")
def _advance(area, fwd, bwd, new_f, new_b, keep):  # pragma: no cover - compiled
    """The new waves, less the sections' loss; a closed section holds no air column: no wave stays trapped in
    it to leave as a click when it opens (its flow A (f - b) would jump with its area)."""
    for j in range(area.shape[0]):
        if area[j] <= MIN_AREA_CM2:
            fwd[j] = 0.0
            bwd[j] = 0.0
        else:
            fwd[j] = keep * new_f[j]
            bwd[j] = keep * new_b[j]


@njit(cache=True)
def _line(frame_areas, frame_index, source, glottal_reflection, rho, c, fs, loss, branch_at,
          branch_areas, noise, noise_at, wall_m, wall_r, wall_k, nasal_at, nasal_areas, nasal_port,
          frame_ports, sinus_at, sinus_m, sinus_k, sinus_a, nostril, aspiration, inject, inject_at,
          skin):  # pragma: no cover - compiled
    n_samples, n = source.shape[0], frame_areas.shape[1]
    fwd, bwd, new_f, new_b, area = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    m = branch_areas.shape[0]
    bf, bb, new_bf, new_bb = np.zeros(m), np.zeros(m), np.zeros(m), np.zeros(m)  # the fossa: away, toward
    nm = nasal_areas.shape[0]
    nas = nasal_areas.copy()
    nf, nb, new_nf, new_nb = np.zeros(nm), np.zeros(nm), np.zeros(nm), np.zeros(nm)  # the nasal branch
    nwv, nwx, sv, sx, rad = np.zeros(nm), np.zeros(nm), np.zeros(len(sinus_a)), np.zeros(len(sinus_a)), np.zeros(7)
    rad[2], rad[3], rad[4], rad[5] = _radiation(nostril, rho, c, fs)  # the nostrils' filter; rad[:2]: its waves
    rad[6] = nostril
    dt, dx = 1.0 / fs, c / fs
    npatch = np.zeros(max(nm - 1, 0))  # the nasal junctions' wall areas (those beside the port: per sample)
    for k in range(nm - 1):
        npatch[k] = 2.0 * np.sqrt(np.pi * 0.5 * (nas[k] + nas[k + 1])) * dx
    out = np.zeros(n_samples)
    last_u, last_f, last_b = 0.0, 0.0, 0.0
    keep = 1.0 - loss
    wall_x, wall_v = np.zeros(n), np.zeros(n)  # each junction's wall patch: displacement (cm), velocity (cm/s)
    wall = np.array([wall_m, wall_r, wall_k])
    was_open = False
    for s in range(n_samples):
        _areas_at(frame_areas, frame_index[s], area)
        port = _value_at(frame_ports, frame_index[s]) if nm > 0 else 0.0
        nasal = port > MIN_AREA_CM2
        if nasal:
            nas[:nasal_port] = port
            for k in range(min(nasal_port, nm - 1)):
                npatch[k] = 2.0 * np.sqrt(np.pi * 0.5 * (nas[k] + nas[k + 1])) * dx
        new_f[0] = glottal_reflection * bwd[0] + source[s] / area[0]
        skin_u = _junctions(area, fwd, bwd, new_f, new_b, wall_x, wall_v, wall, rho, c, dt, dx, branch_at,
                            branch_areas, bb, new_bf, nasal_at if nasal else -1, port, nb, new_nf, inject[s],
                            inject_at[s])
        if 0 <= noise_at[s] < n - 1:  # the jet's turbulence past the narrowest place
            _pressure_source(new_f, new_b, noise[s], noise_at[s], rho, c)
        if aspiration.shape[0] > 0:  # the glottis's turbulence, just above it
            _pressure_source(new_f, new_b, aspiration[s], 0, rho, c)
        if m > 0:
            _branch_step(branch_areas, bf, bb, new_bf, new_bb, keep)
        u_nose = 0.0
        if nasal:
            u_nose = _nasal_step(nas, npatch, sinus_at, sinus_m, sinus_k, sinus_a, nf, nb, new_nf, new_nb, sv, sx,
                                 nwv, nwx, wall, keep, dt, rho, c, rad)
            was_open = True
        elif was_open:  # the port shut: the nasal tract's air column is cut off, its waves gone
            for arr in (nf, nb, nwv, nwx, sv, sx):
                arr[:] = 0.0
            rad[0], rad[1], was_open = 0.0, 0.0, False
        a_l = area[n - 1]
        new_b[n - 1] = _lips_reflect(a_l, fwd[n - 1], last_f, last_b, rho, c, fs)
        last_f, last_b = fwd[n - 1], new_b[n - 1]
        u = area[n - 1] * (fwd[n - 1] - new_b[n - 1]) if a_l > 2e-4 else 0.0  # closed lips radiate nothing
        if nasal:
            u += u_nose
        if inject_at[s] == n - 1:  # the air leaving through the lips' own constriction
            u += inject[s]
        if skin > 0.0:  # the yielding walls move the skin of the neck and cheeks: they radiate too
            u += skin * skin_u
        out[s] = u - last_u
        last_u = u
        _advance(area, fwd, bwd, new_f, new_b, keep)
    return out


def sections_for(length_cm: float, c_cm_s: float, fs_internal: float) -> int:
    return max(2, int(round(length_cm * fs_internal / c_cm_s)))


def resample_tube(length_cm: np.ndarray, area_cm2: np.ndarray, n: int) -> np.ndarray:
    """(n,) areas of a tube at n equal sections: the area at each new section's centre, and 0 for a new
    section that a closed one (area <= 0) overlaps, however short (a closure narrower than the line's
    sections would otherwise fall between their centres and leak)."""
    area = np.asarray(area_cm2, dtype=float)
    edges = np.concatenate([[0.0], np.cumsum(length_cm)])
    step = edges[-1] / n
    centres = (np.arange(n) + 0.5) * step
    k = np.clip(np.searchsorted(edges, centres, side="right") - 1, 0, len(area) - 1)
    out = area[k]
    for j in np.flatnonzero(area <= 0.0):
        first = int(np.clip(np.floor(edges[j] / step), 0, n - 1))
        last = int(np.clip(np.ceil(edges[j + 1] / step) - 1, first, n - 1))
        out[first:last + 1] = 0.0
    return out


def side_branch(at_cm: float, tube_length_cm: float, n: int, branch_length_cm: np.ndarray,
                branch_area_cm2: np.ndarray, c_cm_s: float, fs_internal: float) -> tuple[int, np.ndarray]:
    """Where a closed side branch (the piriform fossae) joins a line of n equal sections over
    ``tube_length_cm`` (the junction after section k) and its areas at the line's section length."""
    k = int(round(at_cm / (tube_length_cm / n))) - 1
    m = sections_for(float(np.sum(branch_length_cm)), c_cm_s, fs_internal)
    return max(0, min(k, n - 2)), np.maximum(resample_tube(branch_length_cm, branch_area_cm2, m), MIN_AREA_CM2)


def noise_samples(frame_times_s: np.ndarray, rms: np.ndarray, at_fraction: np.ndarray, t_s: np.ndarray, n: int,
                  seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """White Gaussian noise per internal sample with the frames' RMS (interpolated in time) and the junction it
    acts at (the nearest frame's place, a fraction of the tract's length from the glottis, as the section of
    the line's n after which it joins; -1 where the RMS is zero)."""
    ft = np.asarray(frame_times_s, float) - float(frame_times_s[0])
    level = np.interp(t_s, ft, np.asarray(rms, float)) if len(ft) > 1 else np.full(len(t_s), float(rms[0]))
    nearest = np.clip(np.searchsorted(ft, t_s), 0, len(ft) - 1)
    k = np.clip(np.round(np.asarray(at_fraction, float)[nearest] * n).astype(np.int64) - 1, 0, n - 2)
    k = np.where(level > 0, k, -1)
    return level * np.random.default_rng(seed).standard_normal(len(t_s)), k


@dataclass
class Extra:
    """The line's sources and branches beyond the voice, each optional (per internal sample where an array):
    ``nasal`` (the nasal branch, from :func:`artic_cli.acoustics.nasal.nasal_line`) with the port's area per
    frame ``frame_ports_cm2``; ``aspiration``: a pressure source just above the glottis (dyn/cm^2);
    ``inject``/``inject_at``: a volume velocity (cm^3/s) entering the junction after section ``inject_at`` (-1:
    none); ``voice_gain``: the voice's flow times this; ``skin``: the share of the yielding walls' volume
    velocity that radiates (0: none)."""

    nasal: NasalLine | None = None
    frame_ports_cm2: np.ndarray | None = None
    aspiration: np.ndarray | None = None
    inject: np.ndarray | None = None
    inject_at: np.ndarray | None = None
    voice_gain: np.ndarray | None = None
    skin: float = 0.0


def _extra_arrays(x: Extra, n_samples: int, n: int, branch_at: int) -> tuple:
    nl = x.nasal
    if nl is None or x.frame_ports_cm2 is None:
        nasal = (-1, np.zeros(0), 0, np.zeros(1), np.zeros(0, np.int64), np.zeros(0), np.zeros(0), np.zeros(0), 1.0)
    else:
        at = nl.at if nl.at != branch_at else min(nl.at + 1, n - 2)
        nasal = (int(at), np.asarray(nl.areas_cm2, float), int(nl.port_sections),
                 np.ascontiguousarray(x.frame_ports_cm2, dtype=float), np.asarray(nl.sinus_junction, np.int64),
                 nl.sinus_mass, nl.sinus_stiffness, nl.sinus_area_cm2, float(nl.nostril_area_cm2))
    asp = np.zeros(0) if x.aspiration is None else np.ascontiguousarray(x.aspiration, dtype=float)
    if x.inject is None:
        inject, inject_at = np.zeros(n_samples), np.full(n_samples, -1, np.int64)
    else:
        inject, inject_at = (np.ascontiguousarray(x.inject, dtype=float),
                             np.ascontiguousarray(x.inject_at, dtype=np.int64))
    return (*nasal, asp, inject, inject_at, float(x.skin))


def synthesize(frame_areas: np.ndarray, frame_times_s: np.ndarray, source: np.ndarray, fs_internal: float,
               glottal_reflection: float = 0.97, section_loss: float = 5e-4, rho: float = 1.14e-3,
               c: float = 35000.0, branch: tuple[int, np.ndarray] | None = None, flow_peak_cm3_s: float | None = None,
               noise: tuple[np.ndarray, np.ndarray] | None = None,
               walls: tuple[float, float, float] | None = None, extra: Extra | None = None) -> np.ndarray:
    """The radiated sound at ``fs_internal`` for areas (frames x N equal sections) at ``frame_times_s`` and a
    source (flow derivative per internal sample); ``branch``: a closed side tube, (the section after which it
    joins, its areas), from :func:`side_branch`; ``flow_peak_cm3_s``: the glottal flow's peak (else arbitrary
    units); ``noise``: a pressure source per internal sample (dyn/cm^2) and the section after which it acts (-1:
    none), on the same scale as a flow of ``flow_peak_cm3_s``; ``walls``: (mass g/cm^2, resistance dyn s/cm^3,
    stiffness dyn/cm^3) per unit area of yielding wall (None: rigid); ``extra``: the nasal branch and the
    aerodynamic sources (:class:`Extra`; None: none, the line as it was before them, bit for bit)."""
    t = np.arange(len(source)) / fs_internal
    index = np.interp(t, frame_times_s, np.arange(len(frame_times_s))) if len(frame_times_s) > 1 else np.zeros(len(t))
    # the source drives flow: integrate its derivative (leaky, so no drift) before it enters the line
    flow = _leaky_integral(np.ascontiguousarray(source, dtype=float), 1.0 / fs_internal, 0.999)
    peak = float(np.max(np.abs(flow))) if len(flow) else 0.0
    flow = flow * (flow_peak_cm3_s / peak if flow_peak_cm3_s is not None and peak > 0 else 1e4)
    extra = Extra() if extra is None else extra
    if extra.voice_gain is not None:
        flow = flow * extra.voice_gain
    at, areas = (-1, np.zeros(0)) if branch is None else (int(branch[0]), np.asarray(branch[1], dtype=float))
    p_noise, k_noise = (np.zeros(len(source)), np.full(len(source), -1, np.int64)) if noise is None else noise
    return _line(np.ascontiguousarray(frame_areas, dtype=float), index.astype(float), flow,
                 glottal_reflection, rho, c, float(fs_internal), section_loss, at, areas,
                 np.ascontiguousarray(p_noise, dtype=float), np.ascontiguousarray(k_noise, dtype=np.int64),
                 *((0.0, 0.0, 0.0) if walls is None else tuple(float(v) for v in walls)),
                 *_extra_arrays(extra, len(source), frame_areas.shape[1], at))
