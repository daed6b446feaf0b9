"""The midsagittal view of the model, like the paper's Fig. 1."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ..geometry.mesh import Mesh
from ..geometry.wall import WallSurface
from .common import draw_tongue, draw_wall, finish_axes, save_figure


TRACT_STYLE = {"lower_incisor": "#8a6d3b", "upper_incisor": "#8a6d3b", "lower_lip": "#d98880", "upper_lip": "#d98880",
               "larynx_front": "#2e86c1", "velum_nasal": "#7d3c98", "velum": "#7d3c98", "port": "#7d3c98",
               "pharynx": "#444444"}


def plot_mesh(mesh: Mesh, wall: WallSurface, landmarks: dict, path: Path | str, title: str = "",
              tract: dict | None = None) -> Path:
    """Fig. 1: the mesh and the wall; ``tract``: the vocal tract's other parts at rest ({name: (n, 2) cm})."""
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    draw_wall(ax, wall)
    for name, xy in (tract or {}).items():
        if name in TRACT_STYLE:
            ax.plot(xy[:, 0], xy[:, 1], color=TRACT_STYLE[name], lw=1.6, ls=":" if name == "port" else "-",
                    label="vocal tract (lips, incisors, velum, larynx)" if name == "larynx_front" else None)
    draw_tongue(ax, mesh.nodes, mesh.grid)
    fixed = np.concatenate([mesh.node_sets.get("anchor", []), mesh.node_sets.get("floor", [])]).astype(int)
    mids = fixed[np.isclose(mesh.nodes[fixed, 2], 0.0)]
    ax.plot(mesh.nodes[mids, 0], mesh.nodes[mids, 1], "s", ms=3, color="#555555", label="held nodes (anchor, floor)")
    for name in ("tip", "dorsum"):
        p = mesh.nodes[mesh.node_sets[name][0]]
        ax.plot(p[0], p[1], "o", ms=7, mfc="none", mew=1.6, label=f"{name} control point")
    pts = np.array(list(landmarks.values()))
    ax.plot(pts[:, 0], pts[:, 1], "x", color="#2c7fb8", ms=5, label="landmarks (projected)")
    finish_axes(ax, title or f"Model configuration: {len(mesh.bricks)} bricks, {len(mesh.nodes)} nodes, "
                f"{len(mesh.cylinders)} cylinders")
    ax.set_xlim(-10.5, 1.5)
    ax.set_ylim(-9, 7)
    return save_figure(fig, path)
