"""The model's vowel space: every EP's F1 and F2, jaw position by jaw position, with vowel targets."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .common import save_figure


def plot_vowel_space(maps, path: Path | str, targets: dict[str, tuple[float, float]] | None = None,
                     title: str = "") -> Path:
    """F2 against F1 (both axes reversed, as phoneticians draw them); the rest of each jaw position ringed."""
    fig, ax = plt.subplots(figsize=(7, 5.5))
    colors = plt.cm.viridis(np.linspace(0, 0.9, max(len(maps.jaws), 1)))
    for color, (jname, nets) in zip(colors, maps.jaws.items()):
        p = maps.points(jname)
        ax.plot(p[:, 1], p[:, 0], ".", ms=3, color=color, alpha=0.6, label=f"{jname} ({len(p)} EPs)")
        rest = nets["rest"].formants_hz.reshape(-1, 4)[0]
        ax.plot(rest[1], rest[0], "o", mfc="none", mec=color, ms=9, mew=1.5)
    for name, (f1, f2) in (targets or {}).items():
        ax.text(f2, f1, f"/{name}/", color="#c0392b", fontsize=13, ha="center", va="center", weight="bold",
                clip_on=True)
    pts = np.concatenate([maps.points(j)[:, :2] for j in maps.jaws] + [np.array(list((targets or {}).values()))
                                                                      .reshape(-1, 2)])
    pts = pts[np.isfinite(pts).all(axis=1)]
    f1_lo, f1_hi = min(200.0, pts[:, 0].min() - 50), max(900.0, pts[:, 0].max() + 50)
    f2_lo, f2_hi = min(700.0, pts[:, 1].min() - 100), max(2500.0, pts[:, 1].max() + 100)
    ax.set_xlim(f2_hi, f2_lo)
    ax.set_ylim(f1_hi, f1_lo)
    ax.set_xlabel("F2 (Hz)")
    ax.set_ylabel("F1 (Hz)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower left", markerscale=3)
    ax.set_title(title or "EP maps in the F1-F2 plane (rings: each jaw position's rest; red: male Japanese vowels)",
                 fontsize=9)
    return save_figure(fig, path)
