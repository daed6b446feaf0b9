"""Utterances: a sequence of targets in time, with a voice (YAML, validated on load).

Example::

    name: aka
    f0_hz: [[0.0, 125], [0.6, 100]]      # [time_s, F0 Hz] points, times rising; between them linear
    ramp_ms: 30                          # optional: each target's forces ramp in over this (config speech.ramp_ms)
    lead_ms: 80                          # optional: ... starting this long before the segment (config speech.lead_ms)
    prepare_ms: 250                      # optional: the first segment's, this long before the sound (speech.prepare_ms)
    force_course: static                 # optional: or pulse_step (config speech.force_course)
    segments:
      - {target: configs/targets/vowels/a.yaml, duration_ms: 250}
      - {target: configs/targets/consonants/k.yaml, duration_ms: 80, voiced: false, lead_ms: 140, press: 1.5}
      - target: {name: a_open, jaw: {forces_n: {JO: 2.5}}, acoustic: {formants_hz: [753, 1385]}}   # inline
        duration_ms: 250
      - {phoneme: g, duration_ms: 70}     # a phoneme of the inventory (configs/phonemes/japanese.yaml)
      - {forces_n: {JO: 1.0, GGp: 2.0}, duration_ms: 100, label: push}     # forces given, nothing solved
    tract:                               # optional lip, velum and glottis course on top of the targets'
      - {at_ms: 250, ramp_ms: 40, lip_area_cm2: 0.0}
      - {at_ms: 330, ramp_ms: 30, glottis_cm2: 0.3, velum_port_cm2: 0.5}
    tiers:                               # optional TextGrid tiers beside 'phones' (the front end's morae, words)
      words: [{start_ms: 0, end_ms: 600, label: aka}]

A segment's ``lead_ms`` overrides the utterance's for its forces alone (a stop's closing gesture starts earlier,
its release comes with the next segment's forces); ``press`` scales a solved target's tongue-muscle forces, up
to ``muscles.max_force_n`` (a stop presses on the wall: a virtual target beyond it; the jaw's forces are kept;
below 1 it softens them, as a channel too narrow needs); ``drive`` scales the pulse that opens the segment's
forces in the pulse-step course (``speech.pulse_gain`` x this: above 1 a vowel too short to be reached otherwise
gets there sooner, below 1 a movement faster than a speaker's is slowed).

A target path is read relative to the working folder, else to the utterance file's folder.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from ..config import read_yaml
from ..errors import ArticError
from ..schedule import TractEntry
from ..validation import DurationMs, ForceN, SafeName, Strict, increasing, parse

MAX_UTTERANCE_MS = 20000.0


class Segment(Strict):
    target: str | dict | None = None  # a target file, or a target inline
    forces_n: dict[str, ForceN] | None = None  # ... or the forces themselves (muscles, jaw units, groups)
    phoneme: str | None = None  # ... or a phoneme of the inventory (its target and controls made from it)
    hold: bool = False  # ... or the forces of the segment before (a bilabial's tongue is its neighbours')
    continues: bool = False  # the same phone as the segment before (an affricate's release): one interval
    duration_ms: DurationMs
    voiced: bool = True  # the glottis adducted (vocal_tract.glottis_cm2) or abducted (speech.glottal_area_voiceless_cm2)
    glottis_cm2: Annotated[float, Field(ge=0, le=2, allow_inf_nan=False)] | None = None  # ... or this opening
    # the cavity enlarging at this rate while the closure the segment makes lasts (a voiced stop or tap)
    cavity_expansion_cm3_s: Annotated[float, Field(ge=0, le=500, allow_inf_nan=False)] | None = None
    devoiced: bool = False  # a vowel phoneme spoken voiceless (the glottis open; its tongue and lips kept)
    label: SafeName | None = None  # the TextGrid's label (default: the target's name)
    lead_ms: Annotated[float, Field(ge=0, le=300, allow_inf_nan=False)] | None = None  # else the utterance's
    press: Annotated[float, Field(ge=0.5, le=3, allow_inf_nan=False)] = 1.0  # the target's tongue forces x this (below 1: softer)
    drive: Annotated[float, Field(ge=0, le=4, allow_inf_nan=False)] = 1.0  # its opening pulse's gain x this

    @model_validator(mode="after")
    def _one_source(self):
        given = [k for k in ("target", "forces_n", "phoneme") if getattr(self, k) is not None] + (
            ["hold"] if self.hold else [])
        if len(given) != 1:
            raise ValueError("give either 'target' (a target file or one inline), 'phoneme' (a symbol of the "
                             "inventory) or 'forces_n', one of them")
        if self.devoiced and self.phoneme is None:
            raise ValueError("'devoiced' belongs to a vowel phoneme segment ({phoneme: u, devoiced: true})")
        if self.forces_n is not None and self.press != 1.0:
            raise ValueError("'press' scales a solved target's forces; with 'forces_n' give the pressed forces")
        return self


class Interval(Strict):
    start_ms: Annotated[float, Field(ge=0, allow_inf_nan=False)]
    end_ms: Annotated[float, Field(gt=0, allow_inf_nan=False)]
    label: str


class Utterance(Strict):
    name: SafeName = "utterance"
    segments: Annotated[list[Segment], Field(min_length=1)]
    f0_hz: list[Annotated[list[Annotated[float, Field(allow_inf_nan=False)]], Field(min_length=2, max_length=2)]] = \
        [[0.0, 120.0]]
    ramp_ms: Annotated[float, Field(ge=0, le=500, allow_inf_nan=False)] | None = None
    lead_ms: Annotated[float, Field(ge=0, le=300, allow_inf_nan=False)] | None = None  # else speech.lead_ms
    prepare_ms: Annotated[float, Field(ge=0, le=1000, allow_inf_nan=False)] | None = None  # else speech.prepare_ms
    force_course: Literal["static", "pulse_step"] | None = None  # the config's speech.force_course otherwise
    tract: list[TractEntry] = []
    tiers: dict[str, list[Interval]] = {}

    @field_validator("f0_hz")
    @classmethod
    def _contour(cls, v):
        if not v:
            raise ValueError("give at least one [time_s, f0_hz] point")
        for k, (t, f) in enumerate(v):
            if t < 0:
                raise ValueError(f"point {k}: time {t:g} s is negative")
            if not 50 <= f <= 500:
                raise ValueError(f"point {k}: F0 {f:g} Hz is outside 50-500 Hz")
        increasing([t for t, _ in v], "times must rise strictly (no overlapping or unsorted points)")
        return v

    @model_validator(mode="after")
    def _length(self):
        total = self.duration_ms
        if total > MAX_UTTERANCE_MS:
            raise ValueError(f"the segments last {total:g} ms, above the {MAX_UTTERANCE_MS:g}-ms limit")
        for k, e in enumerate(self.tract):
            if e.at_ms >= total:
                raise ValueError(f"tract[{k}].at_ms = {e.at_ms:g} is not inside the utterance (its segments end at "
                                 f"{total:g} ms); move the entry or lengthen a segment")
        for name, tier in self.tiers.items():
            if name == "phones":
                raise ValueError("tiers.phones: the phones tier is made from the segments; name yours otherwise")
            end = 0.0
            for k, iv in enumerate(tier):
                if iv.start_ms < end - 1e-6 or iv.end_ms <= iv.start_ms or iv.end_ms > total + 1e-6:
                    raise ValueError(f"tiers.{name}[{k}]: {iv.start_ms:g}-{iv.end_ms:g} ms must follow the one "
                                     f"before, end after it starts and lie inside the {total:g}-ms utterance")
                end = iv.end_ms
        return self

    @property
    def duration_ms(self) -> float:
        return float(sum(s.duration_ms for s in self.segments))

    def leads_ms(self, default_ms: float) -> list[float]:
        """Each segment's lead (ms): its own, else the utterance's, else ``default_ms``."""
        base = default_ms if self.lead_ms is None else self.lead_ms
        return [base if s.lead_ms is None else s.lead_ms for s in self.segments]

    def starts_ms(self) -> list[float]:
        out, t = [], 0.0
        for s in self.segments:
            out.append(t)
            t += s.duration_ms
        return out


def parse_utterance(data: object, source: str = "<utterance>") -> Utterance:
    return parse(Utterance, data, source, "utterance (with 'segments', each a target or forces_n and a duration_ms)",
                 "fix the utterance and rerun")


def load_utterance(path: Path | str) -> Utterance:
    return parse_utterance(read_yaml(path, "utterance file"), str(path))


def target_path(ref: str, utterance_path: Path | str | None) -> Path:
    """A segment's target file: relative to the working folder, else to the utterance's folder."""
    p = Path(ref)
    if p.is_file() or p.is_absolute() or utterance_path is None:
        return p
    beside = Path(utterance_path).parent / p
    return beside if beside.is_file() else p


def check_forces(u: Utterance, valid: list[str], source: str) -> None:
    for k, s in enumerate(u.segments):
        for name in (s.forces_n or {}):
            if name not in valid:
                raise ArticError(f"{source}: segments[{k}].forces_n: '{name}' is unknown; valid: {', '.join(valid)}")


__all__ = ["Interval", "Segment", "Utterance", "load_utterance", "parse_utterance", "target_path", "check_forces"]
