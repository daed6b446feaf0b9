"""Speed of the acoustic maps and of vowel targets (issue "Vowels").

Goals: the acoustic map of every EP at most 30 s on 2 cores; one vowel from the maps at most 0.5 s, with
--refine at most 15 s.  Needs data/epmaps.h5 and data/mesh.h5 of the default speaker (make paper).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from artic_cli.config import load_config
from artic_cli.control.targets import load_target, solve
from artic_cli.io.store import stored_content_hash
from artic_cli.stages import acoustic_map as am_stage
from artic_cli.stages import epmap as epmap_stage
from artic_cli.stages import mesh as mesh_stage
from artic_cli.stages.solve import add_formants, load_context, simulator

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "data"


def _verdict(value: float, goal: float) -> str:
    return f"(goal <= {goal:g} s) -> {'met' if value <= goal else 'NOT MET'}"


def main() -> None:
    maps, mesh = DATA / "epmaps.h5", DATA / "mesh.h5"
    if not (maps.is_file() and mesh.is_file()):
        sys.exit("bench_vowels: run 'make paper' (or artic ep-map) first")
    cfg = load_config()
    m = mesh_stage.read(mesh, cfg)
    ep = epmap_stage.read(maps, mesh)
    n = sum(int(net.converged.size) for jm in ep.jaws.values() for fam in (jm.single, jm.pair, jm.group)
            for net in fam.values()) + len(ep.jaws)
    t0 = time.perf_counter()
    acoustic = am_stage.compute(cfg, m.mesh, ep, jobs=2)
    spent = time.perf_counter() - t0
    print(f"acoustic map: {n} EPs (with the rests) in {spent:.1f} s on 2 workers, {1e3 * spent / n:.1f} ms per EP "
          f"{_verdict(spent, 30.0)}")
    t0 = time.perf_counter()
    acoustic = am_stage.compute(cfg, m.mesh, ep, mapped_lips=True, jobs=2)
    spent = time.perf_counter() - t0
    print(f"  with the config's {len(acoustic.lips)} mapped lip tubes too (the vowels' lips), as 'artic "
          f"acoustic-map' computes it: {spent:.1f} s {_verdict(spent, 30.0)}")
    with tempfile.TemporaryDirectory() as tmp:
        amaps = Path(tmp) / "acoustic_maps.h5"
        prov = am_stage.STAGE.provenance(cfg, inputs={"mesh": m.content_sha256,
                                                      "epmaps": str(stored_content_hash(maps))})
        am_stage.write(amaps, acoustic, prov)
        voicer = simulator(mesh, None, voiced=True)
        # the five vowel targets as `artic solve-target` solves them, each in a fresh context as a new process
        # would (the maps loaded, its lips' formants looked up or computed): from the maps, then with --refine
        quick, slow = {}, {}
        for name in ("a", "e", "i", "o", "u"):
            target = load_target(ROOT / "configs" / "targets" / "vowels" / f"{name}.yaml")
            times = []
            for _ in range(3):
                t0 = time.perf_counter()
                ctx = add_formants(load_context(maps, None, mesh), maps, mesh, None, amaps)
                solve(ctx, target)
                times.append(time.perf_counter() - t0)
            quick[name] = sorted(times)[1]
            t0 = time.perf_counter()
            doc = solve(ctx, target, voicer, refine=True)
            slow[name] = quick[name] + time.perf_counter() - t0
            r = doc["refined"]
            print(f"/{name}/: from the maps {1e3 * quick[name]:.0f} ms (maps loaded and solved, median of 3); "
                  f"with --refine {slow[name]:.1f} s, {r['simulations']} simulation(s), errors "
                  f"{r['errors_pct'][0]:+.1f} / {r['errors_pct'][1]:+.1f} %")
        worst = max(quick, key=quick.get)
        print(f"one vowel from the maps: slowest /{worst}/ {1e3 * quick[worst]:.0f} ms {_verdict(quick[worst], 0.5)}")
        worst = max(slow, key=slow.get)
        print(f"one vowel with --refine: slowest /{worst}/ {slow[worst]:.1f} s {_verdict(slow[worst], 15.0)}")


if __name__ == "__main__":
    main()
