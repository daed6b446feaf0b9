"""The transfer function of a tube with its formants marked."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .common import save_figure


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
