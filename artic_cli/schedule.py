"""Schedules: what acts on the model, when (YAML, validated on load).

Example::

    duration_ms: 300          # optional; --duration overrides
    muscles:
      - muscle: SG            # a muscle, a jaw unit or a group (JO, JC, T-SL)
        force_n: 4.0          # activation: the muscle's force in N at rest length
        onset_ms: 0
        duration_ms: 300
    loads:
      - nodes: tip            # a named node set of the mesh
        force_n: [0, 2.0, 0]  # total force in N, shared equally by the set's nodes
        onset_ms: 0
        duration_ms: 300
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from pydantic import Field, ValidationInfo, field_validator

from .config import read_yaml
from .errors import ArticError
from .validation import DEFAULT_MAX_FORCE_N, DurationMs, ForceN, LoadN, OnsetMs, Strict, parse


class LoadEntry(Strict):
    nodes: str
    force_n: Annotated[list[LoadN], Field(min_length=3, max_length=3)]
    onset_ms: OnsetMs = 0.0
    duration_ms: DurationMs

    @field_validator("force_n")
    @classmethod
    def _capped(cls, v, info: ValidationInfo):
        cap = (info.context or {}).get("max_force_n", DEFAULT_MAX_FORCE_N)
        size = sum(c * c for c in v) ** 0.5
        if size > cap:
            raise ValueError(f"a {size:g}-N load is above the {cap:g}-N cap (raise muscles.max_force_n in the config "
                             "if you mean it)")
        return v


class MuscleEntry(Strict):
    muscle: str
    force_n: ForceN
    onset_ms: OnsetMs = 0.0
    duration_ms: DurationMs


class Schedule(Strict):
    duration_ms: DurationMs | None = None
    muscles: list[MuscleEntry] = []
    loads: list[LoadEntry] = []

    def check_duration(self, duration_ms: float, source: str = "schedule") -> None:
        for kind, entries in (("loads", self.loads), ("muscles", self.muscles)):
            for k, e in enumerate(entries):
                if e.onset_ms >= duration_ms:
                    raise ArticError(f"{source}: {kind}[{k}].onset_ms = {e.onset_ms:g} is not before the end of the "
                                     f"run ({duration_ms:g} ms); lower the onset or lengthen --duration")

    def check_muscles(self, valid: list[str], source: str = "schedule") -> None:
        """Unknown names and overlapping entries for one muscle are errors."""
        for k, e in enumerate(self.muscles):
            if e.muscle not in valid:
                raise ArticError(f"{source}: muscles[{k}].muscle '{e.muscle}' is unknown; valid: {', '.join(valid)}")
        by_name: dict[str, list[tuple[float, float, int]]] = {}
        for k, e in enumerate(self.muscles):
            by_name.setdefault(e.muscle, []).append((e.onset_ms, e.onset_ms + e.duration_ms, k))
        for name, spans in by_name.items():
            spans.sort()
            for (a0, a1, ka), (b0, b1, kb) in zip(spans, spans[1:]):
                if b0 < a1:
                    raise ArticError(f"{source}: muscles[{ka}] and muscles[{kb}] overlap in time for '{name}'; "
                                     "give one entry per interval")


def parse_schedule(data: object, source: str = "<schedule>", max_force_n: float = DEFAULT_MAX_FORCE_N) -> Schedule:
    """A schedule from YAML data; muscle and load forces above ``max_force_n`` (N) are refused."""
    if data is None:
        data = {}
    return parse(Schedule, data, source, "schedule (with 'muscles' and/or 'loads' lists)",
                 "fix the schedule and rerun", context={"max_force_n": max_force_n})


def load_schedule(path: Path | str, max_force_n: float = DEFAULT_MAX_FORCE_N) -> Schedule:
    return parse_schedule(read_yaml(path, "schedule"), str(path), max_force_n)


__all__ = ["Schedule", "LoadEntry", "MuscleEntry", "load_schedule", "parse_schedule"]
