"""The sound of a spoken course with every source: the glottis, the port and the lungs beside the area
functions; the air in time (:mod:`.airflow`), the voice following it, aspiration, frication and bursts,
the nasal branch and the walls' voice bar on the line (:mod:`.synthesis`); docs/modelling.md, "Sources"."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .. import units
from .aerodynamics import flow, glottal_noise_rms, noise_rms, reynolds, voice_gain
from .airflow import airflow, cavities, line_cavities, outlet
from .model import tract_of
from .nasal import nasal_line
from .resample import half_rate
from .synthesis import Extra, noise_samples, sections_for, side_branch, synthesize
from .tube import Tube
from .voice import Audio, frame_areas, source_for


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
    expansion_cm3: np.ndarray | None = None  # the cavity's active enlargement (cm^3), none if not given


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


def _air(areas: np.ndarray, index: np.ndarray, step_s: float, section_cm: float, narrowest_cm2: np.ndarray,
         larynx: Larynx, ac) -> _Air:
    """The cavity behind the line's narrowest place and its air, step by step (:mod:`.airflow`), or with
    ``ac.sources.bursts`` off, the quasi-steady flow of the lungs' pressure through the glottis and the
    constriction in series.  The constriction's area is each frame's own narrowest (``narrowest_cm2``,
    between frames linear): the line's sections, 0.4 cm long, sample a short channel at their centres and
    would widen it."""
    frames = np.arange(len(narrowest_cm2))
    cav = line_cavities(areas, section_cm, index)
    cav = replace(cav, area_cm2=np.interp(index, frames, narrowest_cm2))
    glottis = np.interp(index, frames, larynx.glottis_cm2)
    port = np.interp(index, frames, larynx.port_cm2)
    nose = _nose_cm2(port, ac, cav.at_cm <= larynx.port_at_cm)
    if ac.sources.bursts:
        grow = 0.0
        if larynx.expansion_cm3 is not None and len(index) > 1:
            grow = np.gradient(np.interp(index, frames, larynx.expansion_cm3), step_s)
        a = airflow(step_s * np.arange(len(index)), larynx.lung_pressure, glottis, cav.area_cm2, nose,
                    cav.volume_cm3, cav.wall_cm2, ac, grow)
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
    air = _air(areas, index[::stride], stride / fs, mean_length / n, np.asarray(areas_cm2, float).min(axis=1), larynx,
               ac)
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
