"""Stage ``synthesize``: a WAV file from a tube held for a duration, or from the frames of a vocal-tract file
(areas interpolated sample by sample), voiced by the LF source with optional aspiration noise."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import Field
from scipy.io import wavfile

from ..acoustics.model import tract_of
from ..acoustics.resample import half_rate
from ..acoustics.source import lf_flow_derivative
from ..acoustics.synthesis import noise_samples, resample_tube, sections_for, side_branch, synthesize
from ..acoustics.tube import Tube, read_tube_csv
from ..config import Config, load_config
from ..errors import ArticError
from ..io.store import atomic_path
from ..validation import F0Hz, NonNegative, Strict, check_number, read_csv
from .base import Stage

STAGE = Stage(name="synthesize", module=__name__, sections=("acoustics",), kind="audio",
              hint="rerun 'artic synthesize'")
MAX_DURATION_S = 60.0


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


def compute(tube: Tube, cfg: Config, duration_s: float, f0_hz: float | None = 110.0,
            contour: list[tuple[float, float]] | None = None, amplitude=None, aspiration: float = 0.0) -> Audio:
    """A tube held for ``duration_s``."""
    return compute_frames(tube.length_cm[None], tube.area_cm2[None], np.array([0.0]), cfg, duration_s, f0_hz,
                          contour, amplitude, aspiration)


def compute_frames(lengths_cm: np.ndarray, areas_cm2: np.ndarray, times_s: np.ndarray, cfg: Config,
                   duration_s: float, f0_hz: float | None = 110.0, contour=None, amplitude=None,
                   aspiration: float = 0.0, flow_peak_cm3_s: float | None = None, noise=None) -> Audio:
    """Area functions (frames x sections, glottis first) at ``times_s``, interpolated at the line's rate; the
    line's sections are cut from the frames' mean length (each frame resampled over its own length).
    ``noise``: (RMS dyn/cm^2 (F,), place as a fraction of the length from the glottis (F,), seed), a turbulence
    source per frame, with the
    voice's flow peak ``flow_peak_cm3_s`` setting their relative level."""
    ac = STAGE.view(cfg).acoustics
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


def write(path: Path | str, audio: Audio) -> Path:
    """16-bit PCM WAV, written through a temporary file and a rename."""
    path = Path(path)
    pcm = np.round(np.clip(audio.samples, -1, 1) * 32767).astype(np.int16)
    with atomic_path(path, ".wav") as tmp:
        wavfile.write(tmp, audio.sample_rate_hz, pcm)
    return path


def read_wav(path: Path | str) -> tuple[np.ndarray, int]:
    """Samples (float, -1..1, the first channel) and the rate of a WAV file; a missing or damaged file is
    one error naming the fix."""
    path = Path(path)
    if not path.is_file():
        raise ArticError(f"WAV file not found: {path}; give an existing file (rerun 'artic synthesize')")
    try:
        rate, data = wavfile.read(path)
    except (ValueError, OSError, EOFError):
        raise ArticError(f"{path} is not a readable WAV file (corrupted or truncated); rerun 'artic synthesize'") from None
    data = np.asarray(data)
    if data.ndim > 1:
        data = data[:, 0]
    scale = float(np.iinfo(data.dtype).max) if np.issubdtype(data.dtype, np.integer) else 1.0
    return data.astype(float) / scale, int(rate)


class F0Point(Strict):
    time_s: NonNegative
    f0_hz: F0Hz


class GainPoint(Strict):
    time_s: NonNegative
    amplitude: Annotated[float, Field(ge=0, le=10, allow_inf_nan=False)]


def read_amplitude_contour(path: Path | str) -> list[tuple[float, float]]:
    """A CSV ``time_s,amplitude`` (times ascending, gains 0-10; 1 = the voice as is)."""
    hint = "give a CSV with header time_s,amplitude, times ascending, amplitudes 0-10"
    out = [(p.time_s, p.amplitude) for p in read_csv(path, ["time_s", "amplitude"], GainPoint, "amplitude contour",
                                                      hint)]
    if not out or any(b[0] <= a[0] for a, b in zip(out, out[1:])):
        raise ArticError(f"{path}: needs at least one point and ascending times; {hint}")
    return out


def read_f0_contour(path: Path | str) -> list[tuple[float, float]]:
    """A CSV ``time_s,f0_hz`` (times ascending, F0 50-500 Hz)."""
    hint = "give a CSV with header time_s,f0_hz, times ascending, F0 50-500 Hz"
    out = [(p.time_s, p.f0_hz) for p in read_csv(path, ["time_s", "f0_hz"], F0Point, "F0 contour", hint)]
    if not out or any(b[0] <= a[0] for a, b in zip(out, out[1:])):
        raise ArticError(f"{path}: needs at least one point and ascending times; {hint}")
    return out


