"""Romaji in, an utterance of phonemes out: each phone of the inventory at its default duration, F0 falling
over the whole (the nine hand-built utterances' 125 -> 100 Hz)."""

from __future__ import annotations

import re

from ..errors import ArticError
from .inventory import Inventory
from .utterance import Utterance, parse_utterance

F0_START_HZ, F0_END_HZ = 125.0, 100.0


def text_name(text: str) -> str:
    """A file name for the text: its letters, spaces as '_'."""
    name = re.sub(r"[^A-Za-z0-9_-]+", "_", text.strip()).strip("_")
    if not name:
        raise ArticError("--text: give some romaji, e.g. --text aga")
    return name[:60]


def utterance_of_text(text: str, inv: Inventory, name: str | None = None) -> Utterance:
    phones = inv.phones(text)
    if not phones:
        raise ArticError("--text: give some romaji, e.g. --text aga")
    segments = [{"phoneme": p, "duration_ms": inv.phonemes[p].duration_ms} for p in phones]
    total_s = sum(s["duration_ms"] for s in segments) / 1e3
    return parse_utterance({"name": name or text_name(text), "segments": segments,
                            "f0_hz": [[0.0, F0_START_HZ], [total_s, F0_END_HZ]]}, f"--text {text!r}")


__all__ = ["utterance_of_text", "text_name"]
