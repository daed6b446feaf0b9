"""An utterance's phones (and the front end's morae and words) as a Praat TextGrid."""

from __future__ import annotations

from pathlib import Path

from ..io.store import atomic_path

TIER = "phones"
PAUSE = "pause"  # a pause segment's label: silence ("") in the TextGrid


def intervals(p) -> list[tuple[float, float, str]]:
    """(start s, end s, label) of each phone: a plan's segments, those that continue the one before joined."""
    edges = [round(float(v), 9) for v in (*p.starts_s, p.starts_s[-1] + p.durations_s[-1])]
    goes_on = list(p.continues) or [False] * len(p.labels)
    out: list[list] = []
    for a, b, lab, cont in zip(edges[:-1], edges[1:], p.labels, goes_on):
        if cont and out:
            out[-1][1] = b
        else:
            out.append([a, b, lab])
    return [tuple(i) for i in out if i[2] != PAUSE]


def write_textgrid(path: Path | str, p, tiers: dict | None = None) -> Path:
    """The interval tier 'phones' from a plan's labels, starts and durations, then ``tiers`` (name -> intervals
    with ``start_ms``, ``end_ms``, ``label``; the utterance's), each as an interval tier (Praat reads it)."""
    from praatio import textgrid

    iv = intervals(p)
    end = round(float(p.starts_s[-1] + p.durations_s[-1]), 9)
    tg = textgrid.Textgrid()
    tg.addTier(textgrid.IntervalTier(TIER, iv, 0.0, end))
    for name, spans in (tiers or {}).items():
        entries = [(round(s.start_ms / 1e3, 9), round(min(s.end_ms / 1e3, end), 9), s.label) for s in spans]
        tg.addTier(textgrid.IntervalTier(name, entries, 0.0, end))
    with atomic_path(path, ".TextGrid") as tmp:
        tg.save(str(tmp), format="long_textgrid", includeBlankSpaces=True)
    return Path(path)


def read_phones(path: Path | str) -> list[tuple[float, float, str]]:
    """(start s, end s, label) of the first tier's non-empty intervals (the tier 'phones' of a spoken record)."""
    from praatio import textgrid

    tg = textgrid.openTextgrid(str(path), includeEmptyIntervals=False)
    return [(e.start, e.end, e.label) for e in tg.getTier(tg.tierNames[0]).entries]

