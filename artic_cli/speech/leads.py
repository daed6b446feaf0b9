"""The leads and presses the gesture timing moves (:mod:`.timing`), each segment's within its bounds.

A segment after a voiced vowel switches on no earlier than ``VOWEL_KEPT`` into the vowel, so that the vowel is
heard; a closure that cannot be made in the time left presses harder instead, and only when it may press no
harder (at ``PRESS_MAX``, or a press found too hard: not physical, or faster than a speaker moves) does its lead
reach further into the vowel (by as much as it was late, or ``LEAD_STEP_MS`` when never made).  A segment after
a consonant switches on no sooner after that consonant's switch than its sound lasts (a tap's forces not cut
short by the vowel after it).  Each segment's ``drive`` scales the pulse that opens its forces: a vowel not
reached drives harder (x ``DRIVE_STEP`` up to ``DRIVE_MAX``), a drive found too hard is never reached again, and
a movement faster than a speaker's with nothing pressed or driven above 1 drives softer (down to
``DRIVE_MIN``).  A lead, press or drive the utterance gives is left as given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..control.solver import TargetSpec

PRESS_STEP, PRESS_MAX = 1.15, 2.0
LEAD_STEP_MS, LEAD_MAX_MS, MIN_GAP_MS = 20.0, 250.0, 10.0
DRIVE_STEP, DRIVE_MAX, DRIVE_MIN = 1.5, 3.0, 0.25
VOWEL_KEPT = 0.5  # a segment after a voiced vowel switches on no earlier than this share into the vowel


@dataclass
class Leads:
    """Per segment (ms, factors): the lead, the press, and what bounds them."""

    leads: np.ndarray
    press: np.ndarray
    starts: np.ndarray  # each segment's sound's start
    cap: np.ndarray  # the longest lead
    gap: np.ndarray  # the shortest time after the switch before it
    ceiling: np.ndarray  # the hardest press
    free_lead: list[bool]
    free_press: list[bool]
    drive: np.ndarray | None = None  # each segment's opening pulse's factor (None: 1 each)
    drive_ceiling: np.ndarray | None = None  # ... the hardest
    free_drive: list[bool] | None = None

    def __post_init__(self):
        n = len(self.leads)
        self.drive = np.ones(n) if self.drive is None else np.asarray(self.drive, float)
        self.drive_ceiling = np.full(n, DRIVE_MAX) if self.drive_ceiling is None else self.drive_ceiling
        self.free_drive = [True] * n if self.free_drive is None else self.free_drive

    def longest(self, k: int) -> float:
        """The longest lead segment ``k`` may have: its cap, and its gap after segment ``k - 1``'s switch."""
        return min(self.cap[k], self.starts[k] - (self.starts[k - 1] - self.leads[k - 1]) - self.gap[k])

    def in_order(self) -> None:
        """Each free lead cut to its bounds."""
        for k in range(1, len(self.leads)):
            if self.free_lead[k]:
                self.leads[k] = max(min(self.leads[k], self.longest(k)), 0.0)

    def lead_more(self, k: int, by_ms: float) -> bool:
        """Segment ``k`` leads ``by_ms`` more, as far as its bounds allow; whether it moved."""
        if not self.free_lead[k] or k == 0:
            return False
        new = min(self.leads[k] + by_ms, self.longest(k))
        if new <= self.leads[k] + 0.5:
            return False
        self.leads[k] = new
        return True

    def lead_less(self, k: int, by_ms: float) -> bool:
        """Segment ``k`` leads ``by_ms`` less (not below 0); whether it moved."""
        if not self.free_lead[k] or self.leads[k] <= 0:
            return False
        self.leads[k] = max(self.leads[k] - by_ms, 0.0)
        return True

    def press_more(self, k: int) -> bool:
        """Segment ``k`` presses a step harder, up to its ceiling; whether it moved."""
        if not self.free_press[k] or self.press[k] >= self.ceiling[k] - 1e-9:
            return False
        self.press[k] = min(self.press[k] * PRESS_STEP, self.ceiling[k])
        return True

    def press_less(self, k: int) -> bool:
        """Segment ``k`` presses a step softer, down to ``1 / PRESS_MAX``; whether it moved."""
        if not self.free_press[k] or self.press[k] <= 1.0 / PRESS_MAX:
            return False
        self.press[k] = max(self.press[k] / PRESS_STEP, 1.0 / PRESS_MAX)
        return True

    def further(self, k: int, by_ms: float = LEAD_STEP_MS) -> bool:
        """Segment ``k``, pressing as hard as it may, leads ``by_ms`` further into the vowel before it (its cap
        raised as much, up to ``LEAD_MAX_MS``); whether it moved."""
        if not self.free_lead[k] or k == 0 or self.cap[k] >= LEAD_MAX_MS:
            return False
        self.cap[k] = min(self.cap[k] + by_ms, LEAD_MAX_MS)
        return self.lead_more(k, by_ms)

    def drive_more(self, k: int) -> bool:
        """Segment ``k``'s pulse a step harder, up to its ceiling; whether it moved."""
        if not self.free_drive[k] or self.drive[k] >= self.drive_ceiling[k] - 1e-9:
            return False
        self.drive[k] = min(self.drive[k] * DRIVE_STEP, self.drive_ceiling[k])
        return True

    def drive_less(self, k: int) -> bool:
        """Segment ``k``'s pulse a step softer, down to ``DRIVE_MIN``, and never harder again; whether it moved."""
        if not self.free_drive[k] or self.drive[k] <= DRIVE_MIN + 1e-9:
            return False
        self.drive[k] = max(self.drive[k] / DRIVE_STEP, DRIVE_MIN)
        self.drive_ceiling[k] = self.drive[k]
        return True

    def too_hard(self, drives: bool = True) -> bool:
        """The presses (and ``drives``) of a round that was too hard become each one's ceiling less a step, and
        every free one above 1 softens a step (not below 1); whether any moved."""
        moved = False
        for value, ceiling, free, step in ((self.press, self.ceiling, self.free_press, PRESS_STEP),
                                           (self.drive, self.drive_ceiling, self.free_drive, DRIVE_STEP))[
                                               :2 if drives else 1]:
            hard = np.array(free, bool) & (value > 1.0)
            ceiling[hard] = np.minimum(ceiling[hard], np.maximum(value[hard] / step, 1.0))
            moved |= soften(value, free, step)
        return moved


