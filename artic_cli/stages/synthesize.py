"""Stage ``synthesize``: a WAV file from a tube held for a duration, or from the frames of a vocal-tract file
(areas interpolated sample by sample), voiced by the LF source with optional aspiration noise."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import Field

from ..acoustics.tube import Tube, read_tube_csv
from ..acoustics.voice import Audio, synthesize_frames
from ..acoustics.voice import synthesize_tube as voice_tube
from ..config import Config, load_config
from ..errors import ArticError
from ..io.wav import write_wav
from ..validation import F0Hz, NonNegative, Strict, check_number, read_csv
from .base import Stage

STAGE = Stage(name="synthesize", module=__name__, sections=("acoustics",), kind="audio",
              hint="rerun 'artic synthesize'")
MAX_DURATION_S = 60.0


def compute(tube: Tube, cfg: Config, duration_s: float, f0_hz: float | None = 110.0,
            contour: list[tuple[float, float]] | None = None, amplitude=None, aspiration: float = 0.0) -> Audio:
    """A tube held for ``duration_s`` (:func:`artic_cli.acoustics.voice.synthesize_tube`)."""
    return voice_tube(tube, STAGE.view(cfg).acoustics, duration_s, f0_hz, contour, amplitude, aspiration)


def compute_frames(lengths_cm: np.ndarray, areas_cm2: np.ndarray, times_s: np.ndarray, cfg: Config,
                   duration_s: float, *args, **options) -> Audio:
    """Area functions in time (:func:`artic_cli.acoustics.voice.synthesize_frames`)."""
    return synthesize_frames(lengths_cm, areas_cm2, times_s, STAGE.view(cfg).acoustics, duration_s, *args, **options)


write = write_wav

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
