"""Vocal-tract speed: area functions of one frame and of a 1-s simulation (200 frames) of the default
speaker, and the memory of the result per frame.  Goals (issue 13): 2 ms per frame, 0.5 s for 200 frames,
memory linear in frames."""

from __future__ import annotations

import tracemalloc

import numpy as np

from artic_cli.config import load_config
from artic_cli.geometry.mesh import tongue_mesh
from artic_cli.tract.areas import tracts_of as compute
from artic_cli.tract.controls import controls_for
from artic_cli.tract.shapes import Shapes
from timing import median_time  # benchmarks/timing.py



def _shapes(mesh, frames: int) -> Shapes:
    """The rest surface moved by a smooth dorsum rise and jaw rotation over ``frames`` frames."""
    from artic_cli.tract.shapes import surface_nodes

    mid, lateral = surface_nodes(mesh)
    surf = mesh.nodes[mid, :2]
    t = np.linspace(0.0, 1.0, frames)
    bump = np.exp(-0.5 * ((np.arange(len(surf)) - 4) / 2.0) ** 2)
    tongue = surf[None] + 0.8 * np.sin(np.pi * t)[:, None, None] * np.stack([0 * bump, bump], axis=1)[None]
    ang = np.deg2rad(-6.0) * np.sin(np.pi * t)
    rot = np.zeros((frames, 3, 3))
    rot[:, 0, 0] = rot[:, 1, 1] = np.cos(ang)
    rot[:, 0, 1], rot[:, 1, 0], rot[:, 2, 2] = -np.sin(ang), np.sin(ang), 1.0
    side = tongue + (mesh.nodes[lateral, :2] - surf)[None]
    return Shapes(time_s=t, tongue_cm=tongue, jaw_rotation=rot, jaw_translation=np.zeros((frames, 3)),
                  tongue_lateral_cm=side, lateral_z_cm=float(mesh.nodes[lateral, 2].mean()))


def main() -> None:
    cfg = load_config()
    vt, wall = cfg.vocal_tract, cfg.speaker.wall
    mesh = tongue_mesh(cfg.speaker.tongue)
    one, many = _shapes(mesh, 1), _shapes(mesh, 200)
    c1, c200 = controls_for(vt, one.time_s), controls_for(vt, many.time_s)
    t1 = median_time(lambda: compute(vt, wall, one, c1), n=21)
    t200 = median_time(lambda: compute(vt, wall, many, c200), n=5)
    print(f"one frame: {t1 * 1e3:.2f} ms (goal <= 2 ms: {'met' if t1 <= 0.002 else 'NOT met'})")
    print(f"200 frames (a 1-s simulation at 5 ms): {t200:.3f} s (goal <= 0.5 s: {'met' if t200 <= 0.5 else 'NOT met'}); "
          f"{t200 / 200 * 1e3:.2f} ms per frame")
    peaks = []
    for n in (50, 100, 200, 400):
        s, c = _shapes(mesh, n), None
        c = controls_for(vt, s.time_s)
        tracemalloc.start()
        compute(vt, wall, s, c)
        peaks.append(tracemalloc.get_traced_memory()[1] / 2**20)
        tracemalloc.stop()
    slope = np.polyfit([50, 100, 200, 400], peaks, 1)[0]
    print("peak memory, 50/100/200/400 frames: " + " / ".join(f"{p:.1f}" for p in peaks) +
          f" MiB ({slope * 1024:.0f} kiB per frame; ratio 400/200 frames {peaks[3] / peaks[2]:.2f}, linear: 2)")


if __name__ == "__main__":
    main()
