"""Figures of vocal tracts: the midsagittal view with the grid beside the area function, and an animation."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import FuncAnimation

from .common import save_animation, save_figure

STYLE = {"tongue": ("#c0392b", 2.0), "lower_incisor": ("#8a6d3b", 2.0), "lower_lip": ("#d98880", 2.0),
         "upper_lip": ("#d98880", 2.0), "upper_incisor": ("#8a6d3b", 2.0), "larynx_front": ("#2e86c1", 1.6),
         "velum_nasal": ("#7d3c98", 1.2), "velum": ("#7d3c98", 1.8), "port": ("#7d3c98", 0.8),
         "pharynx": ("#444444", 1.8), "hard_palate": ("#444444", 1.8)}


def _sagittal_axes(ax) -> None:
    ax.set_aspect("equal")
    ax.set_xlim(-9.5, 2.0)
    ax.set_ylim(-9.5, 3.0)
    ax.set_xlabel("x (cm), anterior +")
    ax.set_ylabel("y (cm), superior +")
    ax.grid(alpha=0.2)


def _centres(length: np.ndarray) -> np.ndarray:
    return np.cumsum(length) - 0.5 * length


def _draw_frame(ax_sag, ax_area, t, k: int):
    artists = []
    for name, xy in t.fixed.items():
        color, lw = STYLE.get(name, ("#444444", 1.2))
        ax_sag.plot(xy[:, 0], xy[:, 1], color=color, lw=lw, ls=":" if name == "port" else "-")
    for name, xy in t.contours.items():
        color, lw = STYLE.get(name, ("#444444", 1.2))
        artists.append(ax_sag.plot(xy[k, :, 0], xy[k, :, 1], color=color, lw=lw, label=name.replace("_", " "))[0])
    g, af = t.grid, t.af
    p0 = g.origin + af.inner_s_cm[k][:, None] * g.normal
    p1 = g.origin + af.wall_s_cm[:, None] * g.normal
    lines = [ax_sag.plot([a[0], b[0]], [a[1], b[1]], color="#999999", lw=0.5)[0] for a, b in zip(p0, p1)]
    mid = ax_sag.plot(af.midline_cm[k, :, 0], af.midline_cm[k, :, 1], color="#1e8449", lw=1.0, label="midline")[0]
    x = _centres(af.length_cm[k])
    step = ax_area.step(x, af.area_cm2[k], where="mid", color="#1e8449")[0]
    area, pos, reg = af.constriction()
    mark = ax_area.plot([pos[k]], [area[k]], "v", color="#c0392b", label="constriction")[0]
    return artists, lines, mid, step, mark


def plot_tract(t, k: int, path: Path | str, title: str | None = None) -> Path:
    """The midsagittal tract of frame ``k`` with its grid lines, beside its area function."""
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 5.2), gridspec_kw={"width_ratios": [1.0, 1.25]})
    _sagittal_axes(ax)
    _draw_frame(ax, bx, t, k)
    ax.legend(loc="lower right", fontsize=7)
    area, pos, reg = t.af.constriction()
    bx.set_xlabel("distance from the glottis (cm)")
    bx.set_ylabel("area (cm^2)")
    bx.grid(alpha=0.3)
    bx.set_ylim(0, max(6.0, float(np.nanmax(t.af.area_cm2[k])) * 1.1))
    lip0 = float(np.cumsum(t.af.length_cm[k])[len(t.grid.origin) - 1])
    bx.axvspan(lip0, float(t.af.tract_length_cm[k]), color="#f5b7b1", alpha=0.4, label="lip tube")
    bx.legend(loc="upper left", fontsize=8)
    bx.set_title(f"length {t.af.tract_length_cm[k]:.2f} cm; smallest {area[k]:.2f} cm^2 at {pos[k]:.1f} cm "
                 f"({t.af.region_names[int(reg[k])]}); velum port {t.controls['velum_port_cm2'][k]:.2f} cm^2",
                 fontsize=9)
    ax.set_title(title or f"vocal tract, t = {t.time_s[k]:.3f} s (frame {k})", fontsize=10)
    return save_figure(fig, path)


def animate_tracts(t, path: Path | str, fps: int = 20, max_frames: int = 80) -> Path:
    """An animated GIF (atomically) of the tracts of a simulation, at most ``max_frames`` frames."""
    path = Path(path)
    frames = np.unique(np.linspace(0, t.n_frames - 1, min(max_frames, t.n_frames)).round().astype(int))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.8), gridspec_kw={"width_ratios": [1.0, 1.25]})
    _sagittal_axes(ax)
    artists, lines, mid, step, mark = _draw_frame(ax, bx, t, int(frames[0]))
    bx.set_xlabel("distance from the glottis (cm)")
    bx.set_ylabel("area (cm^2)")
    bx.grid(alpha=0.3)
    bx.set_xlim(0, float(np.nanmax(t.af.tract_length_cm)) + 0.5)
    bx.set_ylim(0, max(6.0, float(np.nanmax(t.af.area_cm2)) * 1.05))
    title = ax.set_title("")
    area, pos, _ = t.af.constriction()
    g, af = t.grid, t.af

    def draw(k):
        for line, (name, xy) in zip(artists, t.contours.items()):
            line.set_data(xy[k, :, 0], xy[k, :, 1])
        p0 = g.origin + af.inner_s_cm[k][:, None] * g.normal
        p1 = g.origin + af.wall_s_cm[:, None] * g.normal
        for line, a, b in zip(lines, p0, p1):
            line.set_data([a[0], b[0]], [a[1], b[1]])
        mid.set_data(af.midline_cm[k, :, 0], af.midline_cm[k, :, 1])
        step.set_data(_centres(af.length_cm[k]), af.area_cm2[k])
        mark.set_data([pos[k]], [area[k]])
        title.set_text(f"t = {t.time_s[k] * 1e3:.0f} ms")
        return [*artists, *lines, mid, step, mark, title]

    return save_animation(fig, FuncAnimation(fig, draw, frames=frames, blit=False), path, fps)
