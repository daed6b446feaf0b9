"""Measures of a sound over time intervals: its level in a frequency band, in dB (re full scale)."""

from __future__ import annotations

import numpy as np


def band_level_db(samples: np.ndarray, rate_hz: int, t0_s: float, t1_s: float, lo_hz: float = 0.0,
                  hi_hz: float | None = None) -> float:
    """The mean power in [lo_hz, hi_hz) of the samples in [t0_s, t1_s), dB re a full-scale sine's."""
    a, b = int(round(t0_s * rate_hz)), int(round(t1_s * rate_hz))
    x = np.asarray(samples[max(a, 0):max(b, a + 1)], float)
    if len(x) < 16:
        return float("nan")
    spec = np.abs(np.fft.rfft(x * np.hanning(len(x)))) ** 2
    f = np.fft.rfftfreq(len(x), 1.0 / rate_hz)
    keep = (f >= lo_hz) & (f < (hi_hz if hi_hz is not None else np.inf))
    power = float(spec[keep].sum()) / (np.sum(np.hanning(len(x)) ** 2) * len(x)) * 2.0
    return 10.0 * np.log10(max(power, 1e-20) / 0.5)


def band_power_db(x: np.ndarray, rate: int, t0: float, t1: float, lo: float = 0.0, hi: float | None = None) -> float:
    """As :func:`band_level_db`, but every instant of [t0, t1) weighed alike (as Praat's intensity): all of it a
    plain mean square, a band from Welch's averaged periodogram (little leakage); for intervals that hold a
    closure and a release, where a Hann window over the whole would weigh the middle most."""
    a, b = max(int(round(t0 * rate)), 0), int(round(t1 * rate))
    seg = np.asarray(x[a:max(b, a + 1)], float)
    if len(seg) < 16:
        return float("nan")
    if lo <= 0 and hi is None:
        power = float(np.mean(seg ** 2))
    else:
        from scipy.signal import welch  # here: scipy.signal takes 0.5 s to import, and speaking needs it not

        f, pxx = welch(seg, rate, nperseg=min(512, len(seg)), noverlap=None, detrend=False)
        keep = (f >= lo) & (f < (hi if hi is not None else np.inf))
        power = float(np.sum(pxx[keep]) * (f[1] - f[0]))
    return 10.0 * np.log10(max(power, 1e-30) / 0.5)


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, end) index pairs of the True runs of a boolean array (end exclusive)."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    d = np.diff(m.astype(int))
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))
