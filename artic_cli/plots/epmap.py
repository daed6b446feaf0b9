"""Fig. 8: EP vectors of the tongue tip and dorsum, with the contour net of a muscle pair."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..errors import ArticError
from .common import save_figure


def plot_ep_map(maps, jaw: str | None, pair: str | None, path: Path | str) -> Path:
    jaw = jaw or maps.typical_jaw
    if jaw not in maps.jaws:
        raise ArticError(f"no jaw position '{jaw}' in the maps; stored: {', '.join(maps.jaws)}")
    jm = maps.jaws[jaw]

    def find(name: str) -> str:
        for cand in (name, "+".join(reversed(name.split("+")))):
            if cand in jm.pair:
                return cand
        stored = ", ".join(jm.pair) or "none (nets are built at " + maps.typical_jaw + ")"
        raise ArticError(f"no two-muscle net '{name}' at jaw position '{jaw}'; stored: {stored}")

    if pair is not None:
        nets = [find(pair)] * 2
    else:  # the first net of the tip list on the tip panel, of the dorsum list on the dorsum panel (Fig. 8)
        spec = json.loads(maps.attrs.get("spec_yaml", "{}"))
        firsts = [spec.get("pairs_tip") or [], spec.get("pairs_dorsum") or []]
        nets = [find("+".join(f[0])) if f and jm.pair else (next(iter(jm.pair)) if jm.pair else None)
                for f in firsts]
    fig, axes = plt.subplots(1, 2, figsize=(13, 6))
    colours = plt.cm.tab20(np.linspace(0, 1, max(len(jm.single), 2)))
    for c, (ax, cp) in enumerate(zip(axes, ("tip", "dorsum"))):
        ax.plot(*jm.rest[c, :2], "ko", ms=6, label="rest")
        for (m, net), col in zip(jm.single.items(), colours):
            xy = net.x[:, c, :2]
            ax.plot(xy[:, 0], xy[:, 1], "-o", color=col, ms=3, lw=1.4, label=m)
            ax.annotate(m, xy[-1], fontsize=8, color=col, xytext=(3, 3), textcoords="offset points")
            bad = ~net.converged
            if bad.any():
                ax.plot(xy[bad, 0], xy[bad, 1], "o", mfc="none", mec="red", ms=9)
        pair = nets[c]
        if pair is not None:
            net = jm.pair[pair]
            g = net.x[:, :, c, :2]
            for i in range(g.shape[0]):
                ax.plot(g[i, :, 0], g[i, :, 1], "-", color="0.35", lw=0.7)
            for j in range(g.shape[1]):
                ax.plot(g[:, j, 0], g[:, j, 1], "--", color="0.35", lw=0.7)
            a, b = net.muscles
            ax.text(0.02, 0.02, f"contour net {a}+{b}: {b} varies along solid lines, {a} along dashed ones",
                    transform=ax.transAxes, fontsize=7, color="0.25")
        ax.set_aspect("equal")
        ax.set_title(f"{cp} EPs, jaw position {jaw} (levels {', '.join(f'{v:g}' for v in next(iter(jm.single.values())).levels[0])} N)",
                     fontsize=9)
        ax.set_xlabel("x (cm), anterior +")
        ax.set_ylabel("y (cm), superior +")
        ax.grid(alpha=0.25)
    axes[1].legend(loc="center left", bbox_to_anchor=(1.02, 0.5), fontsize=7)
    axes[0].plot([], [], "o", mfc="none", mec="red", label="not settled")
    fig.suptitle("Equilibrium-position vectors (the paper's Fig. 8); red rings: not settled")
    return save_figure(fig, path)
