"""Speed of the whole articulator (tongue, jaw, hyoid, muscles, contact, volume constraint).

Goal (issue "muscles, jaw-hyoid complex and contact"): at most 0.5 s of wall
time per simulated second on one core.  Prints the ratio and the share of
time spent in contact handling.
"""

from __future__ import annotations

import os

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[var] = "1"

import time  # noqa: E402

import numpy as np  # noqa: E402
from pathlib import Path  # noqa: E402

from artic_cli.config import load_config  # noqa: E402
from artic_cli.geometry.mesh import tongue_mesh  # noqa: E402
from artic_cli.geometry.wall import wall_surface  # noqa: E402
from artic_cli.mechanics import contact  # noqa: E402
from artic_cli.mechanics.loads import muscle_force_vector  # noqa: E402
from artic_cli.mechanics.model import Control, build_articulator  # noqa: E402
from artic_cli.mechanics.simulate import run, settle  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
GOAL = 0.5
REPEATS = 5


def main() -> None:
    cfg = load_config(ROOT / "configs" / "default.yaml")
    model = build_articulator(cfg, tongue_mesh(cfg.speaker.tongue), wall_surface(cfg.speaker.wall))
    rest = settle(model)
    ctl = Control(node_force=np.zeros((model.n_nodes, 3)), muscle_force=muscle_force_vector(model, {"SG": 4.0, "JO": 3.0}))
    spent = {"contact": 0.0}
    for name in ("contact_planes", "contact_forces", "enforce"):
        fn = getattr(contact, name)

        def timed(*a, _fn=fn, **k):
            t0 = time.perf_counter()
            try:
                return _fn(*a, **k)
            finally:
                spent["contact"] += time.perf_counter() - t0

        setattr(contact, name, timed)
    run(model, rest, lambda t: ctl, 0.3)  # warm-up: compiled loops loaded, caches filled
    walls, shares = [], []
    for _ in range(REPEATS):
        spent["contact"] = 0.0
        traj, end = run(model, rest, lambda t: ctl, 0.3)
        walls.append(traj.stats["wall_time_s"])
        shares.append(spent["contact"] / walls[-1])
    wall = float(np.median(walls))
    ratio = wall / 0.3
    print(f"articulator: {model.n_nodes} nodes ({model.n_tongue} tongue), {len(model.muscle_names)} muscles, "
          f"{len(model.springs.i)} cylinders and links, dt = {model.options.dt * 1e3:g} ms")
    print(f"300 ms of SG 4 N + JO 3 N, {REPEATS} runs: {', '.join(f'{w * 1e3:.0f}' for w in walls)} ms wall; "
          f"median {ratio:.2f} s per simulated second (slowest {max(walls) / 0.3:.2f}; goal <= {GOAL}) -> "
          f"{'MET' if ratio <= GOAL else 'NOT MET'}")
    print(f"Newton iterations {traj.stats['newton_iterations']} "
          f"({traj.stats['newton_iterations'] / traj.stats['steps']:.1f}/step), "
          f"factorisations {traj.stats['refactors']}; contact handling {100 * np.median(shares):.0f} % of the time")


if __name__ == "__main__":
    main()
