"""Gesture timing from the model's own movement: each constriction segment's forces switch on early enough,
and press hard enough, that the model makes the constriction inside its interval, and the segment after it
switches on late enough that it holds to the interval's end (docs/inventory.md, "Timing").

The utterance is simulated (mechanics and area function only, no sound), the area at each constriction's
place read frame by frame, and the leads and presses moved by what was measured:

* a constriction reached ``late`` ms after its start leads by that much more;
* one never reached presses harder (its tongue forces x ``PRESS_STEP``, at most ``PRESS_MAX``), leads
  ``LEAD_STEP_MS`` more and holds its own next part's switch (an affricate's release) back as much;
* a channel never open to its area (an affricate's release after its closure) leads more and presses softer;
* one released before its end (or, never made, narrowest before its end) delays the next segment's switch by
  as much;
* one made more than ``EARLY_MS`` before its start leads less by as much, less ``WINDOW_MS`` (a tap between
  high vowels, whose tongue is near the ridge already);
* one still held more than ``HELD_MS`` after its end brings the next segment's switch forward by as long
  (a release on time: a stop's burst inside its interval, a voiced closure no longer than its voicing lasts).

A round whose simulation is not physical (an inverted brick) is never kept, and every press above 1 softens a
step for the next.  Leads keep the switches in order (``MIN_GAP_MS`` apart); a segment whose lead or press the
utterance gives is left as given.  The rounds stop when nothing moves or every constriction is on time; the
round that missed the fewest ms of its constrictions' intervals is the one kept (the corrections of a closure
and of the channel after it can swing), with what it measured.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import Config
from ..control.solver import TargetSpec
from ..mechanics.model import Model
from ..mechanics.simulate import problems
from ..tract.places import place_area, place_index, section_places
from ..tract.speaker import speaker_tract
from .plan import Plan
from .speak import course_trajectory, default_leads_ms, force_course, tracts_of_run
from .utterance import Utterance

ROUNDS = 9
SLACK_MS = 3.0  # reached within this of the start, held to within this of the end: on time
PRESS_STEP, PRESS_MAX = 1.15, 2.0
LEAD_STEP_MS, LEAD_MAX_MS, MIN_GAP_MS = 20.0, 250.0, 10.0
WINDOW_MS = 20.0  # a constriction made this long before its interval counts as reached at its start
HELD_MS = 15.0  # a constriction held longer than this past its interval's end: the next segment leads more
EARLY_MS = 40.0  # ... made longer than this before its start: its own segment leads less


@dataclass
class Goal:
    segment: int
    place: int  # index of the tract's place
    reach_cm2: float  # reached at or below this area ...
    floor_cm2: float = 0.0  # ... and above this one (a channel, not a closure)


@dataclass
class Timing:
    leads_ms: list[float]
    press: list[float]
    rounds: int
    onset_late_ms: dict[int, float]  # per constriction segment: when its constriction was first made (NaN: never)
    released_early_ms: dict[int, float]  # ... how long before its end it opened again
    held_late_ms: dict[int, float]  # ... how long after its end it still held
    trajectory: object = None  # the returned utterance's movement, when the last round simulated it as it is


def goals_of(targets: list[TargetSpec | None], cfg: Config) -> list[Goal]:
    """A goal per segment whose target is a constriction at a place of the tract."""
    _, names = section_places(speaker_tract(cfg))
    out = []
    for k, t in enumerate(targets):
        if t is not None and t.constriction is not None and t.constriction.place in names:
            c = t.constriction
            floor = c.area_cm2 - c.tolerance_cm2 if c.area_cm2 > c.tolerance_cm2 else 0.0
            out.append(Goal(k, place_index(names, c.place), float(c.area_cm2 + c.tolerance_cm2), float(floor)))
    return out


def place_areas(u: Utterance, p: Plan, cfg: Config, model: Model, rest, goals: list[Goal]):
    """(the utterance's movement, {segment: its place's area per frame, cm^2})."""
    c = force_course(u, p, model, cfg)
    traj = course_trajectory(model, c, cfg, rest)
    tracts = tracts_of_run(u, p, model, traj, cfg)
    region, _ = section_places(speaker_tract(cfg))
    return traj, {g.segment: place_area(tracts.af.area_cm2, region, g.place) for g in goals}


def made(area: np.ndarray, reach: float, floor: float = 0.0) -> np.ndarray:
    """Per frame, whether the constriction is made: its area at most ``reach`` and, for a channel (``floor`` > 0),
    above ``floor``."""
    return (area <= reach) & (area > floor) if floor > 0 else area <= reach


def onset_and_release(t: np.ndarray, area: np.ndarray, reach: float, start: float, end: float, floor: float = 0.0):
    """(ms after ``start`` the constriction is first made (its area at most ``reach``, above ``floor`` when that
    is not 0), NaN if never before ``end``; ms before ``end`` it leaves that range again, 0 if it holds; when never
    made, ms before ``end`` the area was narrowest: where it turned back)."""
    ok = made(area, reach, floor)
    window = (t >= start - WINDOW_MS / 1e3) & (t < end)
    hit = np.flatnonzero(ok & window)
    if not len(hit):
        inside = np.flatnonzero(window)
        if not len(inside):
            return float("nan"), 0.0
        return float("nan"), 1e3 * (end - float(t[inside[np.argmin(area[inside])]]))
    onset = max(float(t[hit[0]]) - start, 0.0)
    after = np.flatnonzero(~ok & (t > t[hit[0]]) & (t < end))
    released = end - float(t[after[0]]) if len(after) else 0.0
    return 1e3 * onset, 1e3 * released


def held_after(t: np.ndarray, area: np.ndarray, reach: float, end: float, floor: float = 0.0) -> float:
    """How long (ms) a constriction made at ``end`` stays made after it (0 if it is open at its end)."""
    ok = made(area, reach, floor)
    at = np.flatnonzero(t >= end - 1e-9)
    if not len(at) or not ok[max(at[0] - 1, 0)]:
        return 0.0
    opened = at[~ok[at]]
    last = float(t[opened[0]]) if len(opened) else float(t[-1])
    return 1e3 * max(last - end, 0.0)


def made_before(t: np.ndarray, area: np.ndarray, reach: float, start: float, floor: float = 0.0) -> float:
    """How long (ms) before ``start`` a constriction made at its start was first made (0 if not made then)."""
    ok = made(area, reach, floor)
    at = np.flatnonzero(t <= start + 1e-9)
    if not len(at) or not ok[at[-1]]:
        return 0.0
    shut = at[~ok[at]]
    first = float(t[shut[-1] + 1]) if len(shut) else float(t[0])
    return 1e3 * max(start - first, 0.0)


def timed(u: Utterance, p: Plan, cfg: Config, model: Model, rest, targets: list[TargetSpec | None],
          rounds: int = ROUNDS) -> tuple[Utterance, Timing | None]:
    """The utterance with the leads and presses its constrictions need (see the module's text); unchanged, with
    no timing, when it asks for no constriction."""
    goals = goals_of(targets, cfg)
    if not goals:
        return u, None
    segs = u.segments
    leads = np.array(u.leads_ms(default_leads_ms(u, cfg)[0]), float)
    press = np.array([s.press for s in segs], float)
    free_lead = [s.lead_ms is None for s in segs]
    free_press = ["press" not in s.model_fields_set for s in segs]  # given (a glide's 1): kept; below 1 softens
    starts = np.array(u.starts_ms(), float)
    ends = starts + np.array([s.duration_ms for s in segs])
    _in_order(leads, starts, free_lead)  # a short part (an affricate's release, a glide) leads no more than fits
    best = None
    for r in range(rounds):
        trial = _with(u, leads, press)
        traj, areas = place_areas(trial, p, cfg, model, rest, goals)
        if problems(traj, model.volume_constraint):  # pressed too hard: never kept, every press softer
            if not soften(press, free_press):
                break
            continue
        t = traj.time
        late, early, held, soon = {}, {}, {}, {}
        tried = leads.copy(), press.copy()
        changed = False
        for g in goals:
            k = g.segment
            on, off = onset_and_release(t, areas[g.segment], g.reach_cm2, starts[k] / 1e3, ends[k] / 1e3, g.floor_cm2)
            late[k], early[k] = on, off
            if not np.isfinite(on):
                inside = areas[g.segment][(t >= starts[k] / 1e3) & (t < ends[k] / 1e3)]
                if len(inside) and inside.max() <= g.floor_cm2:  # a channel too narrow: earlier and softer
                    if free_press[k] and press[k] > 1.0 / PRESS_MAX:
                        press[k] = max(press[k] / PRESS_STEP, 1.0 / PRESS_MAX)
                        changed = True
                    changed |= _lead_more(leads, starts, k, LEAD_STEP_MS, free_lead)
                    continue
                if free_press[k] and press[k] < PRESS_MAX:
                    press[k] = min(press[k] * PRESS_STEP, PRESS_MAX)
                    changed = True
                changed |= _lead_more(leads, starts, k, LEAD_STEP_MS, free_lead)
                if k + 1 < len(segs) and segs[k + 1].continues and free_lead[k + 1] and leads[k + 1] > 0:
                    # nor let its own next part (an affricate's release) cut it short
                    leads[k + 1] = max(leads[k + 1] - LEAD_STEP_MS, 0.0)
                    changed = True
            elif on > SLACK_MS:
                changed |= _lead_more(leads, starts, k, on, free_lead)
            if off > SLACK_MS and k + 1 < len(segs) and free_lead[k + 1] and leads[k + 1] > 0:
                leads[k + 1] = max(leads[k + 1] - off, 0.0)
                changed = True
            ahead = made_before(t, areas[g.segment], g.reach_cm2, starts[k] / 1e3, g.floor_cm2)
            soon[k] = ahead
            if ahead > EARLY_MS and free_lead[k] and leads[k] > 0 and not segs[k].continues:
                leads[k] = max(leads[k] - (ahead - WINDOW_MS), 0.0)
                changed = True
            held[k] = held_after(t, areas[g.segment], g.reach_cm2, ends[k] / 1e3, g.floor_cm2) if np.isfinite(on) else 0.0
            if held[k] > HELD_MS and k + 1 < len(segs) and not segs[k + 1].continues:
                changed |= _lead_more(leads, starts, k + 1, held[k], free_lead)
        _in_order(leads, starts, free_lead)
        score = missed_ms(goals, late, early, starts, ends, areas, t) + sum(max(h - HELD_MS, 0.0) for h in held.values())
        score += sum(max(a - EARLY_MS, 0.0) for a in soon.values())
        if best is None or score < best[0]:
            best = (score, r, tried, late, early, held, traj)
        if not changed or score == 0.0:
            break
    if best is None:  # no round was physical: the last, for the caller to refuse
        return _with(u, leads, press), None
    _, _, (leads, press), late, early, held, traj = best
    return _with(u, leads, press), Timing(leads_ms=leads.tolist(), press=press.tolist(), rounds=r + 1,
                                          onset_late_ms=late, released_early_ms=early, held_late_ms=held,
                                          trajectory=traj)


def missed_ms(goals: list[Goal], late: dict, early: dict, starts: np.ndarray, ends: np.ndarray,
              areas: dict | None = None, t: np.ndarray | None = None) -> float:
    """How much of the constrictions' intervals a round missed (ms): each made one's lateness and early release; a
    closure never made its whole interval; a channel never made its interval times how far its area stayed from
    the channel's range, as a share of the channel's area (at most all of it)."""
    out = 0.0
    for g in goals:
        k = g.segment
        on, span = late[k], ends[k] - starts[k]
        if np.isfinite(on):
            out += max(on - SLACK_MS, 0.0) + max(early[k] - SLACK_MS, 0.0)
            continue
        share = 1.0
        if g.floor_cm2 > 0 and areas is not None:
            inside = areas[k][(t >= starts[k] / 1e3) & (t < ends[k] / 1e3)]
            if len(inside):
                gap = g.floor_cm2 - inside.max() if inside.max() <= g.floor_cm2 else inside.min() - g.reach_cm2
                share = min(max(gap, 0.0) / (0.5 * (g.floor_cm2 + g.reach_cm2)), 1.0)
        out += span * share
    return float(out)


def soften(press: np.ndarray, free: list[bool]) -> bool:
    """Every free press above 1 a step softer (not below 1); whether any moved."""
    hard = np.array(free, bool) & (press > 1.0)
    press[hard] = np.maximum(press[hard] / PRESS_STEP, 1.0)
    return bool(hard.any())


def _in_order(leads: np.ndarray, starts: np.ndarray, free: list[bool]) -> None:
    """Each free lead cut to switch at least ``MIN_GAP_MS`` after the segment before it (in place)."""
    for k in range(1, len(leads)):
        if free[k]:
            leads[k] = max(min(leads[k], starts[k] - (starts[k - 1] - leads[k - 1]) - MIN_GAP_MS), 0.0)


def _lead_more(leads: np.ndarray, starts: np.ndarray, k: int, by_ms: float, free: list[bool]) -> bool:
    """Segment ``k`` leads ``by_ms`` more, as far as the switch before it and ``LEAD_MAX_MS`` allow."""
    if not free[k] or k == 0:
        return False
    limit = min(LEAD_MAX_MS, starts[k] - (starts[k - 1] - leads[k - 1]) - MIN_GAP_MS)
    new = min(leads[k] + by_ms, limit)
    if new <= leads[k] + 0.5:
        return False
    leads[k] = new
    return True


def _with(u: Utterance, leads, press) -> Utterance:
    segs = [s.model_copy(update={"lead_ms": round(float(a), 3), "press": round(float(b), 4)})
            for s, a, b in zip(u.segments, leads, press)]
    return u.model_copy(update={"segments": segs})


__all__ = ["Goal", "Timing", "goals_of", "onset_and_release", "timed"]
