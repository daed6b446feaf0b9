"""Voicing an area function: the LF source with its contours and aspiration, the time-varying line with its
side branch and noise sources, at the audio rate."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import units
from .model import tract_of
from .resample import half_rate
from .source import lf_flow_derivative
from .synthesis import noise_samples, resample_tube, sections_for, side_branch, synthesize
from .tube import Tube


@dataclass
class Audio:
    samples: np.ndarray  # float, peak 0.9 (-1 dBFS)
    sample_rate_hz: int


def f0_track(times_s: np.ndarray, f0: float | None, contour: list[tuple[float, float]] | None) -> np.ndarray:
    if contour:
        t, f = np.array(contour).T
        return np.interp(times_s, t, f)
    return np.full(len(times_s), float(f0))


def frame_areas(lengths_cm: np.ndarray, areas_cm2: np.ndarray, n: int) -> np.ndarray:
    """(F, n) areas at n equal sections of each frame's own length (frames x sections in)."""
    return np.stack([resample_tube(lengths_cm[k], areas_cm2[k], n) for k in range(len(areas_cm2))])


def source_for(t_s: np.ndarray, fs: float, sy, f0_hz: float | None, contour, amplitude=None,
               aspiration: float = 0.0, seed: int = 0) -> np.ndarray:
    """The glottal flow derivative with 20-ms fades at both ends, an amplitude contour ((time_s, gain)
    points) and aspiration: white noise of ``aspiration`` times the voice's RMS, gated by the glottis's
    opening phase (noise while air flows)."""
    src = lf_flow_derivative(f0_track(t_s, f0_hz, contour), fs, sy.lf_tp, sy.lf_te, sy.lf_ta)
    if aspiration > 0:
        rms = float(np.sqrt(np.mean(src ** 2))) if len(src) else 0.0
        gate = (src != 0).astype(float) * 0.5 + 0.5 * (np.abs(src) > 0.05)
        src = src + aspiration * rms * gate * np.random.default_rng(seed).standard_normal(len(src))
    gain = np.ones(len(t_s))
    if amplitude:
        ta, ga = np.array(amplitude).T
        gain = np.interp(t_s, ta, ga)
    fade = np.minimum(1.0, np.minimum(t_s, t_s[-1] - t_s) / 0.02) if len(t_s) else t_s
    return src * gain * fade


def synthesize_frames(lengths_cm: np.ndarray, areas_cm2: np.ndarray, times_s: np.ndarray, ac,
                   duration_s: float, f0_hz: float | None = 110.0, contour=None, amplitude=None,
                   aspiration: float = 0.0, flow_peak_cm3_s: float | None = None, noise=None) -> Audio:
    """Area functions (frames x sections, glottis first) at ``times_s``, interpolated at the line's rate; the
    line's sections are cut from the frames' mean length (each frame resampled over its own length).
    ``noise``: (RMS dyn/cm^2 (F,), place as a fraction of the length from the glottis (F,), seed), a turbulence
    source per frame, with the voice's flow peak ``flow_peak_cm3_s`` setting their relative level.  ``ac``:
    the config's ``acoustics`` section."""
    sy = ac.synthesis
    fs = 2 * sy.sample_rate_hz  # the line runs at twice the audio rate
    n = sections_for(float(np.mean(lengths_cm.sum(axis=1))), ac.sound_speed_cm_s, fs)
    areas = frame_areas(lengths_cm, areas_cm2, n)
    t = np.arange(int(round(duration_s * fs))) / fs
    src = source_for(t, fs, sy, f0_hz, contour, amplitude, aspiration)
    branch = None
    pf = ac.piriform_fossa
    mean_length = float(np.mean(lengths_cm.sum(axis=1)))
    if pf.enabled and mean_length > pf.from_glottis_cm:  # the transfer function's fossa (acoustics/model.py)
        fossa = tract_of(Tube(np.array([mean_length]), np.array([1.0])), ac, velum_area_cm2=0.0).branches[0].tube
        branch = side_branch(pf.from_glottis_cm, mean_length, n, fossa.length_cm, fossa.area_cm2,
                             ac.sound_speed_cm_s, fs)
    pn = None
    if noise is not None:
        rms, at_fraction, seed = noise
        pn = noise_samples(np.asarray(times_s, float), rms, at_fraction, t, n, seed)
    y = synthesize(areas, np.asarray(times_s, float) - float(times_s[0]), src, fs, sy.glottal_reflection,
                   sy.section_loss, ac.air_density_g_cm3, ac.sound_speed_cm_s, branch, flow_peak_cm3_s, pn,
                   (ac.wall_mass_g_cm2, ac.wall_resistance_dyn_s_cm3, ac.wall_stiffness_dyn_cm3)
                   if ac.yielding_walls else None)
    y = half_rate(y)
    peak = float(np.max(np.abs(y))) if len(y) else 0.0
    return Audio(0.9 * y / peak if peak > 0 else y, sy.sample_rate_hz)


