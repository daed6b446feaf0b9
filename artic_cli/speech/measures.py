"""What a spoken utterance did, measured on its record and its sound: formants, levels, closures, how far
each control point got toward where its segment's forces lead, speeds and the force spent."""

from __future__ import annotations

import numpy as np

from ..acoustics.measures import band_level_db, runs
from .record import Record

EMA_PEAK_CM_S = {"tip": 40.0, "dorsum": 32.0, "jaw": 12.0}  # Table II's EMA ranges the paper cites
SPEED_MARGIN = 1.5  # the mechanical goal: peak speeds within the EMA range + 50 %


def peak_speeds(time_s: np.ndarray, points_cm: dict[str, np.ndarray]) -> dict[str, float]:
    """Each control point's peak midsagittal speed (cm/s) over frames ``time_s`` (s) of its track (F, 3) cm."""
    dt = np.diff(time_s)
    return {name: float(np.max(np.linalg.norm(np.diff(xyz[:, :2], axis=0), axis=1) / dt)) if len(dt) else 0.0
            for name, xyz in points_cm.items()}


def too_fast(speeds_cm_s: dict[str, float]) -> dict[str, float]:
    """The articulators faster than the EMA range + 50 %: each one's peak speed over that limit (> 1)."""
    return {k: speeds_cm_s.get(k, np.nan) / (SPEED_MARGIN * v) for k, v in EMA_PEAK_CM_S.items()
            if not speeds_cm_s.get(k, np.nan) <= SPEED_MARGIN * v}


def measures(rec: Record, samples: np.ndarray, rate_hz: int) -> dict:
    """Per segment: median F1/F2 of our tracks over its middle half, its level (dB) overall and above 3 kHz,
    and for tip, dorsum and jaw how far they still are from the segment's EP at its end (cm), the fraction of
    the way covered, and the time to cover 90 % of it (ms); the closures (frames with a zero area) and their
    level; peak speeds of the control points (cm/s); the commanded force's impulse (N s) and peak (N)."""
    t = rec.time_s
    segs = []
    for lab, s0, d in zip(rec.labels, rec.starts_s, rec.durations_s):
        mid = (t >= s0 + 0.25 * d) & (t <= s0 + 0.75 * d)
        fm = rec.formants_hz[mid]
        med = [float(np.nanmedian(fm[:, k])) if np.isfinite(fm[:, k]).any() else float("nan") for k in (0, 1)]
        segs.append({"label": lab, "start_s": float(s0), "duration_s": float(d), "f1_hz": med[0], "f2_hz": med[1],
                     "level_db": band_level_db(samples, rate_hz, s0 + 0.25 * d, s0 + 0.75 * d),
                     "level_above_3khz_db": band_level_db(samples, rate_hz, s0 + 0.25 * d, s0 + 0.75 * d, 3000.0)})
    closed = rec.area_cm2.min(axis=1) <= 0.0
    closures = []
    for a, b in runs(closed):
        t0, t1 = float(t[a]), float(t[min(b, len(t) - 1)])
        closures.append({"start_s": t0, "end_s": t1, "duration_ms": 1e3 * (t1 - t0),
                         "level_db": band_level_db(samples, rate_hz, t0 + 0.005, max(t1 - 0.005, t0 + 0.01))})
    dt = np.diff(t)
    speeds = peak_speeds(t, rec.control_points)
    cps = ("tip", "dorsum", "jaw")
    for k, seg in enumerate(segs):  # how far each control point still is from where the segment's forces lead
        end = min(np.searchsorted(t, seg["start_s"] + seg["duration_s"] - 1e-9), len(t) - 1)
        begin = np.searchsorted(t, seg["start_s"])
        for j, name in enumerate(cps):
            if name in rec.control_points and np.isfinite(rec.eps_cm[k, j]).all():
                ep = rec.eps_cm[k, j, :2]
                left = float(np.linalg.norm(rec.control_points[name][end, :2] - ep))
                away = float(np.linalg.norm(rec.control_points[name][begin, :2] - ep))
                seg[f"{name}_left_cm"] = left
                seg[f"{name}_reached"] = 1.0 - left / away if away > 1e-3 else 1.0
                # the time it takes to cover 90 % of the way (NaN: not within the segment)
                path = np.linalg.norm(rec.control_points[name][begin:end + 1, :2] - ep, axis=1)
                hit = np.flatnonzero(path <= 0.1 * away)
                seg[f"{name}_t90_ms"] = float(1e3 * (t[begin + hit[0]] - seg["start_s"])) if len(hit) else float("nan")
    total = rec.commanded_n.sum(axis=1)
    impulse = float(np.sum(0.5 * (total[1:] + total[:-1]) * dt)) if len(dt) else 0.0
    return {"segments": segs, "closures": closures, "peak_speed_cm_s": speeds, "force_impulse_n_s": impulse,
            "peak_total_force_n": float(total.max()) if len(total) else 0.0, "force_course": rec.force_course,
            "max_volume_change": float(np.nanmax(np.abs(rec.volume_change))),
            "min_constriction_cm2": float(rec.area_cm2.min())}
