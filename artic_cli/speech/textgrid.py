"""An utterance's segments as a Praat TextGrid."""

from __future__ import annotations

from pathlib import Path

from ..io.store import atomic_path


def write_textgrid(path: Path | str, p) -> Path:
    """One interval tier 'segments' from a plan's labels, starts and durations (Praat reads it directly)."""
    from praatio import textgrid

    edges = [round(float(v), 9) for v in (*p.starts_s, p.starts_s[-1] + p.durations_s[-1])]
    tier = textgrid.IntervalTier("segments", [(a, b, lab) for a, b, lab in zip(edges[:-1], edges[1:], p.labels)],
                                 0.0, edges[-1])
    tg = textgrid.Textgrid()
    tg.addTier(tier)
    with atomic_path(path, ".TextGrid") as tmp:
        tg.save(str(tmp), format="long_textgrid", includeBlankSpaces=True)
    return Path(path)
