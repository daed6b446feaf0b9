"""Shared plotting helpers."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..geometry.wall import PARTS, WallSurface  # noqa: E402
from ..io.store import atomic_path  # noqa: E402

WALL_STYLE = {"palate": "#444444", "pharynx": "#444444", "mandible": "#8a6d3b"}


def save_figure(fig, path: Path | str, dpi: int = 130) -> Path:
    """Write a PNG atomically and close the figure."""
    path = Path(path)
    try:
        with atomic_path(path, ".png") as tmp:
            fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format="png")
    finally:
        plt.close(fig)
    return path


def save_animation(fig, animation, path: Path | str, fps: int) -> Path:
    """Write an animated GIF atomically and close the figure."""
    from matplotlib.animation import PillowWriter

    path = Path(path)
    try:
        with atomic_path(path, ".gif") as tmp:
            animation.save(tmp, writer=PillowWriter(fps=fps))
    finally:
        plt.close(fig)
    return path


def wall_outlines(wall: WallSurface, z: float = 0.0):
    """Midsagittal (or other slice) outline of each wall part: {part: (n,2) array}."""
    out = {}
    for k, name in enumerate(PARTS):
        tri = wall.triangles[wall.part == k]
        ids = np.unique(tri)
        v = wall.vertices[ids]
        on = np.isclose(v[:, 2], z)
        if on.any():
            out[name] = v[on][:, :2]
    return out


def draw_wall(ax, wall: WallSurface, lateral: bool = True, parts=None) -> None:
    for name, xy in wall_outlines(wall, 0.0).items():
        if parts is not None and name not in parts:
            continue
        ax.plot(xy[:, 0], xy[:, 1], color=WALL_STYLE[name], lw=2.0, label=f"{name} (midsagittal)")
    if lateral:
        zs = np.unique(np.round(wall.vertices[:, 2], 6))
        z = zs.max()
        for name, xy in wall_outlines(wall, float(z)).items():
            ax.plot(xy[:, 0], xy[:, 1], color=WALL_STYLE[name], lw=0.8, ls=":",
                    label=f"{name} (z = {z:.1f} cm)" if name == "palate" else None)


def draw_tongue(ax, nodes: np.ndarray, grid: tuple, color="#c0392b", lw=0.8, label="tongue mesh",
                lateral=True, alpha=1.0) -> None:
    nr, nc, planes = grid
    g = nodes.reshape(nr, nc, planes, 3)
    mid = g[:, :, planes // 2]
    for k in range(nr):
        ax.plot(mid[k, :, 0], mid[k, :, 1], color=color, lw=lw, alpha=alpha)
    for j in range(nc):
        ax.plot(mid[:, j, 0], mid[:, j, 1], color=color, lw=lw * (1.6 if j == nc - 1 else 1.0), alpha=alpha,
                label=label if j == nc - 1 else None)
    if lateral:
        lat = g[:, :, -1]
        ax.plot(lat[:, -1, 0], lat[:, -1, 1], color=color, lw=0.8, ls="--", alpha=0.7 * alpha,
                label=f"{label}, z = {lat[0, 0, 2]:.1f} cm surface")


def finish_axes(ax, title: str) -> None:
    ax.set_aspect("equal")
    ax.set_xlabel("x (cm), anterior +")
    ax.set_ylabel("y (cm), superior +")
    ax.set_title(title)
    ax.grid(alpha=0.25)
    ax.legend(loc="lower left", fontsize=7, framealpha=0.85)
