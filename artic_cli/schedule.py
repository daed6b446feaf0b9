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
    tract:                    # the lip tube and the velopharyngeal port (read by 'artic vocal-tract')
      - at_ms: 100            # from here the values move to these ...
        ramp_ms: 60           # ... along a raised cosine over this time
        lip_area_cm2: 0.4
        lip_length_cm: 1.5
        velum_port_cm2: 0.0

The mechanics ignore ``tract``: a change there leaves every simulation up to date.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, ValidationInfo, field_validator

from .config import read_yaml
from .errors import ArticError
from .validation import (DEFAULT_MAX_FORCE_N, AreaCm2, DurationMs, ForceN, LoadN, NonNegative, OnsetMs, Strict,
                         parse)


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


class TractEntry(Strict):
    """From ``at_ms`` the given tract controls move to their new values over ``ramp_ms`` (a raised cosine, or
    at a constant rate: ``ramp: linear``)."""

    at_ms: OnsetMs
    ramp_ms: NonNegative = 50.0
    ramp: Literal["cosine", "linear"] = "cosine"
    lip_area_cm2: AreaCm2 | None = None
    lip_length_cm: Annotated[float, Field(gt=0, le=3, allow_inf_nan=False)] | None = None
    velum_port_cm2: AreaCm2 | None = None
    glottis_cm2: Annotated[float, Field(ge=0, le=2, allow_inf_nan=False)] | None = None  # its mean opening
    # the cavity's active enlargement (a lowered larynx, an advanced tongue root) beyond its shape's volume
    cavity_expansion_cm3: Annotated[float, Field(ge=0, le=30, allow_inf_nan=False)] | None = None


TRACT_CONTROLS = ("lip_area_cm2", "lip_length_cm", "velum_port_cm2", "glottis_cm2", "cavity_expansion_cm3")


def tract_controls(entries: list[TractEntry], start: dict[str, float], time_s) -> dict[str, np.ndarray]:
    """Each tract control at ``time_s`` (s): ``start`` values, then each entry's ramp from the value
    reached so far to its own (a smooth time course, like a muscle force's)."""
    t_ms = np.asarray(time_s, dtype=float) * 1e3
    out = {}
    for name in TRACT_CONTROLS:
        if name not in start:  # a control the caller does not drive
            continue
        value = np.full_like(t_ms, float(start[name]))
        for e in sorted(entries, key=lambda e: e.at_ms):
            target = getattr(e, name)
            if target is None:
                continue
            before = float(np.interp(e.at_ms, t_ms, value)) if len(t_ms) else float(start[name])
            if e.ramp_ms > 0:
                u = np.clip((t_ms - e.at_ms) / e.ramp_ms, 0.0, 1.0)
                w = u if e.ramp == "linear" else 0.5 - 0.5 * np.cos(np.pi * u)
            else:
                w = (t_ms >= e.at_ms).astype(float)
            value = np.where(t_ms >= e.at_ms, before + (target - before) * w, value)
        out[name] = value
    return out


class Schedule(Strict):
    duration_ms: DurationMs | None = None
    muscles: list[MuscleEntry] = []
    loads: list[LoadEntry] = []
    tract: list[TractEntry] = []

    def mechanics_digest_data(self) -> dict:
        """What the mechanics read (the tract controls left out)."""
        return self.model_dump(mode="json", exclude={"tract"})

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


__all__ = ["Schedule", "LoadEntry", "MuscleEntry", "TractEntry", "TRACT_CONTROLS", "load_schedule", "parse_schedule",
           "tract_controls"]