def synthesize_tube(tube: Tube, ac, duration_s: float, f0_hz: float | None = 110.0,
            contour: list[tuple[float, float]] | None = None, amplitude=None, aspiration: float = 0.0) -> Audio:
    """A tube held for ``duration_s`` (``ac``: the config's ``acoustics`` section)."""
    return synthesize_frames(tube.length_cm[None], tube.area_cm2[None], np.array([0.0]), ac, duration_s, f0_hz,
                             contour, amplitude, aspiration)


@dataclass
class Larynx:
    """What a spoken course gives the synthesis beyond its areas, per frame: the glottis's and the port's
    areas (cm^2), where the port opens (cm from the glottis), the lungs' pressure (dyn/cm^2), the voicing
    switch (0-1; used when the aerodynamic voicing is off) and the frication noise's settings
    (the config's ``speech.noise``)."""

    glottis_cm2: np.ndarray
    port_cm2: np.ndarray
    port_at_cm: float
    lung_pressure: float
    voicing: np.ndarray
    noise: object
    voiced_cm2: float
    step_s: float = 0.0  # the air's time step (set by the synthesis)


@dataclass
class Sounded:
    audio: Audio
    air: dict[str, np.ndarray]  # per frame: the cavity's pressure, the flows, the voice's gain, the noise levels


def _nose_cm2(port: np.ndarray, ac, behind_port: np.ndarray) -> np.ndarray:
    """The nose's outlet for the air: the port and the nasal valve (the nasal tract's narrowest area) in
    series, open where the narrowest place is in front of the port."""
    if not (ac.nasal.enabled and ac.sources.nasal_branch):
        return np.zeros(len(behind_port))
    valve = float(np.min(ac.nasal.areas_cm2))
    p = np.maximum(np.asarray(port, float), 0.0)
    series = p * valve / np.sqrt(p * p + valve * valve + 1e-30)
    return np.where(behind_port, 0.0, series)


@dataclass
class _Air:
    """The air at the line's air steps (every ``stride`` samples)."""

    pressure: np.ndarray
    glottal: np.ndarray
    constriction: np.ndarray
    nasal: np.ndarray
    glottis_cm2: np.ndarray
    cavity: object  # airflow.Cavity at the steps
    nose_cm2: np.ndarray


def _air(areas: np.ndarray, index: np.ndarray, section_cm: float, narrowest_cm2: np.ndarray, larynx: Larynx,
         ac) -> _Air:
    """The cavity behind the line's narrowest place and its air, step by step (:mod:`.airflow`), or with
    ``ac.sources.bursts`` off, the quasi-steady flow of the lungs' pressure through the glottis and the
    constriction in series.  The constriction's area is each frame's own narrowest (``narrowest_cm2``,
    between frames linear): the line's sections, 0.4 cm long, sample a short channel at their centres and
    would widen it."""
    from dataclasses import replace

    from .aerodynamics import flow
    from .airflow import airflow, line_cavities

    frames = np.arange(len(narrowest_cm2))
    cav = line_cavities(areas, section_cm, index)
    cav = replace(cav, area_cm2=np.interp(index, frames, narrowest_cm2))
    glottis = np.interp(index, frames, larynx.glottis_cm2)
    port = np.interp(index, frames, larynx.port_cm2)
    nose = _nose_cm2(port, ac, cav.at_cm <= larynx.port_at_cm)
    if ac.sources.bursts:
        a = airflow(larynx.step_s * np.arange(len(index)), larynx.lung_pressure, glottis, cav.area_cm2, nose,
                    cav.volume_cm3, cav.wall_cm2, ac)
        return _Air(a.oral_pressure, a.glottal_flow, a.constriction_flow, a.nasal_flow, glottis, cav, nose)
    u = flow(larynx.lung_pressure, glottis, cav.area_cm2, ac.air_density_g_cm3)
    drop = 0.5 * ac.air_density_g_cm3 * (u / np.maximum(cav.area_cm2, 1e-6)) ** 2
    return _Air(drop, u, u, np.zeros(len(u)), glottis, cav, nose)


