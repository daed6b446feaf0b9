"""Speed of the target solver (issue "Dynamic EP maps and the target solver").

Goals: one target from the maps (no --verify) in under 0.2 s; --verify --refine in under 5 s; a batch of
100 targets in under 30 s on 2 cores.  Needs data/epmaps.h5 and data/dynamic.h5 (make paper, or
artic ep-map && artic dynamic-map).
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

from artic_cli.control.solver import parse_target
from artic_cli.control.targets import solve, solve_batch
from artic_cli.stages.solve import load_context, simulator

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "data"


def targets(ctx, n: int, seed: int = 1):
    rest = ctx.maps.jaws[ctx.maps.typical_jaw].rest
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        tip = rest[0, :2] + rng.uniform([-0.5, -0.2], [0.1, 0.4])
        dorsum = rest[1, :2] + rng.uniform([-0.3, -0.2], [0.3, 0.1])
        out.append(parse_target({"name": f"t{k}", "crucial": {"point": "tip", "at_cm": tip.tolist()},
                                 "indecisive": [{"point": "dorsum", "at_cm": dorsum.tolist()}]}))
    return out


def main() -> None:
    maps, dyn, mesh = DATA / "epmaps.h5", DATA / "dynamic.h5", DATA / "mesh.h5"
    if not (maps.is_file() and dyn.is_file()):
        sys.exit("bench_solver: run 'make paper' (or artic ep-map && artic dynamic-map) first")
    t0 = time.perf_counter()
    ctx = load_context(maps, dyn)
    t_load = time.perf_counter() - t0
    ts = targets(ctx, 100)
    times, solved = [], 0
    for t in ts:
        t0 = time.perf_counter()
        try:
            solve(ctx, t)
            solved += 1
        except Exception:  # noqa: BLE001 - unreachable targets count too
            pass
        times.append(time.perf_counter() - t0)
    med = statistics.median(times)
    print(f"one target from the maps: median {1e3 * med:.1f} ms, max {1e3 * max(times):.1f} ms "
          f"(+ {1e3 * t_load:.0f} ms to load the maps once); goal < 200 ms -> {'met' if med + t_load < 0.2 else 'NOT MET'}"
          f"  [{solved}/100 reachable]")
    sim = simulator(mesh)
    reachable = [t for t in ts if _ok(ctx, t)][:5]
    t0 = time.perf_counter()
    solve(ctx, reachable[0], sim, verify=True, refine=True)
    cold = time.perf_counter() - t0
    warm = []
    for t in reachable[1:]:
        t0 = time.perf_counter()
        solve(ctx, t, sim, verify=True, refine=True)
        warm.append(time.perf_counter() - t0)
    print(f"--verify --refine: first {cold:.2f} s (builds the model and the jaw rest), then median "
          f"{statistics.median(warm):.2f} s; goal < 5 s -> {'met' if cold < 5 else 'NOT MET'}")
    t0 = time.perf_counter()
    solve_batch(ctx, ts, jobs=2)
    tb = time.perf_counter() - t0
    t0 = time.perf_counter()
    solve_batch(ctx, ts, jobs=2, sim_args=(sim.cfg, sim.mesh, sim.wall, sim.mesh_sha256), verify=True)
    tv = time.perf_counter() - t0
    print(f"batch of 100 targets: {tb:.2f} s from the maps, {tv:.1f} s with --verify on 2 workers; goal < 30 s -> "
          f"{'met' if max(tb, tv) < 30 else 'NOT MET'}")


def _ok(ctx, t) -> bool:
    try:
        solve(ctx, t)
        return True
    except Exception:  # noqa: BLE001
        return False


if __name__ == "__main__":
    main()
