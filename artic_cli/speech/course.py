"""Force courses: a sequence of force sets in time, each switched on at its segment's start.

As the paper's controller does, a target's forces act "constantly until a new target is coming": at each
start the forces move from the values reached so far to the new set along a raised cosine over ``ramp_s``,
then hold.  Vectors are any unit (the stage passes muscle-unit forces in dyn).  :func:`activated` lets a
muscle's force follow such a course with first-order activation dynamics (beyond the paper).
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


def to_antagonists(pulse: np.ndarray, antagonists) -> np.ndarray:
    """A pulse (M,) whose muscles would pull negatively: each pair's (shares_a (M,), shares_b (M,)) negative
    pull on one side becomes a positive pull of the same size on the other, spread by its shares."""
    out = np.array(pulse, float)
    for a, b in antagonists:
        for this, other in ((np.asarray(a, float), np.asarray(b, float)), (np.asarray(b, float),
                                                                          np.asarray(a, float))):
            deficit = float(np.sum(np.maximum(-pulse, 0.0)[this > 0]))
            if deficit > 0 and other.sum() > 0:
                out += deficit * other / other.sum()
    return out


def pulse_step(starts_s, durations_s, vectors, pulse_s: float, gain, upper: float, antagonists=()):
    """The sets of a pulse-step course (beyond the paper): each segment opens with a pulse of
    ``F_k + gain_k (F_k - F_k-1)`` for ``pulse_s`` (at most half the segment), then holds F_k (``gain``: one for
    all, or one per segment); a pulse below zero
    in one of the ``antagonists`` pairs (shares_a, shares_b) drives the other side instead (a jaw that has to
    close closes with its closers, as it opened with its openers); clipped to 0..``upper``.  Returns the
    starts and vectors to give :func:`course`."""
    v = np.asarray(vectors, float)
    gains = np.broadcast_to(np.asarray(gain, float), (len(v),))
    starts, sets = [], []
    before = np.zeros(v.shape[1])
    for t0, d, f, g in zip(np.asarray(starts_s, float), np.asarray(durations_s, float), v, gains):
        width = min(pulse_s, 0.5 * d)
        starts += [t0, t0 + width]
        sets += [np.clip(to_antagonists(f + g * (f - before), antagonists), 0.0, upper), f]
        before = f
    return np.array(starts), np.array(sets)


def activated(force_at, duration_s: float, rise_s: float, fall_s: float, step_s: float = 5e-4):
    """``g(t) -> (M,)``: each component of ``force_at`` through first-order activation dynamics, a force that
    rises toward its command with time constant ``rise_s`` and falls with ``fall_s`` (the excitation-contraction
    lag of Zajac 1989; the default speaker takes Thelen 2003's 15 / 50 ms), from the command just before
    t = 0; exact exponential steps of ``step_s`` on a grid, linear between them."""
    t = np.arange(0.0, duration_s + 2 * step_s, step_s)
    out = np.empty((len(t), len(np.atleast_1d(force_at(0.0)))))
    out[0] = force_at(-step_s)
    up, down = (np.exp(-step_s / tau) if tau > 0 else 0.0 for tau in (rise_s, fall_s))
    for k in range(1, len(t)):
        u = force_at(t[k] - 0.5 * step_s)
        keep = np.where(u > out[k - 1], up, down)
        out[k] = u + (out[k - 1] - u) * keep

    def at(time: float) -> np.ndarray:
        x = np.clip(time, t[0], t[-1]) / step_s
        k = min(int(x), len(t) - 2)
        w = x - k
        return out[k] * (1.0 - w) + out[k + 1] * w

    return at
