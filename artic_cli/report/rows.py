"""A report row and the verdicts rows share."""

from __future__ import annotations

from pathlib import Path

import h5py

from ..io.store import open_artifact
from dataclasses import dataclass


@dataclass
class Row:
    item: str
    paper: str
    ours: str
    verdict: str


# make paper runs two stages at a time: a stage's own clock may have shared the cores
BESIDE = "timed as make paper ran it, maybe beside another stage; make bench times it alone and splits the time"


def extension(attrs) -> str:
    ext = float(attrs.get("extend_ms", 0.0))
    return f" and up to {ext:g} ms more" if ext > 0 else ""


def verdict(ok: bool, detail: str) -> str:
    return ("agrees" if ok else "differs") + f" ({detail})"


def within(ratio: float, tolerance: float) -> str:
    """Verdict on ours / paper's being within ``tolerance`` (a fraction) of 1."""
    return verdict(abs(ratio - 1) <= tolerance, f"{ratio - 1:+.0%}, goal within {100 * tolerance:g} %")


def sim_file(path: Path) -> h5py.File:
    return open_artifact(path, "simulation", f"rerun 'make paper' to produce {path}")
