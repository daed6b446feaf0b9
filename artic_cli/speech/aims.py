"""A vowel aimed beyond its formants in context: the compensation of undershoot (Lindblom 1963) learnt from the
model's own movement.

A short vowel between consonants is not reached in its 60-90 ms, and its formants stay on the consonants' side.
When the timing's rounds (:mod:`.timing`) hear a vowel beyond its tolerance, the next round aims it beyond its
goal by ``AIM_GAIN`` of how far it was heard off, on the Bark scale (F1 and F2 each: aim' = aim + ``AIM_GAIN``
(goal - heard)), within ``AIM_SPAN_BARK`` of the goal.  The aim's forces are solved on the maps as the vowel's
own are, its jaw, lips, port and where its tongue is highest kept.  A vowel heard further off with its new aim
than with the one before (a tract it closes is infinitely far) goes back to the aim before and moves half as
far from then on (below a gain of 0.1 it is not aimed again).  The vowel's target, and so an isolated vowel,
is unchanged: only its forces in this utterance aim elsewhere.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..control.solver import TargetSpec
from ..units import bark_to_hz, hz_to_bark
from .vowel_class import bark_distance

AIM_SPAN_BARK = 1.5  # an aim at most this far from its vowel's goal, F1 and F2 each
AIM_GAIN = 0.5  # an aim moves this share of how far its vowel was heard from its goal


def next_aim(aim_hz, goal_hz, heard_hz, gain: float = AIM_GAIN) -> np.ndarray | None:
    """(2,) Hz: the aim moved by ``gain`` times how far the vowel was heard from its goal (Bark), within
    ``AIM_SPAN_BARK`` of the goal; None when the vowel had no formants (a closed tract says nothing of where to aim)."""
    heard = np.asarray(heard_hz, float)[:2]
    if not np.all(np.isfinite(heard)):
        return None
    goal = hz_to_bark(np.asarray(goal_hz, float)[:2])
    moved = hz_to_bark(np.asarray(aim_hz, float)[:2]) + gain * (goal - hz_to_bark(heard))
    return np.round(bark_to_hz(np.clip(moved, goal - AIM_SPAN_BARK, goal + AIM_SPAN_BARK)), 0)


@dataclass
class Aiming:
    """The vowels of one utterance aimed in context, round by round: each one's aim (Hz), the aim before it
    (None: its own goal), how far the vowel was heard from its goal with that one and how far it moves; a
    vowel heard further off with its aim than before goes back to the aim before and moves half as far after."""

    aims: dict[int, np.ndarray] = field(default_factory=dict)
    before: dict[int, np.ndarray | None] = field(default_factory=dict)
    heard_off: dict[int, float] = field(default_factory=dict)
    frozen: set[int] = field(default_factory=set)
    gains: dict[int, float] = field(default_factory=dict)

    def step(self, k: int, goal_hz, heard_hz) -> tuple[bool, np.ndarray | None, bool]:
        """Vowel ``k`` missed, heard at ``heard_hz``: (whether its aim moved, its aim now: None for its goal,
        whether it went back)."""
        d = bark_distance(goal_hz, heard_hz)
        d = d if np.isfinite(d) else float("inf")  # a closed tract: infinitely far
        if k in self.before and d > self.heard_off.get(k, float("inf")):  # worse than before: back, half as far
            self.gains[k] = 0.5 * self.gains.get(k, AIM_GAIN)
            return True, self.take_back(k, freeze=self.gains[k] < 0.1), True
        self.heard_off[k] = d
        if k in self.frozen:
            return False, self.aims.get(k), False
        new = next_aim(self.aims.get(k, goal_hz), goal_hz, heard_hz, self.gains.get(k, AIM_GAIN))
        if new is None or (k in self.aims and np.array_equal(new, self.aims[k])):
            return False, self.aims.get(k), False
        self.before[k] = self.aims.get(k)
        self.aims[k] = new
        return True, new, False

    def take_back(self, k: int, freeze: bool = True) -> np.ndarray | None:
        """Vowel ``k``'s last aim taken back (and, ``freeze``, not aimed again): the aim before it (None: its
        goal)."""
        if freeze:
            self.frozen.add(k)
        back = self.before.pop(k, None)
        self.aims.pop(k, None)
        if back is not None:
            self.aims[k] = back
        return back

    def moved_since(self, before: "Aiming") -> list[int]:
        """The vowels whose aim differs from the one ``before`` held (or that had one then and none now)."""
        return sorted(k for k in set(self.aims) | set(before.aims) if k not in self.aims or k not in before.aims
                      or not np.array_equal(self.aims[k], before.aims[k]))

    def copy(self) -> "Aiming":
        return Aiming(dict(self.aims), dict(self.before), dict(self.heard_off), set(self.frozen), dict(self.gains))


def aimed(t: TargetSpec, aim_hz) -> TargetSpec:
    """The vowel's target with its F1 and F2 at ``aim_hz`` (its F3, tolerance, jaw, lips, port and tongue class
    kept), named by its aim."""
    f = [float(v) for v in np.asarray(aim_hz, float)[:2]] + list(t.acoustic.formants_hz[2:])
    if f[1] <= f[0]:  # a goal's formants rise
        f[1] = f[0] + 1.0
    acoustic = t.acoustic.model_copy(update={"formants_hz": f})
    return t.model_copy(update={"acoustic": acoustic, "name": f"{t.name}-aim-{f[0]:.0f}-{f[1]:.0f}"})


__all__ = ["AIM_GAIN", "AIM_SPAN_BARK", "Aiming", "aimed", "next_aim"]
