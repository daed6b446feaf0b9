"""Which articulator made a consonant: the tongue's control points at its closure against where the vowels
beside it hold them (issue 45: the tip makes /t d n s z r/ with the dorsum within 0.6 cm of the vowels'; the
dorsum makes /k g/ with the tip low).

The consonant's frame is the middle one of its narrowest tract (its closure) in its interval (30 ms either
side, as the articulators lead and lag it); the vowels' reference is the mean of their midpoints' positions
(x, y in the midsagittal plane, cm).  "Low" for the tip reads the dorsum's limit: it rises at most 0.6 cm above the
vowels' tip.
"""

from __future__ import annotations

import numpy as np

TIP_MADE = ("t", "d", "n", "s", "z", "r")
DORSUM_MADE = ("k", "g")
LIMIT_CM = 0.6
REACH_S = 0.03


def _at(rec, name: str, t: float) -> np.ndarray:
    xy = rec.control_points[name][:, :2]
    return np.array([np.interp(t, rec.time_s, xy[:, j]) for j in range(2)])


def articulators(rec, intervals: list[tuple[float, float, str]], manners: dict[str, str]) -> list[dict]:
    """For each /t d n s z r k g/ between vowels: its time (s), the dorsum's distance from the vowels' (cm),
    the tip's rise above theirs (cm), the articulator that should make it and whether it did."""
    out = []
    narrowest = rec.area_cm2.min(axis=1)
    for k, (t0, t1, lab) in enumerate(intervals):
        if lab not in TIP_MADE + DORSUM_MADE:
            continue
        vowels = [iv for iv in (intervals[k - 1] if k else None, intervals[k + 1] if k + 1 < len(intervals) else None)
                  if iv is not None and manners.get(iv[2]) == "vowel"]
        if not vowels:
            continue
        inside = (rec.time_s >= t0 - REACH_S) & (rec.time_s <= t1 + REACH_S)
        if not inside.any():
            continue
        low = np.flatnonzero(narrowest[inside] <= narrowest[inside].min() + 1e-3)
        at = float(rec.time_s[inside][low[len(low) // 2]])  # the middle of its closure (or narrowest stretch)
        mids = [0.5 * (a + b) for a, b, _ in vowels]
        ref = {n: np.mean([_at(rec, n, m) for m in mids], axis=0) for n in ("tip", "dorsum")}
        dorsum = float(np.linalg.norm(_at(rec, "dorsum", at) - ref["dorsum"]))
        tip_rise = float(_at(rec, "tip", at)[1] - ref["tip"][1])
        by = "tip" if lab in TIP_MADE else "dorsum"
        ok = dorsum <= LIMIT_CM if by == "tip" else tip_rise <= LIMIT_CM
        out.append({"symbol": lab, "at_s": at, "dorsum_cm": dorsum, "tip_rise_cm": tip_rise, "by": by,
                    "ok": bool(ok)})
    return out
