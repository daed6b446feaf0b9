"""Speed of speaking an utterance once its targets are solved (issue "Utterances").

Goals: simulation plus synthesis of 1 s of speech at most 10 s of wall time on one core (issue "Utterances"), at
most 1 s once its targets are solved (issue "Say any Japanese word").  A 1-s utterance of four force sets (/a/,
/i/-like, a lip closure, /a/) on the default speaker; prints each part's time: the rest posture, the segments'
EPs, the simulation (contact on), the tract and formant tracks, the sound, once from nothing and once with the
rest posture and the EPs kept as ``artic speak`` keeps them (the goal's figure); and beside it, where it is installed,
VocalTractLab's own synthesis of 1 s (``synth_block``: 400 tract states gliding from its /a/ to its /i/, the
modal glottis, 110 samples a state).  Needs only the config.
"""

from __future__ import annotations

import os
import tempfile
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core, as the goal says
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from artic_cli.config import load_config  # noqa: E402
from artic_cli.geometry.mesh import tongue_mesh  # noqa: E402
from artic_cli.geometry.wall import wall_surface  # noqa: E402
from artic_cli.io.result_cache import ResultCache  # noqa: E402
from artic_cli.mechanics.simulate import settle  # noqa: E402
from artic_cli.speech.plan import plan  # noqa: E402
from artic_cli.speech.utterance import parse_utterance  # noqa: E402
from artic_cli.stages import speak  # noqa: E402
from artic_cli.stages.simulate import build  # noqa: E402

UTTERANCE = {"name": "bench", "f0_hz": [[0.0, 125], [1.0, 100]],
             "segments": [{"forces_n": {"JO": 2.5, "HG": 1.0}, "duration_ms": 300, "label": "a"},
                          {"forces_n": {"JO": 0.5, "GGp": 4.0, "SL": 1.0}, "duration_ms": 250, "label": "i"},
                          {"forces_n": {"JO": 0.5}, "duration_ms": 150, "label": "p", "voiced": False},
                          {"forces_n": {"JO": 2.5, "HG": 1.0}, "duration_ms": 300, "label": "a"}],
             "tract": [{"at_ms": 550, "ramp_ms": 15, "lip_area_cm2": 0.0}, {"at_ms": 700, "ramp_ms": 10,
                                                                             "lip_area_cm2": 3.0}]}


def main() -> None:
    cfg = load_config()
    mesh, wall = tongue_mesh(cfg.speaker.tongue), wall_surface(cfg.speaker.wall)
    u = parse_utterance(UTTERANCE, "bench")
    p = plan(u, cfg, [None] * len(u.segments), lambda targets: [])  # every segment's forces given
    model = build(cfg, mesh, wall)
    eps = ResultCache(tempfile.mkdtemp(), "ep")  # held in memory: never committed
    t0 = time.perf_counter()
    s = speak.compute(u, p, cfg, mesh, wall, model=model, known=eps)
    total = time.perf_counter() - t0
    rest = settle(model)
    t0 = time.perf_counter()  # again, as artic speak does once the force sets were spoken or solved before
    warm = speak.compute(u, p, cfg, mesh, wall, model=model, rest=rest, known=eps)
    kept = time.perf_counter() - t0
    st = s.trajectory.stats
    print(f"speak 1.0 s (4 force sets, a lip closure): {total:.1f} s wall on one core, of which the simulation "
          f"{st['wall_time_s']:.1f} s ({st['steps']} steps, {st['newton_iterations']} Newton iterations) "
          f"(goal <= 10 s) -> {'met' if total <= 10.0 else 'NOT MET'}")
    print("  " + "; ".join(f"{name} {t_:.2f} s" for name, t_ in s.timings_s.items()))
    print("  again, its rest posture and the force sets' EPs kept (artic speak's cache): "
          + "; ".join(f"{name} {t_:.2f} s" for name, t_ in warm.timings_s.items()))
    print(f"1 s of speech once its forces are known: {kept:.1f} s with the rest posture and EPs kept, "
          f"{total:.1f} s without (goal <= 1 s) -> {'met' if kept <= 1.0 else 'NOT MET'}")
    vtl = vocaltractlab_seconds()
    if vtl is None:
        print("VocalTractLab not installed (pip install vocaltractlab-cython): no side-by-side figure")
    else:
        print(f"VocalTractLab, 1 s of speech from 400 tract states (synth_block, median of 3): {vtl:.2f} s; "
              f"ours / theirs = {kept / vtl:.2f} ({total / vtl:.2f} without the cache)")


def vocaltractlab_seconds() -> float | None:
    """VocalTractLab's wall time (s) to synthesize 1 s from its own tract states, median of 3 (None: absent)."""
    try:
        import numpy as np
        import vocaltractlab_cython as vtl
    except ImportError:
        return None
    a, i, glottis = vtl.get_shape("a", "tract"), vtl.get_shape("i", "tract"), vtl.get_shape("modal", "glottis")
    w = np.linspace(0.0, 1.0, 400)[:, None]
    tract, folds = a * (1.0 - w) + i * w, np.tile(glottis, (400, 1))
    took = []
    for _ in range(3):
        t0 = time.perf_counter()
        vtl.synth_block(tract, folds, state_samples=110)
        took.append(time.perf_counter() - t0)
    return float(np.median(took))


if __name__ == "__main__":
    main()
