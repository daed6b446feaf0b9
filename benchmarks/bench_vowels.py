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
    am_stage.compute(cfg, m.mesh, ep)
    spent = time.perf_counter() - t0
    print(f"acoustic map: {n} EPs (with the rests) in {spent:.1f} s, {1e3 * spent / n:.1f} ms per EP "
          f"{_verdict(spent, 30.0)}")
    with tempfile.TemporaryDirectory() as tmp:
        amaps = Path(tmp) / "acoustic_maps.h5"
        prov = am_stage.STAGE.provenance(cfg, inputs={"mesh": m.content_sha256,
                                                      "epmaps": str(stored_content_hash(maps))})
        am_stage.write(amaps, am_stage.compute(cfg, m.mesh, ep, jaws=["rest"]), prov)
        target = load_target(ROOT / "configs" / "targets" / "vowels" / "e.yaml")
        # at the rest jaw with neutral lips: the acoustic map's stored formants
        target = target.model_copy(update={"jaw": target.jaw.model_copy(update={"forces_n": {}}), "lips": "neutral"})
        ctx = add_formants(load_context(maps, None, mesh), maps, mesh, None, amaps)
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            try:
                solve(ctx, target.model_copy(update={"acoustic": target.acoustic.model_copy(
                    update={"formants_hz": [470.0, 1600.0]})}))
            finally:
                times.append(time.perf_counter() - t0)
        times.sort()
        print(f"one vowel from the maps (/e/-like 470 / 1600 Hz, the acoustic maps' formants): median "
              f"{1e3 * times[2]:.0f} ms, first {1e3 * times[0]:.0f} ms {_verdict(times[2], 0.5)}")
        voicer = simulator(mesh, None, voiced=True)
        t0 = time.perf_counter()
        doc = solve(ctx, target.model_copy(update={"acoustic": target.acoustic.model_copy(
            update={"formants_hz": [470.0, 1600.0], "tolerance_pct": 2.0})}), voicer, refine=True)
        spent = time.perf_counter() - t0
        r = doc["refined"]
        print(f"the same with --refine (tolerance 2 %): {spent:.1f} s, {r['simulations']} simulations, errors "
              f"{r['errors_pct'][0]:+.1f} / {r['errors_pct'][1]:+.1f} % {_verdict(spent, 15.0)}")


if __name__ == "__main__":
    main()
