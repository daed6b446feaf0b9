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

from pydantic import Field, ValidationError

from .config import Strict, read_yaml
from .errors import ArticError

Finite = Annotated[float, Field(allow_inf_nan=False)]


class LoadEntry(Strict):
    nodes: str
    force_n: Annotated[list[Finite], Field(min_length=3, max_length=3)]
    onset_ms: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 0.0
    duration_ms: Annotated[float, Field(gt=0, allow_inf_nan=False)]


class MuscleEntry(Strict):
    muscle: str
    force_n: Annotated[float, Field(ge=0, allow_inf_nan=False)]
    onset_ms: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 0.0
    duration_ms: Annotated[float, Field(gt=0, allow_inf_nan=False)]


class Schedule(Strict):
    duration_ms: Annotated[float, Field(gt=0, allow_inf_nan=False)] | None = None
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


def parse_schedule(data: object, source: str = "<schedule>") -> Schedule:
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ArticError(f"{source}: a schedule must be a YAML mapping with a 'loads' list")
    try:
        return Schedule.model_validate(data)
    except ValidationError as err:
        first = err.errors()[0]
        loc = ".".join(str(p) for p in first["loc"])
        if first["type"] == "extra_forbidden":
            raise ArticError(f"schedule error: {source}: unknown key '{loc}'; valid keys are duration_ms, muscles "
                             "(muscle, force_n, onset_ms, duration_ms), loads (nodes, force_n, onset_ms, "
                             "duration_ms)") from None
        raise ArticError(f"schedule error: {source}: key '{loc}': {first['msg']}") from None


def load_schedule(path: Path | str) -> Schedule:
    return parse_schedule(read_yaml(path, "schedule"), str(path))


__all__ = ["Schedule", "LoadEntry", "MuscleEntry", "load_schedule", "parse_schedule"]