def synthesize_speech(lengths_cm: np.ndarray, areas_cm2: np.ndarray, times_s: np.ndarray, ac, duration_s: float,
                      larynx: Larynx, f0_hz: float | None = 110.0, contour=None,
                      flow_peak_cm3_s: float | None = None) -> Sounded:
    """The sound of a spoken course: the line with the nasal branch, the voice following the air in time,
    aspiration at the glottis, frication and bursts at the narrowest place, the walls' voice bar (each as
    ``ac.sources`` switches it)."""
    from .aerodynamics import glottal_noise_rms, noise_rms, reynolds, voice_gain
    from .airflow import outlet
    from .nasal import nasal_line
    from .synthesis import Extra, synthesize

    sy, so, nz = ac.synthesis, ac.sources, larynx.noise
    rho, mu = ac.air_density_g_cm3, ac.air_viscosity_dyn_s_cm2
    fs = 2 * sy.sample_rate_hz
    mean_length = float(np.mean(lengths_cm.sum(axis=1)))
    n = sections_for(mean_length, ac.sound_speed_cm_s, fs)
    areas = frame_areas(lengths_cm, areas_cm2, n)
    times = np.asarray(times_s, float) - float(times_s[0])
    t = np.arange(int(round(duration_s * fs))) / fs
    index = np.interp(t, times, np.arange(len(times))) if len(times) > 1 else np.zeros(len(t))
    stride = AIR_STRIDE
    larynx.step_s = stride / fs
    air = _air(areas, index[::stride], mean_length / n, np.asarray(areas_cm2, float).min(axis=1), larynx, ac)
    steps = np.arange(0, len(t), stride)
    up = lambda v: np.interp(np.arange(len(t)), steps, v)  # noqa: E731 - the air's steps to every sample
    cav = air.cavity
    frication = noise_rms(air.constriction, cav.area_cm2, rho, mu, nz.critical_reynolds, nz.gain) \
        if nz.enabled else np.zeros(len(steps))
    asp = glottal_noise_rms(air.glottal, air.glottis_cm2, rho, mu, nz.critical_reynolds, so.aspiration_coefficient) \
        if so.aspiration else np.zeros(len(steps))
    if so.aerodynamic_voicing:
        gain = voice_gain(larynx.lung_pressure - air.pressure, larynx.lung_pressure, air.glottis_cm2,
                          units.kpa_to_cgs(so.phonation_threshold_kpa), larynx.voiced_cm2, so.voicing_stops_at_cm2)
    else:
        gain = np.interp(t[steps], times, larynx.voicing)
    # the jet's noise just past the narrowest place, each frame's own (the line's sections could put it behind
    # a short channel, where the constriction filters it away)
    from .airflow import cavities

    frame_cav = cavities(lengths_cm, areas_cm2)
    unit, place = noise_samples(times, np.ones(len(times)), frame_cav.at_cm / lengths_cm.sum(axis=1), t, n, nz.seed)
    p_noise = up(frication) * unit
    extra = Extra(voice_gain=up(gain), skin=1.0 if so.voice_bar and ac.yielding_walls else 0.0)
    if so.aspiration:
        extra.aspiration = up(asp) * np.random.default_rng(so.seed).standard_normal(len(t))
    if so.bursts:  # the cavity's discharge through the mouth (beyond what the glottis feeds it, less what leaves
        # by the nose; zero while its pressure holds or rises) leaves where the closure was
        extra.inject = up(np.maximum(air.constriction - np.maximum(air.glottal - air.nasal, 0.0), 0.0))
        extra.inject_at = np.repeat(outlet(cav.end, cav.area_cm2, BURST_BELOW_CM2), stride)[:len(t)]
    if so.nasal_branch and ac.nasal.enabled and np.any(np.asarray(larynx.port_cm2) > 0):
        junction = int(np.clip(round(larynx.port_at_cm / (mean_length / n)) - 1, 0, n - 2))
        extra.nasal = nasal_line(ac.nasal, junction, ac.sound_speed_cm_s / fs, rho, ac.sound_speed_cm_s)
        extra.frame_ports_cm2 = np.asarray(larynx.port_cm2, float)
    y = synthesize(areas, times, source_for(t, fs, sy, f0_hz, contour), fs, sy.glottal_reflection, sy.section_loss,
                   rho, ac.sound_speed_cm_s, _fossa(ac, mean_length, n, fs), flow_peak_cm3_s,
                   (p_noise, np.where(up(frication) > 0, place, -1)),
                   (ac.wall_mass_g_cm2, ac.wall_resistance_dyn_s_cm3, ac.wall_stiffness_dyn_cm3)
                   if ac.yielding_walls else None, extra)
    y = half_rate(y)
    peak = float(np.max(np.abs(y))) if len(y) else 0.0
    at_frames = lambda v: np.interp(times, t[steps], np.asarray(v, float))  # noqa: E731
    record = {"oral_pressure": at_frames(air.pressure), "glottal_flow": at_frames(air.glottal),
              "constriction_flow": at_frames(air.constriction), "nasal_flow": at_frames(air.nasal),
              "voice_gain": at_frames(gain), "aspiration_rms": at_frames(asp), "noise_rms": at_frames(frication),
              "reynolds": reynolds(at_frames(air.constriction), at_frames(cav.area_cm2), rho, mu),
              "noise_at": frame_cav.at_cm, "constriction": at_frames(cav.area_cm2),
              "nose_cm2": at_frames(air.nose_cm2)}
    return Sounded(Audio(0.9 * y / peak if peak > 0 else y, sy.sample_rate_hz), record)


AIR_STRIDE = 4  # the air's step: this many of the line's samples (22 kHz at the default rate)
BURST_BELOW_CM2 = 0.3  # a narrowest place under this is a constriction whose release is a burst


def _fossa(ac, mean_length: float, n: int, fs: float):
    """The piriform fossae as the line's closed side branch (the transfer function's, acoustics/model.py)."""
    pf = ac.piriform_fossa
    if not (pf.enabled and mean_length > pf.from_glottis_cm):
        return None
    fossa = tract_of(Tube(np.array([mean_length]), np.array([1.0])), ac, velum_area_cm2=0.0).branches[0].tube
    return side_branch(pf.from_glottis_cm, mean_length, n, fossa.length_cm, fossa.area_cm2, ac.sound_speed_cm_s, fs)
