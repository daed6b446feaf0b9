"""An utterance's phones as a Praat TextGrid."""

from __future__ import annotations

from pathlib import Path

from ..io.store import atomic_path

TIER = "phones"


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
    return [tuple(i) for i in out]


def write_textgrid(path: Path | str, p) -> Path:
    """One interval tier 'phones' from a plan's labels, starts and durations (Praat reads it directly)."""
    from praatio import textgrid

    iv = intervals(p)
    tier = textgrid.IntervalTier(TIER, iv, 0.0, iv[-1][1])
    tg = textgrid.Textgrid()
    tg.addTier(tier)
    with atomic_path(path, ".TextGrid") as tmp:
        tg.save(str(tmp), format="long_textgrid", includeBlankSpaces=True)
    return Path(path)


def read_phones(path: Path | str) -> list[tuple[float, float, str]]:
    """(start s, end s, label) of the first tier's non-empty intervals (the tier 'phones' of a spoken record)."""
    from praatio import textgrid

    tg = textgrid.openTextgrid(str(path), includeEmptyIntervals=False)
    return [(e.start, e.end, e.label) for e in tg.getTier(tg.tierNames[0]).entries]

