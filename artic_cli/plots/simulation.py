"""Start and end shapes of a simulation, with the wall (the paper's Fig. 4 style)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from .common import WALL_STYLE, draw_tongue, draw_wall, finish_axes, save_figure, wall_outlines


def plot_simulation(traj, model, wall, path: Path | str, title: str = "") -> Path:
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    draw_wall(ax, wall, lateral=False, parts=("palate", "pharynx") if model.contact is not None else None)
    if model.contact is not None:  # the mandible's wall moves with the jaw
        from ..mechanics.wall_query import rigid_motion

        xy = wall_outlines(wall, 0.0)["mandible"]
        pts = np.column_stack([xy, np.zeros(len(xy))])
        for frame, style, label in ((0, ":", "mandible, start"), (-1, "-", "mandible, end")):
            r, t = rigid_motion(model.contact.jaw_rest, traj.x[frame][model.contact.jaw_nodes])
            moved = pts @ r.T + t
            ax.plot(moved[:, 0], moved[:, 1], style, color=WALL_STYLE["mandible"], lw=2.0, label=label)
    grid = model.mesh.grid
    nt = model.n_tongue
    draw_tongue(ax, traj.x[0, :nt], grid, color="#999999", label="start", lateral=False)
    draw_tongue(ax, traj.x[-1, :nt], grid, color="#c0392b", label=f"end ({traj.time[-1] * 1e3:.0f} ms)", lateral=False)
    if model.n_nodes > nt:  # jaw and hyoid links (left side) at start and end
        frame_names = [f"{p}_{s}" for p in ("condyle", "coronoid", "gonion", "symphysis", "hyoid_body", "hyoid_horn")
                       for s in ("l", "r")]
        bones = np.array([model.names[n] for n in frame_names if n in model.names])
        pairs = np.column_stack([model.springs.i, model.springs.j])
        pairs = pairs[np.isin(pairs, bones).all(axis=1) & (model.rest[pairs][:, :, 2] >= 0).all(axis=1)]
        for frame, colour, label in ((0, "#999999", "jaw and hyoid, start"), (-1, "#1f4e79", "jaw and hyoid, end")):
            for k, (a, b) in enumerate(pairs):
                xy = traj.x[frame][[a, b]]
                ax.plot(xy[:, 0], xy[:, 1], color=colour, lw=1.0, label=label if k == 0 else None)
    for name, marker in (("tip", "o"), ("dorsum", "s"), ("jaw", "^")):
        if name in model.node_sets:
            i = model.node_sets[name][0]
            ax.plot(traj.x[:, i, 0], traj.x[:, i, 1], "-", lw=1.2, marker=marker, ms=2,
                    label=f"{name} path")
    finish_axes(ax, title)
    ax.set_xlim(-10.5, 1.5)
    ax.set_ylim(-9, 7)
    return save_figure(fig, path)
