"""Speed of saying a word from text (issue "Say any Japanese word").

Goals on one core: a new four-mora word, its targets not yet cached (an empty solutions folder; the maps built),
in at most 20 s; and, with its targets solved, 1 s of speech in at most 1 s (in-process: ``bench_speak.py``
times the simulation and sound of 1 s once the forces are known).  Here each figure is the command's whole wall
time as a user sees it (start-up, model, plan, the timing's rounds, simulation, sound, files); warm is the
median of three runs with the solutions kept and the record removed, given per second of speech.  Needs
data/mesh.h5, data/epmaps.h5, data/acoustic_maps.h5 and data/dynamic.h5.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ARTIC = Path(sys.executable).with_name("artic")
ENV = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
WORD = "sayonara"  # four morae: sa yo na ra; no other word of configs/words shares its record


def run(out: Path, solutions: Path) -> tuple[float, float, str]:
    """(wall s, speech s, the timing line) of one ``artic speak --text WORD``."""
    t0 = time.perf_counter()
    res = subprocess.run([str(ARTIC), "speak", "--text", WORD, "--out", str(out), "--solutions", str(solutions),
                          "--accept-nearest", "--jobs", "1"], cwd=ROOT, env=ENV, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if res.returncode != 0:
        sys.exit(f"error: artic speak --text {WORD} failed (exit {res.returncode}): {res.stderr.strip()[-400:]}")
    said = re.search(r"\(([\d.]+) s\)", res.stdout + res.stderr)
    timing = next((ln for ln in (res.stdout + res.stderr).splitlines() if ln.startswith("timing:")), "")
    return wall, float(said.group(1)) if said else float("nan"), timing


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        out, sol = tmp / f"{WORD}.wav", tmp / "solutions"
        cold, speech_s, timing = run(out, sol)
        warm = []
        for _ in range(3):
            out.with_suffix(".h5").unlink()  # the record gone: spoken again from the cached solutions
            warm.append(run(out, sol)[0])
        solved = len(list(sol.glob("*.yaml")))
    w = float(np.median(warm))
    print(f"artic speak --text {WORD} (4 morae, {speech_s:.2f} s of speech), cold ({solved} solution files "
          f"written): {cold:.1f} s wall on one core (goal <= 20 s) -> {'met' if cold <= 20.0 else 'NOT MET'}")
    print(f"  {timing[:100]}")
    print(f"artic speak --text {WORD}, warm (targets cached; median of 3: {', '.join(f'{v:.1f}' for v in warm)} s): "
          f"{w:.1f} s, {w / speech_s:.1f} s per second of speech (the whole command: start-up, the timing's "
          "rounds and the files included)")


if __name__ == "__main__":
    main()
