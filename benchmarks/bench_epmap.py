"""Speed of the EP maps (issue "Equilibrium-position maps at nine jaw positions").

Goal: every single-muscle map at the nine jaw positions (864 EPs with the
zero levels) plus the two- and three-muscle maps at the typical jaw position
in at most 5 minutes of wall time on this 2-core machine.  Prints equilibria
per second, the wall time of the full build with 2 workers (and with
``--fast``), and the parallel efficiency from 1 to 2 workers on the rest
jaw's single-muscle vectors.  Every build starts from an empty cache.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import yaml

from artic_cli.config import load_config
from artic_cli.control.epmap import plan
from artic_cli.stages.epmap import build_ep_maps
from artic_cli.stages.mesh import build_mesh

ROOT = Path(__file__).resolve().parent.parent
GOAL_S = 300.0


def _build(tmp: Path, cfg: Path, name: str, jobs: int, fast: bool = False) -> tuple[float, int]:
    t0 = time.perf_counter()
    r = build_ep_maps(tmp / "mesh.h5", cfg, tmp / f"{name}.h5", jobs=jobs, fast=fast, cache=tmp / f"cache-{name}")
    return time.perf_counter() - t0, r.total


def main() -> None:
    quick = "--quick" in sys.argv  # skip the full builds (for a smoke run)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        build_mesh(ROOT / "configs" / "default.yaml", tmp / "mesh.h5")
        data = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
        data["epmap"] = {"jaw_positions": {"rest": {}}, "typical_jaw": "rest", "net_jaw_positions": [],
                         "pairs_tip": [], "pairs_dorsum": [], "groups": []}
        small = tmp / "rest.yaml"
        small.write_text(yaml.safe_dump(data))
        t1, n = _build(tmp, small, "rest-1", 1)
        t2, _ = _build(tmp, small, "rest-2", 2)
        print(f"rest jaw, single-muscle vectors ({n} EPs incl. the rest): 1 worker {t1:.1f} s "
              f"({n / t1:.2f} EP/s), 2 workers {t2:.1f} s ({n / t2:.2f} EP/s); parallel efficiency "
              f"{t1 / (2 * t2):.0%}")
        if quick:
            return
        cfg = ROOT / "configs" / "default.yaml"
        total = len(plan(load_config(cfg).epmap)) + len(load_config(cfg).epmap.jaw_positions)
        tf, n = _build(tmp, cfg, "full", 2)
        verdict = "met" if tf <= GOAL_S else "NOT MET"
        print(f"full default map ({n} EPs: 9 jaw positions x 12 vectors x 8 levels, 18 pair nets and 5 groups at "
              f"JO_0.5): {tf:.0f} s with 2 workers, {n / tf:.2f} EP/s (goal <= {GOAL_S:.0f} s) -> {verdict}")
        tq, _ = _build(tmp, cfg, "fast", 2, fast=True)
        print(f"the same with --fast (each EP stopped once settled): {tq:.0f} s, {n / tq:.2f} EP/s")
        assert n == total


if __name__ == "__main__":
    main()
