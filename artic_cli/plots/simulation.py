"""Start and end shapes of a simulation, with the wall (the paper's Fig. 4 style)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt

from .common import draw_tongue, draw_wall, finish_axes, save_figure


def plot_simulation(traj, model, wall, path: Path | str, title: str = "") -> Path:
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    draw_wall(ax, wall, lateral=False)
    grid = model.mesh.grid
    draw_tongue(ax, traj.x[0], grid, color="#999999", label="start", lateral=False)
    draw_tongue(ax, traj.x[-1], grid, color="#c0392b", label=f"end ({traj.time[-1] * 1e3:.0f} ms)", lateral=False)
    for name, marker in (("tip", "o"), ("dorsum", "s")):
        if name in model.mesh.node_sets:
            i = model.mesh.node_sets[name][0]
            ax.plot(traj.x[:, i, 0], traj.x[:, i, 1], "-", lw=1.2, marker=marker, ms=2,
                    label=f"{name} path")
    finish_axes(ax, title)
    ax.set_xlim(-10.5, 1.5)
    ax.set_ylim(-9, 7)
    return save_figure(fig, path)
