"""Typed Japanese in, an utterance of phonemes out (docs/inventory.md, "Words"): words of morae
(:mod:`.romaji`), devoiced high vowels (:mod:`.devoicing`), mora-timed durations (:mod:`.durations`), a Tokyo
F0 contour from the accents (:mod:`.accent`), and the TextGrid's ``morae`` and ``words`` tiers."""

from __future__ import annotations

import re

from typing import Annotated

from pydantic import Field

from ..errors import ArticError
from ..validation import SafeName, Strict, parse
from .accent import f0_points
from .devoicing import devoice
from .durations import mora_phones_ms
from .inventory import Inventory
from .romaji import Word, words
from .textgrid import PAUSE
from .utterance import Utterance, parse_utterance

MAX_MORAE = 200
RATES = (0.5, 2.0)


def text_name(text: str, phrases: list[list[Word]] | None = None) -> str:
    """A file name for the text: its letters, an accent mark as '-', spaces and pauses as '_'; kana and
    macrons as the romaji of their morae (``phrases``)."""
    if not text.isascii() and phrases:
        text = "_".join("".join(_ascii(w) for w in p) for p in phrases)
    name = re.sub(r"[^A-Za-z0-9_-]+", "_", text.strip().replace("'", "-")).strip("_")
    if not name:
        raise ArticError("--text: give some romaji, e.g. --text aga")
    return name[:60]


def _ascii(w: Word) -> str:
    labels = [m.label for m in w.morae]
    return "".join(("n" if lab == "N" else (labels[k + 1][0] if lab == "Q" and k + 1 < len(labels) else lab))
                   for k, lab in enumerate(labels))


def phrases_of(text: str, inv: Inventory, accent: int | None = None) -> list[list[Word]]:
    """The text's phrases (parted by ','), each its words with their devoiced morae marked; every limit checked.
    ``accent``: the mora a one-word text's pitch falls after (0: unaccented), for a text without a mark."""
    out: list[list[Word]] = [[]]
    for w in words(text):
        if w is None:
            out.append([])
        else:
            out[-1].append(w)
    out = [p for p in out if p]
    if not out:
        raise ArticError("--text: give some romaji, e.g. --text aga")
    n = sum(len(w.morae) for p in out for w in p)
    if n > MAX_MORAE:
        raise ArticError(f"--text: {n} morae is more than the {MAX_MORAE} spoken at once; split the text")
    if accent is not None:
        _set_accent(out, accent)
    for p in out:
        morae = [m for w in p for m in w.morae]
        starts = [0]
        for w in p:
            starts.append(starts[-1] + len(w.morae))
        accented = {s + w.accent - 1 for s, w in zip(starts, p) if w.accent is not None}
        devoice(morae, accented, inv)
    return out


def _set_accent(phrases: list[list[Word]], accent: int) -> None:
    ws = [w for p in phrases for w in p]
    if len(ws) != 1 or ws[0].accent is not None:
        raise ArticError(f"accent {accent}: an accent column is for one word without an accent mark; mark the "
                         "accents in the text instead (e.g. ha'shi)")
    if accent > len(ws[0].morae):
        raise ArticError(f"accent {accent}: '{ws[0].text}' has {len(ws[0].morae)} morae; give 0 (unaccented) to "
                         f"{len(ws[0].morae)}")
    ws[0].accent = accent or None


def utterance_of_text(text: str, inv: Inventory, name: str | None = None, rate: float = 1.0,
                      f0_range_hz: tuple[float, float] | None = None, accent: int | None = None) -> Utterance:
    """The text as an utterance: each phone of its morae a phoneme segment at its mora-timed duration, a pause a
    silent segment (the glottis shut), the F0 from its accents, its morae and words as tiers."""
    if not RATES[0] <= rate <= RATES[1]:
        raise ArticError(f"--rate {rate:g}: give a factor from {RATES[0]:g} to {RATES[1]:g} (1: the inventory's "
                         "mora timing)")
    if f0_range_hz is not None and not 50 <= f0_range_hz[0] < f0_range_hz[1] <= 500:
        raise ArticError(f"--f0-range {f0_range_hz[0]:g},{f0_range_hz[1]:g}: give LOW,HIGH in Hz with "
                         "50 <= LOW < HIGH <= 500")
    segments: list[dict] = []
    morae_tier, words_tier, timed = [], [], []
    t = 0.0
    phrases = phrases_of(text, inv, accent)
    for n, phrase in enumerate(phrases):
        if n:
            d = inv.timing.pause_ms / rate
            segments.append({"hold": True, "voiced": False, "glottis_cm2": 0.0, "duration_ms": d, "label": PAUSE})
            t += d
        durs = iter(mora_phones_ms([m for w in phrase for m in w.morae], inv, rate))
        timed.append([])
        for w in phrase:
            start, spans = t, []
            for m in w.morae:
                d = next(durs)
                if not m.phones:  # a long vowel's second mora: the vowel lasts on
                    segments[-1]["duration_ms"] += d[0]
                for sym, ms in zip(m.phones, d):
                    seg = {"phoneme": sym, "duration_ms": ms}
                    if m.devoiced and sym == m.vowel:
                        seg["devoiced"] = True
                    segments.append(seg)
                spans.append((t, t + sum(d)))
                morae_tier.append({"start_ms": t, "end_ms": t + sum(d), "label": m.label})
                t += sum(d)
            words_tier.append({"start_ms": start, "end_ms": t, "label": w.text})
            timed[-1].append((spans, w.accent))
    return parse_utterance({"name": name or text_name(text, phrases), "segments": segments,
                            "f0_hz": f0_points(timed, inv.pitch, f0_range_hz),
                            "tiers": {"morae": morae_tier, "words": words_tier}}, f"--text {text!r}")


class TextUtterance(Strict):
    """An utterance file that gives text (``configs/words/*.yaml``): ``{name: kitte, text: kitte}``, optionally a
    ``rate`` and an ``f0_range_hz`` [low, high]."""

    name: SafeName | None = None
    text: str
    rate: Annotated[float, Field(ge=RATES[0], le=RATES[1], allow_inf_nan=False)] = 1.0
    f0_range_hz: Annotated[list[Annotated[float, Field(ge=50, le=500, allow_inf_nan=False)]],
                           Field(min_length=2, max_length=2)] | None = None


def text_utterance(data: dict, source: str, inv: Inventory) -> Utterance:
    t = parse(TextUtterance, data, source, "text utterance (name, text, rate, f0_range_hz)", "fix it and rerun")
    try:
        return utterance_of_text(t.text, inv, t.name, t.rate, None if t.f0_range_hz is None else tuple(t.f0_range_hz))
    except ArticError as err:
        raise ArticError(f"{source}: {err}") from None


__all__ = ["TextUtterance", "text_utterance", "utterance_of_text", "text_name", "phrases_of", "MAX_MORAE"]