def _check_out(out: Path | str) -> Path:
    out = Path(out)
    if out.suffix.lower() != ".wav":
        raise ArticError(f"--out {out}: give a .wav file name")
    if not out.parent.is_dir():
        raise ArticError(f"--out {out}: the folder {out.parent} does not exist; create it or give another path")
    return out


def _voice_inputs(out, duration_s, f0_hz, f0_contour, amplitude_contour, aspiration):
    """The output path and the voice's options, checked; the contour files read: (out, f0 points, gains)."""
    check_number("--duration", duration_s, gt=0, le=MAX_DURATION_S, unit="s")
    if f0_contour is None:
        check_number("--f0", f0_hz, ge=50, le=500, unit="Hz")
    check_number("--aspiration", aspiration, ge=0, le=10)
    out = _check_out(out)
    contour = read_f0_contour(f0_contour) if f0_contour is not None else None
    amp = read_amplitude_contour(amplitude_contour) if amplitude_contour is not None else None
    return out, contour, amp


def synthesize_tube(tube: Path | str, out: Path | str, duration_s: float, f0_hz: float | None = 110.0,
                    f0_contour: Path | str | None = None, config: Path | str | None = None,
                    amplitude_contour: Path | str | None = None, aspiration: float = 0.0) -> Audio:
    out, contour, amp = _voice_inputs(out, duration_s, f0_hz, f0_contour, amplitude_contour, aspiration)
    cfg = load_config(config)
    t = read_tube_csv(tube)
    audio = compute(t, cfg, duration_s, f0_hz, contour, amp, aspiration)
    write(out, audio)
    return audio


def solution_tube(path: Path | str) -> Tube:
    """The simulated area function a solve-target answer records (refined, else verified)."""
    from ..config import read_yaml

    doc = read_yaml(path, "solution file")
    if not isinstance(doc, dict) or not ("chosen" in doc or "unreachable" in doc):
        raise ArticError(f"{path} is not a solve-target answer; run 'artic solve-target' first")
    for key in ("refined", "verified"):
        af = (doc.get(key) or {}).get("area_function")
        if af:
            try:
                lengths = np.asarray(af["length_cm"], dtype=float)
                areas = np.asarray(af["area_cm2"], dtype=float)
            except (KeyError, TypeError, ValueError):
                break
            if lengths.shape != areas.shape or lengths.ndim != 1 or not len(lengths):
                break
            for k, (l, a) in enumerate(zip(lengths, areas)):
                check_number(f"{path}: {key}.area_function.length_cm[{k}]", float(l), gt=0, le=5, unit="cm")
                check_number(f"{path}: {key}.area_function.area_cm2[{k}]", float(a), ge=0, le=50, unit="cm^2")
            return Tube(lengths, areas)
    raise ArticError(f"{path} records no simulated area function; solve the target with --verify or --refine "
                     "(an acoustic target)")


def synthesize_solution(solution: Path | str, out: Path | str, duration_s: float, f0_hz: float | None = 110.0,
                        f0_contour: Path | str | None = None, config: Path | str | None = None,
                        amplitude_contour: Path | str | None = None, aspiration: float = 0.0) -> Audio:
    """The sound of a solved vowel: its simulated area function held for ``duration_s``."""
    out, contour, amp = _voice_inputs(out, duration_s, f0_hz, f0_contour, amplitude_contour, aspiration)
    cfg = load_config(config)
    audio = compute(solution_tube(solution), cfg, duration_s, f0_hz, contour, amp, aspiration)
    write(out, audio)
    return audio


def synthesize_tracts(tracts: Path | str, out: Path | str, f0_hz: float | None = 110.0,
                      f0_contour: Path | str | None = None, config: Path | str | None = None,
                      amplitude_contour: Path | str | None = None, aspiration: float = 0.0,
                      duration_s: float | None = None) -> Audio:
    """The sound of a vocal-tract file's frames (one frame: held for ``duration_s``, default 1 s)."""
    from . import vocal_tract as vt_stage

    out, contour, amp = _voice_inputs(out, duration_s, f0_hz, f0_contour, amplitude_contour, aspiration)
    cfg = load_config(config)
    t = vt_stage.read(tracts)
    span = float(t.time_s[-1] - t.time_s[0])
    if duration_s is None:
        duration_s = span if t.n_frames > 1 and span > 0 else 1.0
    audio = compute_frames(t.af.length_cm, t.af.area_cm2, t.time_s, cfg, duration_s, f0_hz, contour, amp, aspiration)
    write(out, audio)
    return audio
