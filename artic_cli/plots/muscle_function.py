"""Figs. 5 and 6: starting points (grey) and where each muscle drives the tip / dorsum in 150 ms (crosses)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .common import save_figure


def plot_muscle_function(mf, point: str, path: Path | str) -> Path:
    c = ("tip", "dorsum").index(point)
    n = len(mf.muscles)
    cols = min(5, n)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.2 * rows), squeeze=False, sharex=True, sharey=True)
    s = mf.starts[:, c, :2]
    for k, ax in enumerate(axes.flat):
        if k >= n:
            ax.axis("off")
            continue
        e = mf.ends[k, :, c, :2]
        ax.plot(s[:, 0], s[:, 1], "o", ms=2.5, mfc="none", mec="0.7", label=f"{len(s)} starting points")
        ax.plot(e[:, 0], e[:, 1], "x", ms=3.5, color="0.1", label=f"after {mf.muscles[k]} {mf.drive_n:g} N, "
                                                                 f"{mf.drive_ms:g} ms")
        ax.plot(*mf.rest[c, :2], "o", ms=11, mfc="none", mec="#c0392b", mew=1.5, label="initial (rest) position")
        ax.set_title(mf.muscles[k], fontsize=10)
        ax.set_aspect("equal")
        ax.grid(alpha=0.25)
        if k % cols == 0:
            ax.set_ylabel("y (cm), superior +")
        if k >= n - cols:
            ax.set_xlabel("x (cm), anterior +")
    axes.flat[0].legend(fontsize=6, loc="lower left")
    fig.suptitle(f"{'Fig. 5' if point == 'tip' else 'Fig. 6'}: tongue {point} from scattered starts "
                 f"({' / '.join('-'.join(cb) for cb in mf.combinations)} at six levels, 120 ms), then one muscle")
    return save_figure(fig, path)


def plot_fig7(data: dict, path: Path | str) -> Path:
    """Fig. 7: trajectories from four starting shapes to the EPs of each force level."""
    muscles = list(data)
    fig, axes = plt.subplots(2, len(muscles), figsize=(4.2 * len(muscles), 7.5), squeeze=False)
    colours = plt.cm.viridis(np.linspace(0, 0.9, max(len(next(iter(data.values()))["forces"]), 2)))
    for j, m in enumerate(muscles):
        d = data[m]
        for c, cp in enumerate(("tip", "dorsum")):
            ax = axes[c, j]
            for f_i, force in enumerate(d["forces"]):
                for s_i in range(d["paths"].shape[1]):
                    xy = d["paths"][f_i, s_i, :, c, :2]
                    ax.plot(xy[:, 0], xy[:, 1], "-", lw=0.9, color=colours[f_i],
                            label=f"{force:g} N" if s_i == 0 else None)
                    ax.plot(*xy[0], "s", ms=4, color="0.3")
                    ax.plot(*xy[-1], "o", ms=5, mfc="none", mec=colours[f_i])
            ax.set_title(f"{m}: {cp}", fontsize=10)
            ax.set_aspect("equal")
            ax.grid(alpha=0.25)
            ax.set_xlabel("x (cm), anterior +")
            ax.set_ylabel("y (cm), superior +")
            ax.legend(fontsize=7, title="force", title_fontsize=7)
    fig.suptitle("Fig. 7: from four starting shapes (squares) to one equilibrium per force (circles), 400 ms")
    return save_figure(fig, path)
