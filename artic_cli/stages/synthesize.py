"""Stage ``synthesize``: a WAV file from a tube held for a duration, voiced by the LF source."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.io import wavfile
from scipy.signal import resample_poly

from ..acoustics.source import lf_flow_derivative
from ..acoustics.synthesis import resample_tube, sections_for, synthesize
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


def compute(tube: Tube, cfg: Config, duration_s: float, f0_hz: float | None = 110.0,
            contour: list[tuple[float, float]] | None = None) -> Audio:
    ac = STAGE.view(cfg).acoustics
    sy = ac.synthesis
    fs = 2 * sy.sample_rate_hz  # the line runs at twice the audio rate
    n = sections_for(tube.total_length_cm, ac.sound_speed_cm_s, fs)
    areas = resample_tube(tube.length_cm, tube.area_cm2, n)[None, :]
    t = np.arange(int(round(duration_s * fs))) / fs
    src = lf_flow_derivative(f0_track(t, f0_hz, contour), fs, sy.lf_tp, sy.lf_te, sy.lf_ta)
    ramp = np.minimum(1.0, np.minimum(t, t[-1] - t) / 0.02)  # 20-ms fades: no clicks at either end
    y = synthesize(areas, np.array([0.0]), src * ramp, fs, sy.glottal_reflection, sy.section_loss,
                   ac.air_density_g_cm3, ac.sound_speed_cm_s)
    y = resample_poly(y, 1, 2)
    peak = float(np.max(np.abs(y))) if len(y) else 0.0
    return Audio(0.9 * y / peak if peak > 0 else y, sy.sample_rate_hz)


def write(path: Path | str, audio: Audio) -> Path:
    """16-bit PCM WAV, written through a temporary file and a rename."""
    path = Path(path)
    pcm = np.round(np.clip(audio.samples, -1, 1) * 32767).astype(np.int16)
    with atomic_path(path, ".wav") as tmp:
        wavfile.write(tmp, audio.sample_rate_hz, pcm)
    return path


class F0Point(Strict):
    time_s: NonNegative
    f0_hz: F0Hz


def read_f0_contour(path: Path | str) -> list[tuple[float, float]]:
    """A CSV ``time_s,f0_hz`` (times ascending, F0 50-500 Hz)."""
    hint = "give a CSV with header time_s,f0_hz, times ascending, F0 50-500 Hz"
    out = [(p.time_s, p.f0_hz) for p in read_csv(path, ["time_s", "f0_hz"], F0Point, "F0 contour", hint)]
    if not out or any(b[0] <= a[0] for a, b in zip(out, out[1:])):
        raise ArticError(f"{path}: needs at least one point and ascending times; {hint}")
    return out


def synthesize_tube(tube: Path | str, out: Path | str, duration_s: float, f0_hz: float | None = 110.0,
                    f0_contour: Path | str | None = None, config: Path | str | None = None) -> Audio:
    check_number("--duration", duration_s, gt=0, le=MAX_DURATION_S, unit="s")
    if f0_contour is None:
        check_number("--f0", f0_hz, ge=50, le=500, unit="Hz")
    out = Path(out)
    if out.suffix.lower() != ".wav":
        raise ArticError(f"--out {out}: give a .wav file name")
    if not out.parent.is_dir():
        raise ArticError(f"--out {out}: the folder {out.parent} does not exist; create it or give another path")
    cfg = load_config(config)
    t = read_tube_csv(tube)
    contour = read_f0_contour(f0_contour) if f0_contour is not None else None
    audio = compute(t, cfg, duration_s, f0_hz, contour)
    write(out, audio)
    return audio
