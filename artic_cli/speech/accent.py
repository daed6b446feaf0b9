"""A Tokyo-Japanese F0 contour from the words' accents (japanese.md, "Pitch"; Pierrehumbert & Beckman 1988).

Each word is an accentual phrase: its first mora low and the rest high up to the accented mora, low after it;
a word accented on its first mora is high-low; an unaccented word stays high to its end.  The phrase-initial
low lies ``initial_low_share`` of the range above the low level (shallower than a post-accent low), an accented
word lowers the high level of those after it (``downstep``), and both levels decline at ``declination_hz_s``
from each pause.  The contour's points lie at each mora's middle, and at the accented mora's end (the fall
comes in the mora after it)."""

from __future__ import annotations

from .inventory import Pitch

Span = tuple[float, float]  # a mora's start and end (ms)


def tones(n: int, accent: int | None) -> list[str]:
    """Each mora's tone: 'H', 'L' (after an accent) or 'l' (the phrase-initial low)."""
    if accent == 1:
        return ["H"] + ["L"] * (n - 1)
    return ["l"] + ["H" if accent is None or m <= accent else "L" for m in range(2, n + 1)]


def f0_points(phrases: list[list[tuple[list[Span], int | None]]], pitch: Pitch,
              f0_range_hz: tuple[float, float] | None = None) -> list[list[float]]:
    """[time s, F0 Hz] points for phrases of words, each word its morae's spans and its accent."""
    lo, hi = f0_range_hz if f0_range_hz is not None else pitch.f0_range_hz
    out: list[list[float]] = []
    for words in phrases:
        t0 = words[0][0][0][0]
        span = 1.0

        def level(t_ms: float, share: float) -> float:
            drop = pitch.declination_hz_s * (t_ms - t0) / 1e3
            return max(lo - drop, 50.0) + share * (hi - lo)
        for spans, accent in words:
            for (a, b), tone in zip(spans, tones(len(spans), accent)):
                share = {"H": span, "L": 0.0, "l": min(pitch.initial_low_share, span)}[tone]
                out.append([(a + b) / 2e3, level((a + b) / 2, share)])
            if accent is not None:
                b = spans[accent - 1][1]
                out.append([b / 1e3 - 1e-3, level(b - 1.0, span)])
                span *= pitch.downstep
    out.sort(key=lambda p: p[0])
    return [[round(t, 4), round(f, 2)] for t, f in out]


__all__ = ["f0_points", "tones"]
