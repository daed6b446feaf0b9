"""Speed of ``artic speak --text aga`` with the maps built (issue "phoneme inventory").

Goals on one core: at most 10 s cold (its three targets solved: an empty solutions folder) and at most 3 s warm
(its targets cached: the solutions kept, the sound made again).  Each figure is the command's whole wall time,
start-up included, as a user sees it; the warm one is the median of three runs.  Needs data/mesh.h5,
data/epmaps.h5, data/acoustic_maps.h5 and data/dynamic.h5.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ARTIC = Path(sys.executable).with_name("artic")
ENV = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}


def run(out: Path, solutions: Path) -> float:
    t0 = time.perf_counter()
    res = subprocess.run([str(ARTIC), "speak", "--text", "aga", "--out", str(out), "--solutions", str(solutions),
                          "--accept-nearest"], cwd=ROOT, env=ENV, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if res.returncode != 0:
        sys.exit(f"error: artic speak --text aga failed (exit {res.returncode}): {res.stderr.strip()[-400:]}")
    return wall


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        out, sol = tmp / "aga.wav", tmp / "solutions"
        cold = run(out, sol)
        warm = []
        for _ in range(3):
            out.with_suffix(".h5").unlink()  # the record gone: spoken again from the cached solutions
            warm.append(run(out, sol))
        solved = len(list(sol.glob("*.yaml")))
    w = float(np.median(warm))
    print(f"artic speak --text aga, cold ({solved} solution files written): {cold:.1f} s wall on one core "
          f"(goal <= 10 s) -> {'met' if cold <= 10.0 else 'NOT MET'}")
    print(f"artic speak --text aga, warm (targets cached; median of 3: "
          f"{', '.join(f'{v:.1f}' for v in warm)} s): {w:.1f} s (goal <= 3 s) -> {'met' if w <= 3.0 else 'NOT MET'}")


if __name__ == "__main__":
    main()
