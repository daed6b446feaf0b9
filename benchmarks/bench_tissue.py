"""Speed of the tissue model: wall time per simulated second on one core.

Goal (issue "semicontinuum tongue"): a 300 ms simulation of the 231-node
tongue at the default step in at most 0.25 s of wall time per simulated
second (the paper: about 40).  Prints the ratio and where the time goes.

Run: ``make bench`` (or ``python benchmarks/bench_tissue.py``).
"""

from __future__ import annotations

import os

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[var] = "1"  # one core

import statistics  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from artic_cli.config import load_config  # noqa: E402
from artic_cli.geometry.mesh import tongue_mesh  # noqa: E402
from artic_cli.mechanics import assembly, integrator  # noqa: E402
from artic_cli.mechanics.model import Control, build_model, rest_state  # noqa: E402
from artic_cli.mechanics.simulate import run  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
GOAL = 0.25
PAPER = 40.0


class Timers:
    def __init__(self):
        self.t = {}

    def wrap(self, owner, name, label):
        fn = getattr(owner, name)

        def timed(*a, **k):
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                self.t[label] = self.t.get(label, 0.0) + time.perf_counter() - t0

        setattr(owner, name, timed)
        return fn


def main() -> None:
    cfg = load_config(ROOT / "configs" / "default.yaml")
    model = build_model(tongue_mesh(cfg.speaker.tongue), cfg.materials.tongue, cfg.simulation)
    f = np.zeros((model.n_nodes, 3))
    blade = model.node_set("blade")
    f[blade] = np.array([1.4, 1.4, 0.0]) * 1e5 / len(blade)  # 2 N pull
    ctl = Control(node_force=f)
    duration = 0.3
    run(model, rest_state(model), lambda t: ctl, duration)  # warm-up
    walls, diag = [], []
    for _ in range(7):
        traj, end = run(model, rest_state(model), lambda t: ctl, duration)
        walls.append(traj.stats["wall_time_s"])
        diag.append(traj.stats["diagnostics_time_s"])
    best, med = min(walls), statistics.median(walls)

    timers = Timers()
    timers.wrap(integrator, "forces", "forces (every term)")
    timers.wrap(integrator, "tangent", "tangent assembly")
    timers.wrap(integrator, "factorize", "banded Cholesky factorisation")
    orig_solve = assembly.BandFactor.solve
    timers.wrap(assembly.BandFactor, "solve", "banded solves")
    traj, _ = run(model, rest_state(model), lambda t: ctl, duration)
    total = traj.stats["wall_time_s"]
    assembly.BandFactor.solve = orig_solve

    ratio = med / duration
    print(f"tissue model: 231 nodes, {len(model.springs.i)} cylinders, band half-width {model.layout.pattern.u}, "
          f"dt = {model.options.dt * 1e3:g} ms, {traj.stats['steps']} steps")
    print(f"300 ms simulation: median {med * 1e3:.1f} ms, best {best * 1e3:.1f} ms wall (7 runs); "
          f"afterwards volumes, energies and inversion checks of all frames: {statistics.median(diag) * 1e3:.1f} ms")
    print(f"wall time per simulated second: {ratio:.3f} (goal <= {GOAL}; paper ~{PAPER:g}: "
          f"{PAPER / ratio:.0f}x faster) -> {'MET' if ratio <= GOAL else 'NOT MET'}")
    print(f"Newton iterations {traj.stats['newton_iterations']} ({traj.stats['newton_iterations'] / traj.stats['steps']:.2f}"
          f"/step), factorisations {traj.stats['refactors']}")
    print("time split of the stepping (one instrumented run):")
    accounted = 0.0
    for label, t in sorted(timers.t.items(), key=lambda kv: -kv[1]):
        print(f"  {label:32s} {t * 1e3:7.1f} ms  {100 * t / total:5.1f} %")
        accounted += t
    print(f"  {'rest (residual, predictor, loads)':32s} {(total - accounted) * 1e3:7.1f} ms  "
          f"{100 * (total - accounted) / total:5.1f} %")


if __name__ == "__main__":
    main()
