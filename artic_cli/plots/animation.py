"""A short GIF of a simulation: the midsagittal tongue, jaw and hyoid moving against the wall."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import FuncAnimation

from .common import WALL_STYLE, draw_wall, save_animation, wall_outlines


def animate_simulation(traj, model, wall, path: Path | str, fps: int = 20, max_frames: int = 80) -> Path:
    """Write an animated GIF (atomically) of the recorded frames, at most ``max_frames`` of them."""
    path = Path(path)
    frames = np.unique(np.linspace(0, len(traj.time) - 1, min(max_frames, len(traj.time))).round().astype(int))
    nr, nc, planes = model.mesh.grid
    nt = model.n_tongue
    fig, ax = plt.subplots(figsize=(6, 6))
    draw_wall(ax, wall, lateral=False, parts=("palate", "pharynx") if model.contact is not None else None)
    ax.set_aspect("equal")
    ax.set_xlim(-10.5, 1.5)
    ax.set_ylim(-9, 7)
    ax.set_xlabel("x (cm), anterior +")
    ax.set_ylabel("y (cm), superior +")
    ax.grid(alpha=0.25)
    mid = lambda x: x[:nt].reshape(nr, nc, planes, 3)[:, :, planes // 2]  # noqa: E731
    radial = [ax.plot([], [], color="#c0392b", lw=0.7)[0] for _ in range(nr)]
    rings = [ax.plot([], [], color="#c0392b", lw=1.4 if j == nc - 1 else 0.7)[0] for j in range(nc)]
    jaw_line = ax.plot([], [], color=WALL_STYLE["mandible"], lw=2.0)[0]
    jaw_xy = None
    if model.contact is not None:
        from ..mechanics.wall_query import rigid_motion

        xy = wall_outlines(wall, 0.0)["mandible"]
        jaw_xy = np.column_stack([xy, np.zeros(len(xy))])
    marks = {name: ax.plot([], [], marker, ms=6, label=name)[0]
             for name, marker in (("tip", "o"), ("dorsum", "s"), ("jaw", "^")) if name in model.node_sets}
    ax.legend(loc="lower left", fontsize=7)
    title = ax.set_title("")

    def draw(k):
        x = traj.x[k]
        g = mid(x)
        for i, line in enumerate(radial):
            line.set_data(g[i, :, 0], g[i, :, 1])
        for j, line in enumerate(rings):
            line.set_data(g[:, j, 0], g[:, j, 1])
        if jaw_xy is not None:
            r, t = rigid_motion(model.contact.jaw_rest, x[model.contact.jaw_nodes])
            moved = jaw_xy @ r.T + t
            jaw_line.set_data(moved[:, 0], moved[:, 1])
        for name, m in marks.items():
            i = model.node_sets[name][0]
            m.set_data([x[i, 0]], [x[i, 1]])
        title.set_text(f"t = {traj.time[k] * 1e3:.0f} ms")
        return [*radial, *rings, jaw_line, *marks.values(), title]

    return save_animation(fig, FuncAnimation(fig, draw, frames=frames, blit=False), path, fps)
