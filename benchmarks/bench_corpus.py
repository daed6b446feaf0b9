"""Speed of `artic corpus` on dask.distributed (issue "A corpus of speech from muscles").

1. The 100 words of benchmarks/words100.tsv from nothing (an empty solutions folder) on a LocalCluster of 2
   workers: the wall time, items per minute, each worker's peak memory.
2. Its first 20 words again into fresh folders (the solutions and their cache now kept: each word's targets
   solved and its gestures timed) with 1 worker and with 2: items per minute each, and the ratio (goal: at
   least 1.6 on this 2-core machine).

Each time is the whole run as the CLI does it: the cluster started, the items spoken, the index and the card
written.  Unreachable targets are spoken at their nearest answers, as `make utterances` speaks them.  Needs
data/mesh.h5, data/epmaps.h5, data/acoustic_maps.h5 and data/dynamic.h5.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", NUMBA_NUM_THREADS="1")

ROOT = Path(__file__).resolve().parents[1]
WORDS = ROOT / "benchmarks" / "words100.tsv"
SUBSET = 20


def run(listing: Path, out: Path, solutions: Path, jobs: int):
    from artic_cli.stages.corpus import Setup, run_corpus

    data = ROOT / "data"
    setup = Setup(maps=str(data / "epmaps.h5"), mesh=str(data / "mesh.h5"),
                  acoustic_maps=str(data / "acoustic_maps.h5"), dynamic=str(data / "dynamic.h5"), solutions=str(solutions), accept_nearest=True)
    t0 = time.perf_counter()
    res = run_corpus(listing, out, setup, jobs=jobs)
    return time.perf_counter() - t0, res


def main() -> None:
    lines = [ln for ln in WORDS.read_text().splitlines() if ln and not ln.startswith("#")]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        sol = tmp / "solutions"
        wall, res = run(WORDS, tmp / "hundred", sol, 2)
        ok = sum(r["status"] == "ok" for r in res.rows)
        speech = sum(float(r["duration_s"] or 0) for r in res.rows)
        print(f"100-word corpus from nothing, 2 workers: {wall:.0f} s ({len(res.rows) / wall * 60:.1f} items/min), "
              f"{ok} spoken ({speech:.1f} s of speech), {len(res.failed)} not")
        print(f"  peak memory per worker: {', '.join(f'{mb:.0f} MB' for mb in sorted(res.peak_mb.values()))}")
        sub = tmp / "subset.tsv"
        sub.write_text("\n".join(lines[:SUBSET]) + "\n")
        rates = {}
        for jobs in (1, 2):
            wall, res = run(sub, tmp / f"subset{jobs}", sol, jobs)
            rates[jobs] = len(res.rows) / wall * 60
            print(f"{SUBSET} words, targets solved and timed, {jobs} worker(s): {wall:.1f} s, {rates[jobs]:.1f} items/min, "
                  f"peak memory per worker {max(res.peak_mb.values()):.0f} MB")
        ratio = rates[2] / rates[1]
        print(f"items/min 2 workers / 1 worker: {ratio:.2f} (goal >= 1.6: {'met' if ratio >= 1.6 else 'NOT MET'})")


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    main()
