"""Force courses: a sequence of force sets in time, each switched on at its segment's start.

As the paper's controller does, a target's forces act "constantly until a new target is coming": at each
start the forces move from the values reached so far to the new set along a raised cosine over ``ramp_s``,
then hold.  Vectors are any unit (the stage passes muscle-unit forces in dyn).
"""

from __future__ import annotations

import numpy as np


def raised_cosine(u: np.ndarray | float) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * u)


def course(starts_s, vectors, ramp_s: float, initial=None):
    """``f(t) -> (M,)`` for sets ``vectors`` (K, M) starting at ``starts_s`` (K,, rising), from ``initial``
    (zero by default) before the first; a set that starts before the last ramp ended starts from where it
    had got to."""
    starts = np.asarray(starts_s, float)
    v = np.asarray(vectors, float)
    base = []
    now = np.zeros(v.shape[1]) if initial is None else np.asarray(initial, float)
    for k in range(len(starts)):
        base.append(now.copy())
        if k + 1 < len(starts):
            w = 1.0 if ramp_s <= 0 else float(raised_cosine((starts[k + 1] - starts[k]) / ramp_s))
            now = now + (v[k] - now) * w
    base = np.array(base)

    def at(t: float) -> np.ndarray:
        k = int(np.searchsorted(starts, t, side="right")) - 1
        if k < 0:
            return np.zeros(v.shape[1]) if initial is None else np.asarray(initial, float)
        w = 1.0 if ramp_s <= 0 else float(raised_cosine((t - starts[k]) / ramp_s))
        return base[k] + (v[k] - base[k]) * w

    return at


def pulse_step(starts_s, durations_s, vectors, pulse_s: float, gain: float, upper: float):
    """The sets of a pulse-step course (beyond the paper): each segment opens with a pulse of
    ``F_k + gain (F_k - F_k-1)`` (clipped to 0..``upper``) for ``pulse_s`` (at most half the segment), then
    holds F_k; returns the starts and vectors to give :func:`course`."""
    v = np.asarray(vectors, float)
    starts, sets = [], []
    before = np.zeros(v.shape[1])
    for t0, d, f in zip(np.asarray(starts_s, float), np.asarray(durations_s, float), v):
        width = min(pulse_s, 0.5 * d)
        starts += [t0, t0 + width]
        sets += [np.clip(f + gain * (f - before), 0.0, upper), f]
        before = f
    return np.array(starts), np.array(sets)
