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

import numpy as np

from ..jit import njit

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
def _lips_reflect(a_l, f_now, last_f, last_b, rho, c, fs):  # pragma: no cover - compiled
    """The wave reflected at the lips: the radiation load, a parallel R-L (Flanagan), by the bilinear
    transform of its reflection filter, from the forward wave now and the last sample's two waves."""
    pi = np.pi
    zc = rho * c / a_l
    r_rad = 128.0 * rho * c / (9.0 * pi * pi * a_l)
    k_rad = 2.0 * fs * 8.0 * rho / (3.0 * pi * np.sqrt(pi * a_l))
    b0 = k_rad * (r_rad - zc) - zc * r_rad
    b1 = -k_rad * (r_rad - zc) - zc * r_rad
    a0 = k_rad * (r_rad + zc) + zc * r_rad
    a1 = -k_rad * (r_rad + zc) + zc * r_rad
    return (b0 * f_now + b1 * last_f - a1 * last_b) / a0


@njit(cache=True)
def _line(frame_areas, frame_index, source, glottal_reflection, rho, c, fs, loss, branch_at,
          branch_areas, noise, noise_at, wall_m, wall_r, wall_k):  # pragma: no cover - compiled
    n_samples = source.shape[0]
    n = frame_areas.shape[1]
    fwd = np.zeros(n)
    bwd = np.zeros(n)
    new_f = np.zeros(n)
    new_b = np.zeros(n)
    area = np.zeros(n)
    m = branch_areas.shape[0]
    bf = np.zeros(m)  # the side branch: waves away from its junction ...
    bb = np.zeros(m)  # ... and toward it
    new_bf = np.zeros(m)
    new_bb = np.zeros(m)
    out = np.zeros(n_samples)
    last_u = 0.0
    keep = 1.0 - loss
    last_f = 0.0
    last_b = 0.0
    pi = np.pi
    wall_x = np.zeros(n)  # each junction's wall patch: displacement (cm) and velocity (cm/s)
    wall_v = np.zeros(n)
    walls = wall_m > 0.0
    dt = 1.0 / fs
    dx = c / fs
    for s in range(n_samples):
        _areas_at(frame_areas, frame_index[s], area)
        new_f[0] = glottal_reflection * bwd[0] + source[s] / area[0]
        for j in range(n - 1):  # each junction's pressure p / (rho c) = f + b from the flows U = A (f - b) into it
            a_sum = area[j] + area[j + 1]
            into = 2.0 * (area[j] * fwd[j] + area[j + 1] * bwd[j + 1])
            if j == branch_at:  # three tubes meet: the side branch's flow joins
                a_sum += branch_areas[0]
                into += 2.0 * branch_areas[0] * bb[0]
            elif walls:  # less what the junction's wall patch takes; the wall's velocity and the pressure solved
                # together (backward Euler): stable for any area, a closure's slit included
                patch = 2.0 * np.sqrt(pi * 0.5 * a_sum) * dx
                wall_v[j] = ((wall_m / dt) * wall_v[j] + rho * c * into / a_sum - wall_k * wall_x[j]) / (
                    wall_m / dt + rho * c * patch / a_sum + wall_r + wall_k * dt)
                wall_x[j] += dt * wall_v[j]
                into -= patch * wall_v[j]
            pj = into / a_sum
            new_f[j + 1] = pj - bwd[j + 1]
            new_b[j] = pj - fwd[j]
            if j == branch_at:
                new_bf[0] = pj - bb[0]
        k_n = noise_at[s]
        if 0 <= k_n < n - 1:  # a series pressure source between sections k_n and k_n + 1: half each way
            half = 0.5 * noise[s] / (rho * c)
            new_f[k_n + 1] += half
            new_b[k_n] -= half
        if m > 0:
            _branch_step(branch_areas, bf, bb, new_bf, new_bb, keep)
        a_l = area[n - 1]
        new_b[n - 1] = _lips_reflect(a_l, fwd[n - 1], last_f, last_b, rho, c, fs)
        last_f = fwd[n - 1]
        last_b = new_b[n - 1]
        u = area[n - 1] * (fwd[n - 1] - new_b[n - 1]) if a_l > 2e-4 else 0.0  # closed lips radiate nothing
        out[s] = u - last_u
        last_u = u
        for j in range(n):
            if area[j] <= MIN_AREA_CM2:  # a closed section holds no air column: no wave stays trapped in it to
                fwd[j] = 0.0  # leave as a click when it opens (its flow A (f - b) would jump with its area)
                bwd[j] = 0.0
            else:
                fwd[j] = keep * new_f[j]
                bwd[j] = keep * new_b[j]
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


def synthesize(frame_areas: np.ndarray, frame_times_s: np.ndarray, source: np.ndarray, fs_internal: float,
               glottal_reflection: float = 0.97, section_loss: float = 5e-4, rho: float = 1.14e-3,
               c: float = 35000.0, branch: tuple[int, np.ndarray] | None = None, flow_peak_cm3_s: float | None = None,
               noise: tuple[np.ndarray, np.ndarray] | None = None,
               walls: tuple[float, float, float] | None = None) -> np.ndarray:
    """The radiated sound at ``fs_internal`` for areas (frames x N equal sections) at ``frame_times_s`` and a
    source (flow derivative per internal sample); ``branch``: a closed side tube, (the section after which it
    joins, its areas), from :func:`side_branch`; ``flow_peak_cm3_s``: the glottal flow's peak (else arbitrary
    units); ``noise``: a pressure source per internal sample (dyn/cm^2) and the section after which it acts (-1:
    none), on the same scale as a flow of ``flow_peak_cm3_s``; ``walls``: (mass g/cm^2, resistance dyn s/cm^3,
    stiffness dyn/cm^3) per unit area of yielding wall (None: rigid)."""
    t = np.arange(len(source)) / fs_internal
    index = np.interp(t, frame_times_s, np.arange(len(frame_times_s))) if len(frame_times_s) > 1 else np.zeros(len(t))
    # the source drives flow: integrate its derivative (leaky, so no drift) before it enters the line
    flow = _leaky_integral(np.ascontiguousarray(source, dtype=float), 1.0 / fs_internal, 0.999)
    peak = float(np.max(np.abs(flow))) if len(flow) else 0.0
    flow = flow * (flow_peak_cm3_s / peak if flow_peak_cm3_s is not None and peak > 0 else 1e4)
    at, areas = (-1, np.zeros(0)) if branch is None else (int(branch[0]), np.asarray(branch[1], dtype=float))
    p_noise, k_noise = (np.zeros(len(source)), np.full(len(source), -1, np.int64)) if noise is None else noise
    return _line(np.ascontiguousarray(frame_areas, dtype=float), index.astype(float), flow,
                 glottal_reflection, rho, c, float(fs_internal), section_loss, at, areas,
                 np.ascontiguousarray(p_noise, dtype=float), np.ascontiguousarray(k_noise, dtype=np.int64),
                 *((0.0, 0.0, 0.0) if walls is None else tuple(float(v) for v in walls)))
