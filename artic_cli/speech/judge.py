"""Every phone interval of a spoken record judged: a consonant by its manner's landmark checks
(:mod:`.landmarks`), a vowel by the vowel it sounds like (:mod:`.vowel_class`), a devoiced vowel by having no
voice (Praat-like periodicity in under half of it)."""

from __future__ import annotations

import numpy as np

from .inventory import Inventory
from .landmarks import consonants, share_voiced, voiced_frames
from .vowel_class import heard_text, heard_vowels

DEVOICED = "\u0325"  # IPA's ring below: a devoiced vowel's label (u̥), no symbol of the inventory
DEVOICED_VOICE_MAX = 0.5


def devoiced_marked(iv: list[tuple[float, float, str]], starts_s, voiced, manners: dict[str, str]
                    ) -> list[tuple[float, float, str]]:
    """The phone intervals with each vowel spoken voiceless (a segment starting there with ``voiced`` False)
    labelled ``u̥``: neither heard as a vowel nor a consonant's neighbouring vowel, having no voice to measure."""
    unvoiced = {round(float(s), 6) for s, v in zip(starts_s, voiced) if not v}
    return [(a, b, lab + DEVOICED if manners.get(lab) == "vowel" and round(a, 6) in unvoiced else lab)
            for a, b, lab in iv]


def phone_results(x: np.ndarray, rate: int, iv: list[tuple[float, float, str]], time_s: np.ndarray,
                  formants_hz: np.ndarray, inv: Inventory) -> list[dict]:
    """Each judged interval (devoiced vowels marked, :func:`devoiced_marked`): label, start and end (s), kind
    (consonant, vowel, devoiced), whether it passes, and what failed."""
    manners = {k: p.manner for k, p in inv.phonemes.items()}
    means = {v: tuple(p.formants_hz[:2]) for v, p in inv.phonemes.items() if p.manner == "vowel"}
    frames = voiced_frames(x, rate)
    measured = {round(m["start_s"], 6): m for m in consonants(x, rate, iv, manners, (time_s, formants_hz), frames)}
    heard = {round(h["start_s"], 6): h for h in heard_vowels(iv, time_s, formants_hz, means)}
    out = []
    for a, b, lab in iv:
        man = manners.get(lab)
        if lab.endswith(DEVOICED):
            v = share_voiced(x, rate, a, b, frames)
            out.append({"label": lab, "start_s": a, "end_s": b, "kind": "devoiced", "ok": v < DEVOICED_VOICE_MAX,
                        "failed": [] if v < DEVOICED_VOICE_MAX else [f"voiced {100 * v:.0f} %"]})
        elif man == "vowel" and round(a, 6) in heard:
            h = heard[round(a, 6)]
            out.append({"label": lab, "start_s": a, "end_s": b, "kind": "vowel", "ok": h["ok"],
                        "failed": [] if h["ok"] else [heard_text(h)]})
        elif man not in (None, "vowel") and round(a, 6) in measured:
            m = measured[round(a, 6)]
            failed = [k for k, ok in m["checks"].items() if not ok]
            out.append({"label": lab, "start_s": a, "end_s": b, "kind": "consonant", "ok": not failed,
                        "failed": failed})
    return out


__all__ = ["DEVOICED", "devoiced_marked", "phone_results"]
