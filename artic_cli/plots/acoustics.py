"""The transfer function of a tube with its formants marked."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..acoustics.spectrogram import spectrogram
from .common import save_figure

CLOSURE_CM2 = 0.05  # frames narrower than this are shaded: the tract is (nearly) closed


def plot_transfer(result, frame: int, path: Path | str, title: str = "") -> Path:
    fig, ax = plt.subplots(figsize=(8, 4.5))
    f = result.frequency_hz
    ax.plot(f, result.transfer_db[frame], color="#2c3e50", lw=1.2, label="U_lips / U_glottis")
    for k, (fk, bk) in enumerate(zip(result.formants_hz[frame], result.bandwidths_hz[frame])):
        if np.isfinite(fk):
            ax.axvline(fk, color="#c0392b", lw=0.8, ls=":")
            ax.text(fk, ax.get_ylim()[1], f"F{k + 1} {fk:.0f}\nB {bk:.0f}", ha="center", va="bottom", fontsize=7)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("dB")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title(title, pad=22)
    return save_figure(fig, path)


def plot_tracks(result, path: Path | str, title: str = "") -> Path:
    """Formant tracks over time (frames of a vocal-tract file), bandwidths as shaded bands."""
    fig, ax = plt.subplots(figsize=(8, 4.5))
    t = result.time_s if result.time_s is not None else np.arange(len(result.formants_hz))
    for k in range(result.formants_hz.shape[1]):
        f, b = result.formants_hz[:, k], result.bandwidths_hz[:, k]
        line = ax.plot(t * 1e3, f, lw=1.4, label=f"F{k + 1}")[0]
        ax.fill_between(t * 1e3, f - b / 2, f + b / 2, color=line.get_color(), alpha=0.2, lw=0)
    if result.min_area_cm2 is not None:
        closed = result.min_area_cm2 < CLOSURE_CM2
        if closed.any():
            ax.fill_between(t * 1e3, 0, 1, where=closed, transform=ax.get_xaxis_transform(), color="#999999",
                            alpha=0.25, lw=0, label=f"constriction < {CLOSURE_CM2:g} cm^2 (peaks are not formants)")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("frequency (Hz)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8, ncol=5)
    ax.set_title(title)
    return save_figure(fig, path)


def plot_spectrogram(samples: np.ndarray, sample_rate_hz: int, path: Path | str, title: str = "",
                     max_hz: float = 5500.0) -> Path:
    """A wide-band spectrogram (6-ms Hann windows), 60 dB of range."""
    nper = max(16, int(0.006 * sample_rate_hz))
    f, t, sxx = spectrogram(samples, sample_rate_hz, nper, nper * 3 // 4, max(512, nper))
    db = 10 * np.log10(np.maximum(sxx, 1e-20))
    keep = f <= max_hz
    fig, ax = plt.subplots(figsize=(8, 4))
    top = float(db[keep].max()) if keep.any() and db.size else 0.0
    ax.pcolormesh(t, f[keep], db[keep], shading="auto", cmap="Greys", vmin=top - 60, vmax=top)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title(title)
    return save_figure(fig, path)
