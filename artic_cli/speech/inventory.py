"""The phoneme inventory (``configs/phonemes/japanese.yaml``): each phoneme's articulatory features, validated
on load (docs/inventory.md), and romaji split into its symbols."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Annotated, Literal

from pydantic import BeforeValidator, Field, model_validator

from ..config import read_yaml
from ..control.solver import JawSpec, Lips, TongueClass
from ..errors import ArticError
from ..validation import DurationMs, FormantHz, Strict, increasing, parse

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "configs" / "phonemes" / "japanese.yaml"
SYMBOLS = ("a i u e o k g s z t d n h b p m y r w f sh ch ts j ky gy ny hy my ry py by N Q").split()

Manner = Literal["vowel", "stop", "nasal", "fricative", "affricate", "tap", "approximant", "moraic_nasal", "geminate"]
Place = Literal["bilabial", "alveolar", "postalveolar", "palatal", "velar", "glottal"]
Height = TongueClass  # where a vowel's tongue is highest: high / mid / low x front / central / back
Area = Annotated[float, Field(gt=0, le=2, allow_inf_nan=False)]
JAW_NAME = re.compile(r"^(rest|(JO|JC)_(\d+(\.\d+)?))$")


def _jaw_position(v):
    """A jaw named as the EP maps name their jaw positions (``rest``, ``JO_6``: the opener holding 6 N, ``JC_1.5``:
    the closer 1.5 N), or ``{opening_cm: x}`` (the incisors x cm from rest)."""
    if isinstance(v, str):
        m = JAW_NAME.match(v.strip())
        if m is None:
            raise ValueError(f"jaw '{v}': give a jaw position (rest, JO_<N> or JC_<N>, e.g. JO_2.5) or "
                             "{opening_cm: x}")
        return {"forces_n": {} if m.group(1) == "rest" else {m.group(2): float(m.group(3))}}
    if isinstance(v, dict) and "forces_n" in v:
        raise ValueError("an inventory names jaw positions (rest, JO_<N>, JC_<N>) or {opening_cm: x}, not forces")
    return v


Jaw = Annotated[JawSpec, BeforeValidator(_jaw_position)]
NEEDS_PLACE = ("stop", "nasal", "fricative", "affricate", "tap", "approximant")


class Phoneme(Strict):
    manner: Manner
    place: Place | None = None
    voiced: bool = True
    channel_cm2: Area | None = None  # a fricative's or affricate's channel, a glide's narrowing
    velum_port_cm2: Annotated[float, Field(ge=0, le=2, allow_inf_nan=False)] = 0.0
    glottis_cm2: Area | None = None  # else adducted (voiced) or speech.glottal_area_voiceless_cm2
    lips: Literal["closed", "rounded", "compressed", "spread", "neutral", "open"] | Lips = "neutral"
    jaw: Jaw | None = None
    formants_hz: Annotated[list[FormantHz], Field(min_length=2, max_length=3)] | None = None
    tongue_highest: Height | None = None
    palatalized: bool = False
    closure_place: Place | None = None  # an affricate whose closure spans more than its channel's place
    like: str | None = None  # a glide: the vowel whose tongue it narrows (its non-syllabic counterpart)
    duration_ms: DurationMs

    @model_validator(mode="after")
    def _features(self):
        m = self.manner
        if m == "vowel":
            if self.formants_hz is None or self.tongue_highest is None:
                raise ValueError("a vowel needs formants_hz and tongue_highest")
            increasing(self.formants_hz, "formants must increase (F1 < F2 < F3)")
        elif self.formants_hz is not None or self.tongue_highest is not None:
            raise ValueError("formants_hz and tongue_highest belong to vowels")
        if m in NEEDS_PLACE and self.place is None:
            raise ValueError(f"a {m} needs a place")
        if m in ("fricative", "affricate", "approximant") and self.channel_cm2 is None and self.place != "glottal":
            raise ValueError(f"a {m} needs channel_cm2 (its narrowing at the place)")
        if m in ("nasal", "moraic_nasal") and self.velum_port_cm2 <= 0:
            raise ValueError("a nasal needs velum_port_cm2 > 0 (the port open)")
        if self.like is not None and m != "approximant":
            raise ValueError("like belongs to glides (approximants): the vowel whose tongue a glide narrows")
        if self.closure_place is not None and m != "affricate":
            raise ValueError("closure_place belongs to affricates (where the closure before the channel is made)")
        if m not in ("nasal", "moraic_nasal") and self.velum_port_cm2 > 0:
            raise ValueError("only nasals open the port (velum_port_cm2)")
        return self


Share = Annotated[float, Field(gt=0, lt=1, allow_inf_nan=False)]
Ms = Annotated[float, Field(ge=0, le=200, allow_inf_nan=False)]


class Realisation(Strict):
    """How entries become targets and tract controls (:mod:`artic_cli.speech.phones`)."""

    vowel_tolerance_pct: Annotated[list[Annotated[float, Field(gt=0, le=50)]], Field(min_length=2, max_length=2)] \
        = [10.0, 7.0]  # F1's and F2's
    # a vowel's tongue highest at least this far above / below / before / behind the rest tongue's, as its
    # tongue_highest names (control/solver.py, TongueHighest)
    tongue_margin_cm: Annotated[float, Field(ge=0, le=2, allow_inf_nan=False)] = 0.15
    closure_tolerance_cm2: Annotated[float, Field(gt=0, le=0.1, allow_inf_nan=False)] = 0.01
    channel_tolerance: Annotated[float, Field(gt=0, le=1, allow_inf_nan=False)] = 0.3  # a share of the channel
    affricate_closure_share: Share = 0.5  # of an affricate's duration, the rest its channel
    palatal_glide_share: Share = 0.4  # of a palatalized consonant's duration: the glide to the palate after it
    palatal_glide_cm2: Annotated[float, Field(gt=0, le=2, allow_inf_nan=False)] = 0.3  # ... its narrowing (a
    # secondary articulation, wider than the glide /y/'s own)
    nasal_margin_ms: Ms = 30.0  # the port opens this long before a nasal and closes as long after it
    lip_closing_ms: Ms = 20.0  # a bilabial's lips close over this, shut at its start
    lip_opening_ms: Ms = 15.0  # ... and open over this from its end
    # a voiced stop, affricate or tap enlarges the cavity behind its closure at this mean rate while the closure
    # lasts (a lowered larynx, an advanced tongue root: docs/modelling.md, "Sources")
    voiced_stop_expansion_cm3_s: Annotated[float, Field(ge=0, le=500, allow_inf_nan=False)] = 120.0


Factor = Annotated[float, Field(ge=1, le=3, allow_inf_nan=False)]


class Timing(Strict):
    """Mora-timed durations (:mod:`artic_cli.speech.durations`, docs/inventory.md, "Words")."""

    mora_ms: Annotated[float, Field(ge=60, le=400, allow_inf_nan=False)] = 150.0  # at rate 1
    vowel_min_share: Share = 0.4  # of a mora: a CV mora's vowel at least this, whatever its consonant
    geminate_ratio: Annotated[float, Field(gt=1, le=5, allow_inf_nan=False)] = 2.8  # Q + C over C
    before_coda: Factor = 1.11  # a vowel before Q or N, the coda shortened as much
    devoiced_fricative_share: Share = 0.75  # of a mora: a fricative or affricate before its devoiced vowel
    final_lengthening: Factor = 1.3  # the phrase-final mora's vowel or nasal
    pause_ms: Annotated[float, Field(ge=50, le=2000, allow_inf_nan=False)] = 250.0  # a ',' at rate 1


Hz = Annotated[float, Field(ge=50, le=500, allow_inf_nan=False)]


class Pitch(Strict):
    """A Tokyo-accent F0 contour (:mod:`artic_cli.speech.accent`, docs/inventory.md, "Pitch")."""

    f0_range_hz: Annotated[list[Hz], Field(min_length=2, max_length=2)] = [95.0, 135.0]  # the low and high levels
    initial_low_share: Share = 0.4  # a phrase's first low mora: this share of the range above the low level
    declination_hz_s: Annotated[float, Field(ge=0, le=100, allow_inf_nan=False)] = 10.0  # both levels fall so
    downstep: Share = 0.7  # after an accented word, the high level keeps this share of its span

    @model_validator(mode="after")
    def _range(self):
        lo, hi = self.f0_range_hz
        if not lo < hi:
            raise ValueError(f"f0_range_hz: the low level {lo:g} Hz must be below the high {hi:g} Hz")
        return self


class Inventory(Strict):
    schema_version: Literal[1]
    language: str
    sources: list[str] = []
    places: dict[Place, str]  # a phonetic place -> the tract's place (an area-law region, lips or glottis)
    jaws: dict[Place, Jaw] = {}  # a consonant's jaw position at its place, unless its entry gives one
    vowel_jaw_beside: dict[Place, Jaw] = {}  # a vowel next to a consonant of this place: at most this open
    realisation: Realisation = Realisation()
    timing: Timing = Timing()
    pitch: Pitch = Pitch()
    phonemes: dict[str, Phoneme]

    @model_validator(mode="after")
    def _complete(self):
        missing = [s for s in SYMBOLS if s not in self.phonemes]
        if missing:
            raise ValueError(f"phonemes: missing {', '.join(missing)} (the inventory names {len(SYMBOLS)} symbols)")
        for sym, p in self.phonemes.items():
            if p.like is not None and (p.like not in self.phonemes or self.phonemes[p.like].manner != "vowel"):
                raise ValueError(f"phonemes.{sym}.like: '{p.like}' is not a vowel of the inventory")
            for key in ("place", "closure_place"):
                where = getattr(p, key)
                if where is not None and where not in self.places:
                    raise ValueError(f"phonemes.{sym}.{key}: '{where}' has no entry under 'places'")
            if p.place not in (None, "bilabial", "glottal") and p.jaw is None and p.place not in self.jaws:
                raise ValueError(f"phonemes.{sym}: place '{p.place}' has no jaw; give the entry 'jaw' or add "
                                 f"jaws.{p.place}")
        return self

    def check_places(self, tract_places: tuple[str, ...], source: str = "inventory") -> None:
        """Every place maps to one the tract has (its area law's regions, lips) or the glottis."""
        for place, where in self.places.items():
            if where != "glottis" and where not in tract_places:
                raise ArticError(f"{source}: places.{place}: '{where}' is not a place of the tract; places: "
                                 f"{', '.join(tract_places)}, glottis")

    def phones(self, text: str) -> list[str]:
        """Romaji split into the inventory's symbols, longest first (``sh`` before ``s``); ``N`` and ``Q`` as
        written; spaces between words ignored.  An unknown character is an error naming it and its place."""
        out, k = [], 0
        longest = max(len(s) for s in self.phonemes)
        while k < len(text):
            if text[k].isspace():
                k += 1
                continue
            for n in range(min(longest, len(text) - k), 0, -1):
                if text[k:k + n] in self.phonemes:
                    out.append(text[k:k + n])
                    k += n
                    break
            else:
                raise ArticError(f"--text: '{text[k]}' at position {k + 1} is not in the inventory; symbols: "
                                 f"{' '.join(self.phonemes)}")
        return out


def load_inventory(path: Path | str = DEFAULT) -> Inventory:
    return parse(Inventory, read_yaml(path, "phoneme inventory"), str(path),
                 "phoneme inventory (schema_version, places, phonemes)", "fix the inventory and rerun")


__all__ = ["Inventory", "Phoneme", "Pitch", "Realisation", "SYMBOLS", "Timing", "load_inventory"]
