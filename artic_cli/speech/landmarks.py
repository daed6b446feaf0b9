"""A consonant's acoustic landmarks, measured on the sound over its interval against the vowels beside it:
closure (duration, depth, the release after it), voicing, murmur (level, low-frequency ratio), frication
(3-8 kHz band, spectral centroid), the tap's dip, a glide's F2; and the criteria each manner is judged by
(docs/inventory.md, "Landmarks").

Levels are dB re full scale; a level "against the vowels" is the consonant's minus the mean of the
neighbouring vowels' (their middle halves).  Voicing is a Praat-like autocorrelation judgement (40-ms frames
every 5 ms, voiced when the normalised autocorrelation peaks above 0.45 between 75 and 400 Hz and the frame
is not quiet: Boersma's unvoiced strength, a threshold raised below 0.03 of the sound's peak): the tests hold these
figures to Praat's own.
"""

from __future__ import annotations

import numpy as np

from ..acoustics.measures import band_power_db, runs

FLOOR_DB = -150.0  # digital silence
VOICED_STOPS = ("b", "d", "g", "gy", "by")  # judged by a shallower closure with voicing in it
RMS_MS, STEP_MS = 5.0, 1.0


def rms_contour_db(x: np.ndarray, rate: int, win_ms: float = RMS_MS, step_ms: float = STEP_MS):
    """(times s, dB re full scale) of the RMS in ``win_ms`` windows every ``step_ms``."""
    w, h = max(int(rate * win_ms / 1e3), 1), max(int(rate * step_ms / 1e3), 1)
    c = np.concatenate([[0.0], np.cumsum(np.asarray(x, float) ** 2)])
    starts = np.arange(0, max(len(x) - w, 0) + 1, h)
    ms = (c[starts + w] - c[starts]) / w
    db = np.maximum(10 * np.log10(np.maximum(ms, 1e-300) / 0.5), FLOOR_DB)
    return (starts + w / 2) / rate, db


def voiced_frames(x: np.ndarray, rate: int, f_lo: float = 75.0, f_hi: float = 400.0, threshold: float = 0.45,
                  silence: float = 0.03):
    """(times s, voiced) of 40-ms frames every 10 ms: a periodicity above ``threshold`` between ``f_lo`` and
    ``f_hi`` in a frame whose peak is above ``silence`` of the sound's."""
    x = np.asarray(x, float)
    n, h = int(rate * 3 / f_lo), int(rate * 0.005)
    if len(x) < n:
        return np.zeros(0), np.zeros(0, bool)
    win = np.hanning(n)
    wac = np.correlate(win, win, "full")[n - 1:]
    lo, hi = int(rate / f_hi), int(rate / f_lo)
    peak = np.max(np.abs(x)) or 1.0
    times, out = [], []
    for a in range(0, len(x) - n + 1, h):
        f = x[a:a + n]
        times.append((a + n / 2) / rate)
        local = np.max(np.abs(f)) / peak
        g = (f - f.mean()) * win
        spec = np.fft.rfft(g, 2 * n)
        ac = np.fft.irfft(np.abs(spec) ** 2)[:n]
        r = ac[lo:hi] / (ac[0] * wac[lo:hi] / wac[0] + 1e-30)
        # Boersma's (1993) unvoiced strength: the threshold, raised in quiet frames (below about 0.04 of the peak)
        out.append(bool(r.max() > threshold + max(0.0, 2.0 - local / (silence / (1.0 + threshold)))))
    return np.array(times), np.array(out)


EDGE_S = 0.01  # a frame centred this near an interval's edge reaches a quarter of its window over it


def share_voiced(x, rate, t0: float, t1: float, frames=None) -> float:
    """The share of voiced frames centred in [t0, t1], each edge's ``EDGE_S`` left out (where a frame's window
    reaches the neighbour's voice)."""
    t, v = voiced_frames(x, rate) if frames is None else frames
    a, b = (t0 + EDGE_S, t1 - EDGE_S) if t1 - t0 > 4 * EDGE_S else (t0, t1)
    inside = (t >= a) & (t <= b)
    return float(v[inside].mean()) if inside.any() else 0.0


def _mid(iv):
    a, b = iv[0], iv[1]
    return a + 0.25 * (b - a), b - 0.25 * (b - a)


def low_ratio_db(x, rate, t0, t1) -> float:
    """Energy below 500 Hz against 500-4000 Hz (dB)."""
    return band_power_db(x, rate, t0, t1, 0.0, 500.0) - band_power_db(x, rate, t0, t1, 500.0, 4000.0)


