"""Pictures of a spoken utterance: the spectrogram with our formant tracks and the segments, and the tip,
dorsum and jaw heights below on the same time axis; a GIF of the midsagittal view."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..acoustics.spectrogram import spectrogram
from .common import save_figure


def plot_utterance(record, samples: np.ndarray, sample_rate_hz: int, path: Path | str, max_hz: float = 8000.0) -> Path:
    """``record``: :class:`artic_cli.speech.record.Record`; ``samples``: its WAV."""
    nper = max(16, int(0.006 * sample_rate_hz))
    f, t, sxx = spectrogram(samples, sample_rate_hz, nper, nper * 3 // 4, max(512, nper))
    db = 10 * np.log10(np.maximum(sxx, 1e-20))
    keep = f <= max_hz
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    top = float(db[keep].max()) if keep.any() and db.size else 0.0
    ax.pcolormesh(t, f[keep], db[keep], shading="auto", cmap="Greys", vmin=top - 70, vmax=top)
    fm = record.formants_hz
    for k, color in zip(range(min(3, fm.shape[1])), ("#c0392b", "#2471a3", "#1e8449")):
        ax.plot(record.time_s, fm[:, k], ".", ms=2.5, color=color, label=f"F{k + 1} (transfer function)")
    ends = record.starts_s + record.durations_s
    for a_ in (ax, bx):
        for s in record.starts_s[1:]:
            a_.axvline(s, color="#7d3c98", lw=0.8, ls="--")
    for s, e, lab in zip(record.starts_s, ends, record.labels):
        ax.text(0.5 * (s + e), max_hz * 0.97, lab, ha="center", va="top", fontsize=9, color="#7d3c98",
                bbox={"fc": "white", "ec": "none", "alpha": 0.7, "pad": 1})
    ax.set_ylim(0, max_hz)
    ax.set_ylabel("frequency (Hz)")
    ax.legend(loc="upper right", fontsize=7, markerscale=3, bbox_to_anchor=(1.0, 0.9))
    ax.set_title(f"{record.attrs.get('name', '')}: spectrogram, formant tracks, segments")
    for name, color in (("tip", "#c0392b"), ("dorsum", "#2471a3"), ("jaw", "#8a6d3b")):
        if name in record.control_points:
            y = record.control_points[name][:, 1]
            bx.plot(record.time_s, y - y[0], color=color, label=f"{name} height (from rest)")
    bx.set_xlabel("time (s)")
    bx.set_ylabel("height change (cm)")
    bx.grid(alpha=0.3)
    bx.legend(loc="best", fontsize=7)
    return save_figure(fig, path)


def animate_utterance(record, model, wall, path: Path | str, fps: int = 20, max_frames: int = 100) -> Path:
    """The midsagittal tongue, jaw and wall moving through the utterance (a GIF); ``model``: the articulator
    the record was simulated with."""
    from types import SimpleNamespace

    from .animation import animate_simulation

    traj = SimpleNamespace(time=record.time_s, x=record.positions_cm.astype(float))
    return animate_simulation(traj, model, wall, path, fps=fps, max_frames=max_frames)
