"""Formants and bandwidths from a transfer function: peaks on a grid, each refined by zooming in.

``magnitude(f_hz)`` evaluates |H| at any frequencies (vectorised).  A peak is a local maximum of the grid
with at least 1 dB of prominence; it is refined by three rounds of 8-point zooms around the maximum (the
bracket shrinks 512-fold: sub-hertz on a 5-Hz grid), and its bandwidth is the distance between the two
half-power (-3 dB) points, each found the same way inside its grid cell.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

ROUNDS = 3
POINTS = 8


def prominent_peaks(y: np.ndarray, prominence: float) -> np.ndarray:
    """Indices of the local maxima of ``y`` whose prominence is at least ``prominence``, ascending: what
    ``scipy.signal.find_peaks(y, prominence=...)[0]`` gives (a plateau's peak is its middle sample, rounded
    down; the prominence is the height above the higher of the two lowest points reached before a higher
    sample or the end on either side).  Not imported from there: importing scipy.signal takes 2.6 s (SciPy
    1.17), and every command that computes formants would pay it."""
    y = np.asarray(y, dtype=float)
    n = len(y)
    if n < 3:
        return np.zeros(0, dtype=np.int64)
    # plateaus as runs of equal samples: a run is a peak when both neighbouring runs are lower
    start = np.flatnonzero(np.r_[True, y[1:] != y[:-1]])
    end = np.r_[start[1:], n] - 1
    value = y[start]
    inner = np.arange(1, len(start) - 1)
    top = inner[(value[inner] > value[inner - 1]) & (value[inner] > value[inner + 1])]
    peaks = (start[top] + end[top]) // 2
    out = []
    for p in peaks:
        higher_left = np.flatnonzero(y[:p] > y[p])
        lo = higher_left[-1] + 1 if len(higher_left) else 0
        higher_right = np.flatnonzero(y[p + 1:] > y[p])
        hi = p + 1 + higher_right[0] if len(higher_right) else n
        base = max(y[lo:p + 1].min(), y[p:hi].min())
        if y[p] - base >= prominence:
            out.append(p)
    return np.array(out, dtype=np.int64)


def _zoom_peaks(magnitude: Callable[[np.ndarray], np.ndarray], centre: np.ndarray, half: float,
                rounds: int = ROUNDS) -> tuple[np.ndarray, np.ndarray]:
    """Each peak's frequency and its height (|H|, from the parabola through the last three points)."""
    lo, hi = centre - half, centre + half
    for _ in range(rounds):
        grid = np.linspace(lo, hi, POINTS + 1, axis=-1)  # (P, 9)
        m = magnitude(grid.ravel()).reshape(grid.shape)
        k = np.clip(np.argmax(m, axis=1), 1, POINTS - 1)
        rows = np.arange(len(grid))
        lo, hi = grid[rows, k - 1], grid[rows, k + 1]
    grid = np.linspace(lo, hi, 3, axis=-1)
    m = 20 * np.log10(magnitude(grid.ravel()).reshape(grid.shape))
    a, b, c = m[:, 0], m[:, 1], m[:, 2]
    den = a - 2 * b + c
    safe = np.where(den < 0, den, -1.0)
    shift = np.where(den < 0, 0.5 * (a - c) / safe, 0.0)
    top_db = np.where(den < 0, b - 0.125 * (a - c) ** 2 / safe, b)
    return grid[:, 1] + shift * (grid[:, 2] - grid[:, 1]), 10.0 ** (top_db / 20.0)


def _crossing(magnitude, lo: np.ndarray, hi: np.ndarray, level: np.ndarray) -> np.ndarray:
    """Where |H| crosses ``level`` inside [lo, hi] (|H| - level changes sign there)."""
    for _ in range(ROUNDS):
        grid = np.linspace(lo, hi, POINTS + 1, axis=-1)
        d = magnitude(grid.ravel()).reshape(grid.shape) - level[:, None]
        s = np.signbit(d)
        change = s[:, 1:] != s[:, :1]
        k = np.where(change.any(axis=1), np.argmax(change, axis=1), POINTS - 1)
        rows = np.arange(len(grid))
        lo, hi = grid[rows, k], grid[rows, k + 1]
    return 0.5 * (lo + hi)


def formants(magnitude: Callable[[np.ndarray], np.ndarray], f_max_hz: float = 5500.0, step_hz: float = 5.0,
             count: int = 5, f_min_hz: float = 50.0, lossless: bool = False,
             bandwidths: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The first ``count`` formants (Hz, ascending) and their -3 dB bandwidths (Hz); NaN where there are
    fewer peaks below ``f_max_hz``.  ``lossless``: the peaks are poles on the real axis (bandwidth 0), only
    their frequencies are refined.  ``bandwidths=False``: the frequencies only (bandwidths NaN; a third less
    work)."""
    f = np.arange(f_min_hz, f_max_hz + step_hz, step_hz)
    m = magnitude(f)
    db = 20 * np.log10(np.maximum(m, 1e-300))
    peaks = prominent_peaks(db, 1.0)
    peaks = peaks[:count]
    freq = np.full(count, np.nan)
    bw = np.full(count, np.nan)
    if len(peaks) == 0:
        return freq, bw
    # a lossy peak is smooth: two zoom rounds leave a bracket of step / 16 where the parabola is exact to far
    # below a hertz; a lossless one (a pole on the axis) gets a third
    fp, top = _zoom_peaks(magnitude, f[peaks], step_hz, ROUNDS if lossless else ROUNDS - 1)
    if lossless:
        freq[: len(peaks)] = fp
        bw[: len(peaks)] = 0.0
        return freq, bw
    if not bandwidths:
        freq[: len(peaks)] = fp
        return freq, bw
    half = top / np.sqrt(2.0)
    left = np.empty(len(peaks))
    right = np.empty(len(peaks))
    for j, p in enumerate(peaks):  # the grid cells where |H| first falls below half power on each side
        below = np.flatnonzero(m[:p] < half[j])
        left[j] = f[below[-1]] if len(below) else np.nan
        above = np.flatnonzero(m[p + 1:] < half[j])
        right[j] = f[p + 1 + above[0]] if len(above) else np.nan
    ok_l, ok_r = np.isfinite(left), np.isfinite(right)
    lx = np.full(len(peaks), np.nan)
    rx = np.full(len(peaks), np.nan)
    if ok_l.any() or ok_r.any():  # both sides' crossings in one search (one evaluation per round)
        lo = np.concatenate([left[ok_l], np.maximum(right[ok_r] - step_hz, fp[ok_r])])
        hi = np.concatenate([np.minimum(left[ok_l] + step_hz, fp[ok_l]), right[ok_r]])
        x = _crossing(magnitude, lo, hi, np.concatenate([half[ok_l], half[ok_r]]))
        lx[ok_l], rx[ok_r] = x[:ok_l.sum()], x[ok_l.sum():]
    width = np.where(ok_l & ok_r, rx - lx, np.where(ok_l, 2 * (fp - lx), 2 * (rx - fp)))
    freq[: len(peaks)] = fp
    bw[: len(peaks)] = width
    return freq, bw