def centroid_hz(x, rate, t0, t1, lo=1000.0, hi=10000.0) -> float:
    a, b = int(t0 * rate), int(t1 * rate)
    seg = np.asarray(x[a:b], float)
    if len(seg) < 32:
        return float("nan")
    spec = np.abs(np.fft.rfft(seg * np.hanning(len(seg)))) ** 2
    f = np.fft.rfftfreq(len(seg), 1 / rate)
    keep = (f >= lo) & (f <= hi)
    return float(np.sum(f[keep] * spec[keep]) / max(np.sum(spec[keep]), 1e-30))


def vowel_reference(x, rate, vowels: list[tuple[float, float]]) -> dict:
    """The neighbouring vowels' mean level overall, 3-8 kHz, 1-8 kHz, and their low-frequency ratio (dB)."""
    mids = [_mid(v) for v in vowels]
    mean = lambda f: float(np.mean([f(a, b) for a, b in mids]))  # noqa: E731
    return {"level_db": mean(lambda a, b: band_power_db(x, rate, a, b)),
            "band_3_8k_db": mean(lambda a, b: band_power_db(x, rate, a, b, 3000.0, 8000.0)),
            "band_1_8k_db": mean(lambda a, b: band_power_db(x, rate, a, b, 1000.0, 8000.0)),
            "low_ratio_db": mean(lambda a, b: low_ratio_db(x, rate, a, b))}


def closure(t, db, t0, t1, below_db, margin_s=0.015):
    """The longest stretch within [t0 - margin, t1 + margin] whose 5-ms level is below ``below_db``:
    (start s, end s, its mean level dB) or None."""
    inside = (t >= t0 - margin_s) & (t <= t1 + margin_s)
    idx = np.flatnonzero(inside)
    if not len(idx):
        return None
    best = max(runs(db[idx] < below_db), key=lambda r: r[1] - r[0], default=None)
    if best is None:
        return None
    a, b = idx[best[0]], idx[best[1] - 1]
    return float(t[a]), float(t[b]), float(np.mean(db[a:b + 1]))


def measure(x, rate, iv: tuple[float, float, str], vowels: list[tuple[float, float]], manner: str,
            formants=None, frames=None, contour=None) -> dict:
    """The landmarks of the consonant interval ``iv`` (start s, end s, symbol) of manner ``manner``, against the
    ``vowels`` (start s, end s) beside it; ``formants``: (times s, (F, 2) F1 F2 Hz) for a glide's F2."""
    t0, t1, sym = iv
    frames = voiced_frames(x, rate) if frames is None else frames
    ref = vowel_reference(x, rate, vowels)
    t, db = rms_contour_db(x, rate) if contour is None else contour
    out = {"symbol": sym, "manner": manner, "start_s": t0, "duration_ms": 1e3 * (t1 - t0),
           "voiced_share": share_voiced(x, rate, t0, t1, frames),
           "level_db": band_power_db(x, rate, t0, t1) - ref["level_db"]}
    inside = (t >= t0) & (t <= t1)
    out["dip_db"] = float(db[inside].min() - ref["level_db"]) if inside.any() else float("nan")
    if manner in ("stop", "affricate"):
        depth = 12.0 if manner == "stop" and sym in VOICED_STOPS else (
            20.0 if manner == "affricate" else 25.0)
        c = closure(t, db, t0, t1, ref["level_db"] - depth)
        if c is None:
            out.update(closure_ms=0.0, closure_db=out["dip_db"], release_db=float("nan"), closure_voiced=0.0)
        else:
            after = (t > c[1]) & (t <= c[1] + 0.015)
            out.update(closure_ms=1e3 * (c[1] - c[0]), closure_db=c[2] - ref["level_db"],
                       release_db=float(db[after].max() - c[2]) if after.any() else float("nan"),
                       closure_voiced=share_voiced(x, rate, c[0], c[1], frames))
    if manner == "nasal":
        a, b = _mid((t0, t1))
        out["low_ratio_db"] = low_ratio_db(x, rate, a, b) - ref["low_ratio_db"]
    if manner in ("fricative", "affricate"):
        a = t0 + 0.6 * (t1 - t0) if manner == "affricate" else t0 + 0.2 * (t1 - t0)
        b = t1 if manner == "affricate" else t1 - 0.2 * (t1 - t0)
        out["band_3_8k_db"] = band_power_db(x, rate, a, b, 3000.0, 8000.0) - ref["band_3_8k_db"]
        out["band_1_8k_db"] = band_power_db(x, rate, a, b, 1000.0, 8000.0) - ref["band_1_8k_db"]
        out["centroid_hz"] = centroid_hz(x, rate, a, b)
    if manner == "approximant" and formants is not None:
        ft, fm = formants
        a, b = _mid((t0, t1))
        sel = (ft >= a) & (ft <= b) & np.isfinite(fm[:, 1])
        out["f2_hz"] = float(np.median(fm[sel, 1])) if sel.any() else float("nan")
    return out


