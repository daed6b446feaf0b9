"""Fig. 9: the EP map of a jaw position, simulated (thick) and derived from the typical map (thin)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..errors import ArticError
from .common import save_figure


def plot_dynamic_map(maps, dm, jaw: str, path: Path | str) -> Path:
    from ..control.dynamic import derive

    if jaw not in maps.jaws:
        raise ArticError(f"no jaw position '{jaw}' in the maps; stored: {', '.join(maps.jaws)}")
    sim = maps.jaws[jaw]
    derived = derive(maps, dm, float(sim.rest[2, 1]))
    k = dm.jaws.index(jaw)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.5))
    colours = plt.cm.tab20(np.linspace(0, 1, max(len(sim.single), 2)))
    for c, (ax, cp) in enumerate(zip(axes, ("tip", "dorsum"))):
        for (m, net), col in zip(sim.single.items(), colours):
            if m not in derived.single:
                continue
            a = net.x[:, c, :2]
            b = derived.single[m].x[:, c, :2]
            ax.plot(a[:, 0], a[:, 1], "-", lw=2.6, color=col, label=f"{m} simulated")
            ax.plot(b[:, 0], b[:, 1], "--", lw=1.0, color="k")
        ax.plot([], [], "--", lw=1.0, color="k", label=f"derived from {dm.typical}")
        ax.set_title(f"{cp}: mean difference {dm.error_mean[k, c]:.3f} cm", fontsize=10)
        ax.set_aspect("equal")
        ax.set_xlabel("x (cm), anterior +")
        ax.set_ylabel("y (cm), superior +")
        ax.grid(alpha=0.25)
    axes[1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    fig.suptitle(f"Fig. 9: EP vectors at jaw position {jaw} ({sim.rest[2, 1] - dm.rest_height:+.2f} cm), simulated "
                 f"(thick) and carried from the typical map by rotation and translation (thin)", fontsize=10)
    return save_figure(fig, path)
