"""Voicing an area function: the LF source with its contours and aspiration, the time-varying line with its
side branch and noise sources, at the audio rate."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
