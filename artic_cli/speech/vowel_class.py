"""Which vowel a vowel interval sounds like: its F1 and F2 (medians over the interval's middle half) against the
five male Japanese means, the nearest in Bark (Traunmueller's scale, ``units.hz_to_bark``) its class."""

from __future__ import annotations

import numpy as np

from .. import units


def bark_distance(a_hz, b_hz) -> float:
    """How far apart two (F1, F2) pairs (Hz) lie in Bark (NaN when either has no formants)."""
    return float(np.linalg.norm(units.hz_to_bark(np.asarray(a_hz, float)[:2]) -
                                units.hz_to_bark(np.asarray(b_hz, float)[:2])))


def nearest_vowel(f1_hz: float, f2_hz: float, means_hz: dict[str, tuple[float, float]]) -> str:
    """The vowel whose mean (F1, F2 Hz) lies nearest (F1, F2) in Bark."""
    return min(means_hz, key=lambda v: bark_distance((f1_hz, f2_hz), means_hz[v]))


def heard_vowels(intervals: list[tuple[float, float, str]], time_s: np.ndarray, formants_hz: np.ndarray,
                 means_hz: dict[str, tuple[float, float]]) -> list[dict]:
    """Each interval labelled with a vowel of ``means_hz``: its F1 and F2 over its middle half (the formant tracks
    ``formants_hz`` (F, >= 2) at ``time_s``) and the vowel nearest them."""
    out = []
    for t0, t1, label in intervals:
        if label not in means_hz:
            continue
        q = 0.25 * (t1 - t0)
        inside = (time_s >= t0 + q) & (time_s <= t1 - q)
        f1, f2 = (float(np.nanmedian(formants_hz[inside, k])) if np.isfinite(formants_hz[inside, k]).any()
                  else float("nan") for k in (0, 1))
        heard = nearest_vowel(f1, f2, means_hz) if np.isfinite(f1) and np.isfinite(f2) else ""
        out.append({"label": label, "start_s": t0, "f1_hz": f1, "f2_hz": f2, "heard": heard, "ok": heard == label})
    return out


def heard_text(h: dict) -> str:
    """What a vowel of :func:`heard_vowels` was heard as, in words: the vowel and its F1 / F2, or that it has
    no formants (the tract closed through its middle half)."""
    if not h["heard"]:
        return "no formants: the tract closed through its middle half"
    return f"heard /{h['heard']}/ ({h['f1_hz']:.0f} / {h['f2_hz']:.0f} Hz)"


__all__ = ["bark_distance", "heard_text", "heard_vowels", "nearest_vowel"]