VOICED_FRICATIVES = ("z", "j")


def criteria(m: dict) -> dict[str, bool]:
    """Each check of the consonant's manner (issue 45's thresholds) on its landmarks ``m``."""
    sym, man = m["symbol"], m["manner"]
    voiced_stop = sym in VOICED_STOPS
    c: dict[str, bool] = {}
    if man == "stop" and not voiced_stop:
        c["closure >= 25 ms at -25 dB"] = m["closure_ms"] >= 25.0
        c["release >= +15 dB"] = m["release_db"] >= 15.0
    elif man == "stop":
        c["closure <= -12 dB"] = m["closure_ms"] > 0
        c["closure voiced >= 40 %"] = m["closure_voiced"] >= 0.4
    elif man == "nasal":
        c["voiced >= 70 %"] = m["voiced_share"] >= 0.7
        c["level -25..+5 dB"] = -25.0 <= m["level_db"] <= 5.0
        c["low ratio >= +6 dB"] = m["low_ratio_db"] >= 6.0
    elif man == "fricative" and sym in ("s", "sh"):
        c["3-8 kHz >= +10 dB"] = m["band_3_8k_db"] >= 10.0
    elif man == "fricative" and sym in VOICED_FRICATIVES:
        c["voiced >= 30 %"] = m["voiced_share"] >= 0.3
        c["3-8 kHz >= -5 dB"] = m["band_3_8k_db"] >= -5.0
    elif man == "fricative":  # h f hy
        c["1-8 kHz >= -10 dB"] = m["band_1_8k_db"] >= -10.0
        c["voiced < 70 %"] = m["voiced_share"] < 0.7
    elif man == "affricate" and sym in VOICED_FRICATIVES:  # /j/: a voiced affricate, judged as /z/
        c["voiced >= 30 %"] = m["voiced_share"] >= 0.3
        c["3-8 kHz >= -5 dB"] = m["band_3_8k_db"] >= -5.0
    elif man == "affricate":
        c["closure >= 15 ms at -20 dB"] = m["closure_ms"] >= 15.0
        c["3-8 kHz (last 40 %) >= +5 dB"] = m["band_3_8k_db"] >= 5.0
    elif man == "tap":
        c["<= 60 ms"] = m["duration_ms"] <= 60.0
        c["voiced >= 50 %"] = m["voiced_share"] >= 0.5
        c["dip <= -6 dB"] = m["dip_db"] <= -6.0
    elif man == "approximant":
        c["F2 >= 1800 Hz" if sym == "y" else "F2 <= 1200 Hz"] = (m["f2_hz"] >= 1800.0 if sym == "y"
                                                                 else m["f2_hz"] <= 1200.0)
        c["voiced >= 70 %"] = m["voiced_share"] >= 0.7
    return c


def consonants(x, rate, intervals: list[tuple[float, float, str]], manners: dict[str, str], formants=None,
               frames=None) -> list[dict]:
    """The landmarks and checks of every consonant interval with a vowel on each side (or one, at an edge)."""
    frames = voiced_frames(x, rate) if frames is None else frames
    contour = rms_contour_db(x, rate)
    out = []
    for k, iv in enumerate(intervals):
        man = manners.get(iv[2])
        if man in (None, "vowel") or not iv[2]:
            continue
        before = next(((a, b) for a, b, s in reversed(intervals[:k]) if manners.get(s) == "vowel"), None)
        after = next(((a, b) for a, b, s in intervals[k + 1:] if manners.get(s) == "vowel"), None)
        vowels = [v for v in (before, after) if v is not None]
        if not vowels:
            continue
        m = measure(x, rate, iv, vowels, man, formants, frames, contour)
        m["checks"] = criteria(m)
        out.append(m)
    return out


__all__ = ["consonants", "criteria", "measure", "rms_contour_db", "voiced_frames", "vowel_reference"]
