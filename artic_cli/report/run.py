"""The report's run section: how long make paper took."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from .rows import Row, verdict


PAPER_GOAL_MIN = 15.0  # make paper from scratch on two cores (the vowels issue's goal)


PAPER_RUN_ENV = "ARTIC_PAPER_RUN"  # set by the Makefile for make paper: "START_EPOCH_S FROM_SCRATCH(0|1) JOBS"


def paper_run(value: str | None) -> tuple[float, bool, int] | None:
    """``ARTIC_PAPER_RUN``'s start (s since the epoch), whether OUT held no artefact then, stages at a time."""
    parts = (value or "").split()
    if len(parts) != 3:
        return None
    try:
        start, scratch, jobs = float(parts[0]), parts[1] == "1", int(parts[2])
    except ValueError:
        return None
    return (start, scratch, jobs) if np.isfinite(start) and jobs >= 1 else None


def run_section(data: Path, now_s: float | None = None) -> tuple[list[Row], list[str]]:
    """How long this ``make paper`` took, from its start to this report (the report is its last step)."""
    run = paper_run(os.environ.get(PAPER_RUN_ENV))
    item = "make paper's wall time, from its start to this report"
    goal = f"<= {PAPER_GOAL_MIN:g} min from scratch on 2 cores (goal)"
    if run is None:
        return [Row(item, goal, "not timed", "not compared (the report was written outside make paper)")], []
    start, scratch, jobs = run
    minutes = ((time.time() if now_s is None else now_s) - start) / 60.0
    ours = f"{minutes:.1f} min ({jobs} stage{'s' if jobs > 1 else ''} at a time{', from scratch' if scratch else ''})"
    if not scratch:
        return [Row(item, goal, ours, "not compared (OUT held artefacts: only what changed was rebuilt)")], []
    return [Row(item, goal, ours, verdict(minutes <= PAPER_GOAL_MIN, f"goal <= {PAPER_GOAL_MIN:g} min"))], []