def soften(press: np.ndarray, free: list[bool], step: float = PRESS_STEP) -> bool:
    """Every free press (or drive) above 1 a step softer (not below 1); whether any moved."""
    hard = np.array(free, bool) & (press > 1.0)
    press[hard] = np.maximum(press[hard] / step, 1.0)
    return bool(hard.any())


def lead_bounds(segs, targets: list[TargetSpec | None]) -> tuple[np.ndarray, np.ndarray]:
    """Each segment's longest lead and shortest gap after the switch before it (ms).  After a voiced vowel (a
    formant target): the lead at most the share of that vowel's duration past ``VOWEL_KEPT``, the gap
    ``MIN_GAP_MS``; after anything else: the lead at most ``LEAD_MAX_MS``, the gap as long as that segment's
    sound."""
    cap = np.full(len(segs), LEAD_MAX_MS)
    gap = np.full(len(segs), MIN_GAP_MS)
    for k in range(1, len(segs)):
        t, before = targets[k - 1], segs[k - 1]
        if t is not None and t.acoustic is not None and before.voiced and not segs[k].continues:
            cap[k] = min(LEAD_MAX_MS, (1.0 - VOWEL_KEPT) * before.duration_ms)
        else:
            gap[k] = max(before.duration_ms, MIN_GAP_MS)
    return cap, gap


def leads_of(u, targets: list[TargetSpec | None], default_lead_ms: float) -> Leads:
    """The utterance's leads (its own, else ``default_lead_ms``) and presses, within their bounds."""
    segs = u.segments
    cap, gap = lead_bounds(segs, targets)
    out = Leads(leads=np.array(u.leads_ms(default_lead_ms), float), press=np.array([s.press for s in segs], float),
                starts=np.array(u.starts_ms(), float), cap=cap, gap=gap, ceiling=np.full(len(segs), PRESS_MAX),
                free_lead=[s.lead_ms is None for s in segs],
                # a press the utterance gives (a glide's 1) is kept
                free_press=["press" not in s.model_fields_set for s in segs],
                drive=np.array([s.drive for s in segs], float), free_drive=["drive" not in s.model_fields_set
                                                                            for s in segs])
    out.in_order()  # a short part (an affricate's release, a glide) leads no more than fits
    return out


__all__ = ["DRIVE_MAX", "DRIVE_MIN", "DRIVE_STEP", "LEAD_MAX_MS", "LEAD_STEP_MS", "Leads", "PRESS_MAX",
           "PRESS_STEP", "VOWEL_KEPT", "lead_bounds", "leads_of", "soften"]
