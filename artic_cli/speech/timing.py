"""Gesture timing from the model's own movement: each constriction segment's forces switch on early enough,
and press hard enough, that the model makes the constriction inside its interval, and the segment after it
switches on late enough that it holds to the interval's end (docs/inventory.md, "Timing").

The utterance is simulated (mechanics and area function only, no sound), the area at each constriction's
place read frame by frame, and the leads and presses moved by what was measured:

* a constriction reached ``late`` ms after its start leads by that much more, or, when it may not lead more,
  presses harder, or, when it may press no harder, leads further into the vowel before it (:mod:`.leads`);
* one never reached presses harder (its tongue forces and jaw closers x ``PRESS_STEP``, up to its ceiling),
  leads ``LEAD_STEP_MS`` more (or, neither possible, further into the vowel) and holds its own next part's
  switch (an affricate's release) back as much;
* a channel never open to its area (an affricate's release after its closure) leads more and presses softer;
* one released before its end (or, never made, narrowest before its end) delays the next segment's switch by
  as much;
* one made more than ``EARLY_MS`` before its start leads less by as much, less ``WINDOW_MS`` (a tap between
  high vowels, whose tongue is near the ridge already); what is made before the utterance's sound begins
  counts as made at its start (a word-initial /g/ shut during the preparation is not early), and a constriction
  the next segment continues (a geminate Q and its consonant) is held into it and made before it by design;
* one still held more than ``HELD_MS`` after its end brings the next segment's switch forward by as long
  (a release on time: a stop's burst inside its interval, a voiced closure no longer than its voicing lasts).

A vowel not heard near enough its formants (see below) opens with a harder pulse in the next round (its ``drive``,
:mod:`.leads`) and aims beyond its goal by a share of how far it was heard off (:mod:`.aims`); an aim that took it
further off is taken back (its pulse not harder for that round; its next aims move half as far), and so are the aims
of a round they made not physical, those vowels not aimed again.  Any other round whose simulation is not physical
(an inverted brick, a tongue off the tract's grid) is never kept, its presses and drives become their ceilings less
a step, and every press and drive above 1 softens a step for the next.  A round faster than a speaker moves (peak
speeds beyond the EMA range + 50 %) counts as missing the share it is too fast of every constriction's interval; the
next round is the same with its presses a step softer, or, no press being above 1, with the pulse of the segment
whose forces switched on last before the fastest movement softer (the vowels' drives are kept: they are what reaches
the vowels); when the round so slowed is too fast again, it is corrected as any other, its presses and that pulse
softer as well.  Leads keep their bounds (:mod:`.leads`: a segment after a vowel switches on no earlier than the
vowel's middle until it may press no harder).  The rounds stop when nothing moves or every constriction is on time;
of the rounds within the speed limits (any, when none is) the one that missed the fewest ms of its constrictions'
intervals and of its vowels is the one kept (the corrections of a closure and of the channel after it can swing),
with what it measured.  A voiced vowel counts as missed by as much of its duration as its F1 or F2 (the tract's own,
over its middle half) stay beyond its tolerance from its formant goal, a share growing to all of it ``VOWEL_SPAN``
tolerances further: a consonant that leads so far into a vowel that the vowel is not heard costs that vowel.  A
devoiced vowel is not heard (the judge asks only that it be voiceless).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from ..config import Config
from ..control.solver import TargetSpec
from ..errors import OffGrid
from ..mechanics.model import Model
from ..mechanics.simulate import problems
from ..tract.places import place_area, place_index, section_places
from ..tract.speaker import speaker_tract
from .aims import Aiming, aimed
from .leads import LEAD_STEP_MS, Leads, leads_of
from .measures import peak_speeds, too_fast
from .plan import Plan
from .speak import (course_trajectory, default_leads_ms, force_course, formants_at,
                    tracts_of_run)
from .utterance import Utterance

ROUNDS = 9
SLACK_MS = 3.0  # reached within this of the start, held to within this of the end: on time
WINDOW_MS = 20.0  # a constriction made this long before its interval counts as reached at its start
HELD_MS = 15.0  # a constriction held longer than this past its interval's end: the next segment leads more
EARLY_MS = 40.0  # ... made longer than this before its start: its own segment leads less
# a vowel's F1 and F2 are read at VOWEL_FRAMES frames of its middle half; one further than its tolerance from its
# goal misses a share of itself, all of it VOWEL_SPAN tolerances further
VOWEL_FRAMES, VOWEL_SPAN = 5, 2.0


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
    drive: list[float] | None = None  # each segment's pulse factor (None: 1 each)
    plan: Plan | None = None  # the plan the kept round spoke: its vowels' forces aimed in context (:mod:`.aims`)
    aims_hz: dict[int, list[float]] | None = None  # per vowel aimed beyond its goal: the F1 and F2 it aimed at


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


def joined_goals(goals: list[Goal]) -> set[int]:
    """The segments whose constriction the next segment continues: the same place and range (a geminate Q and its
    consonant, a moraic nasal before /n/), one closure or channel held over both."""
    by = {g.segment: g for g in goals}
    return {k for k, g in by.items() if k + 1 in by and (by[k + 1].place, by[k + 1].reach_cm2, by[k + 1].floor_cm2)
            == (g.place, g.reach_cm2, g.floor_cm2)}


def place_areas(u: Utterance, p: Plan, cfg: Config, model: Model, rest, goals: list[Goal], prior=None):
    """(the utterance's movement, {segment: its place's area per frame, cm^2}, (its course, the movement): the
    ``prior`` of the next round, which simulates only from where its forces differ, its tracts)."""
    c = force_course(u, p, model, cfg)
    traj = course_trajectory(model, c, cfg, rest, prior=prior, resumable=True)
    tracts = tracts_of_run(u, p, model, traj, cfg)
    region, _ = section_places(speaker_tract(cfg))
    return traj, {g.segment: place_area(tracts.af.area_cm2, region, g.place) for g in goals}, (c, traj), tracts


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


def vowels_heard(segs, targets: list[TargetSpec | None]) -> list:
    """(segment, its acoustic goal) of each vowel the timing hears by its formants: the voiced ones (a devoiced
    vowel is judged by its voicelessness, not its sound)."""
    return [(k, t.acoustic) for k, t in enumerate(targets) if t is not None and t.acoustic is not None
            and segs[k].voiced]


def heard_formants(vowels: list, starts: np.ndarray, ends: np.ndarray, tracts, time_s: np.ndarray, cfg: Config
                   ) -> dict[int, np.ndarray]:
    """Per vowel (segment, its acoustic goal), its F1 and F2 (Hz) as a round heard them: medians of
    ``VOWEL_FRAMES`` frames over its middle half (NaN: a tract closed in most of them)."""
    picked = {}
    for k, goal in vowels:
        a, b = starts[k] + 0.25 * (ends[k] - starts[k]), starts[k] + 0.75 * (ends[k] - starts[k])
        inside = np.flatnonzero((time_s >= a / 1e3) & (time_s <= b / 1e3))
        if len(inside):
            picked[k] = inside[np.unique(np.linspace(0, len(inside) - 1, VOWEL_FRAMES).round().astype(int))]
    if not picked:
        return {}
    heard = np.split(formants_at(tracts, np.concatenate(list(picked.values())), cfg)[:, :2],
                     np.cumsum([len(f) for f in picked.values()])[:-1])  # every vowel's frames in one analysis
    return {k: (np.nanmedian(f, axis=0) if np.mean(np.isfinite(f[:, 0])) >= 0.5 else np.full(2, np.nan))
            for k, f in zip(picked, heard)}


def shares_missed(vowels: list, heard: dict[int, np.ndarray]) -> dict[int, float]:
    """Per vowel heard (:func:`heard_formants`), the share of it missed: how far its F1 or F2 stay beyond its
    tolerance, in ``VOWEL_SPAN`` tolerances, at most 1 (no formants: 1)."""
    goals = dict(vowels)
    out = {}
    for k, f in heard.items():
        if not np.all(np.isfinite(f)):
            out[k] = 1.0
            continue
        off = np.abs(f / np.asarray(goals[k].formants_hz[:2], float) - 1.0) / goals[k].tolerance
        out[k] = float(np.clip((off.max() - 1.0) / VOWEL_SPAN, 0.0, 1.0))
    return out


def fastest_switch(fast: dict[str, float], traj, model: Model, switches_ms: np.ndarray) -> int:
    """The segment whose forces switched on (``switches_ms``, rising) last before the fastest movement of the
    articulator most beyond its limit in ``fast`` (0 if none before it)."""
    name = max(fast, key=fast.get)
    x = traj.x[:, model.control_points()[name], :2]
    speed = np.linalg.norm(np.diff(x, axis=0), axis=1) / np.diff(traj.time)
    i = int(np.argmax(speed))
    peak_ms = 1e3 * 0.5 * (traj.time[i] + traj.time[i + 1])
    return max(int(np.searchsorted(switches_ms, peak_ms, side="right")) - 1, 0)


Aim = Callable[[TargetSpec], tuple[dict[str, float], str, str]]  # a target -> its forces, how found, its file


def vowels_missed(p: Plan, given: Plan, shares: dict, heard_hz: dict, targets: list, aiming: Aiming,
                  aim: Aim | None, kn: Leads) -> tuple[Plan, bool]:
    """Each vowel a round missed aimed further (:func:`aim_vowel`, when ``aim`` is given) and its pulse harder,
    unless its aim was what missed it (taken back): (the plan, whether anything moved)."""
    changed = False
    for k in (k for k, v in shares.items() if v > 0):
        back = False
        if aim is not None:
            p, moved, back = aim_vowel(p, given, k, targets[k], heard_hz[k], aiming, aim)
            changed |= moved
        if not back:
            changed |= kn.drive_more(k)
    return p, changed


def aimed_back(physical: tuple[Plan, Aiming] | None, aiming: Aiming) -> tuple[Plan, Aiming] | None:
    """After a round that was not physical, when vowels were aimed anew since the last ``physical`` round (its
    plan and aims): that round's plan and aims, those vowels not aimed again; else None."""
    moved = [] if physical is None else aiming.moved_since(physical[1])
    if not moved:
        return None
    back = physical[1].copy()
    back.frozen.update(moved)
    return physical[0], back


def aim_vowel(p: Plan, given: Plan, k: int, t: TargetSpec, heard_hz: np.ndarray, aiming: Aiming, aim: Aim
              ) -> tuple[Plan, bool, bool]:
    """Vowel ``k``, missed as heard at ``heard_hz``, aimed anew (:meth:`Aiming.step`): (the plan with its forces,
    those of its aim or, at its own goal, its ``given`` ones; whether they moved; whether the vowel went back to
    an aim before).  The aim's forces are the maps' answer, whatever their static formants: the rounds hear where
    they take the vowel in context."""
    moved, now, back = aiming.step(k, t.acoustic.formants_hz[:2], heard_hz)
    if not moved:
        return p, False, back
    found = (given.forces_n[k], given.notes[k], given.solutions[k]) if now is None else aim(aimed(t, now))
    return with_forces(p, k, found), True, back


def with_forces(p: Plan, k: int, found: tuple[dict[str, float], str, str]) -> Plan:
    """The plan with segment ``k``'s forces, note and solution file those ``found``."""
    forces, notes, files = list(p.forces_n), list(p.notes), list(p.solutions)
    forces[k], notes[k], files[k] = dict(found[0]), found[1], str(found[2])
    return replace(p, forces_n=forces, notes=notes, solutions=files)


def timed(u: Utterance, p: Plan, cfg: Config, model: Model, rest, targets: list[TargetSpec | None],
          rounds: int = ROUNDS, aim: Aim | None = None) -> tuple[Utterance, Timing | None]:
    """The utterance with the leads and presses its constrictions need (see the module's text); unchanged, with
    no timing, when it asks for no constriction.  ``aim``: solves a vowel's target aimed elsewhere (:mod:`.aims`;
    None: vowels are not aimed)."""
    goals = goals_of(targets, cfg)
    if not goals:
        return u, None
    segs = u.segments
    joined = joined_goals(goals)
    heard = vowels_heard(segs, targets)
    kn = leads_of(u, targets, default_leads_ms(u, cfg)[0])
    starts, ends = kn.starts, kn.starts + np.array([s.duration_ms for s in segs])
    best = prior = None
    slowing = False  # the round before was slowed alone
    aiming, given = Aiming(), p  # the vowels' aims in context; the plan as it came
    physical = None  # the plan and aims of the last round that was physical
    for r in range(rounds):
        trial = with_leads(u, kn.leads, kn.press, kn.drive)
        try:
            traj, areas, prior, tracts = place_areas(trial, p, cfg, model, rest, goals, prior)
            bad = bool(problems(traj, model.volume_constraint))
        except OffGrid:  # the tongue left the tract's grid
            bad = True
        if bad:  # aimed too far: the aims of the last physical round, not aimed again; else pressed too hard
            if (back := aimed_back(physical, aiming)) is not None:
                p, aiming = back
                continue
            if not kn.too_hard():  # every press softer
                break
            continue
        t = traj.time
        tried = kn.leads.copy(), kn.press.copy(), kn.drive.copy()
        physical = p, aiming.copy()
        late, early, held, soon = measure(goals, joined, t, areas, starts, ends)
        changed = False
        for g in goals:
            k = g.segment
            changed |= correct(kn, g, segs, t, areas[k], (late[k], early[k], soon[k], held[k]), ends[k])
        kn.in_order()
        score = missed_ms(goals, late, early, starts, ends, areas, t)
        heard_hz = heard_formants(heard, starts, ends, tracts, traj.time, cfg)
        shares = shares_missed(heard, heard_hz)
        score += sum((ends[k] - starts[k]) * v for k, v in shares.items())
        score += sum(max(h - HELD_MS, 0.0) for h in held.values()) + sum(max(a - EARLY_MS, 0.0) for a in soon.values())
        fast = too_fast(peak_speeds(t, {n: traj.x[:, i] for n, i in model.control_points().items()}))
        slowed = False
        if fast:  # too fast: as bad as missing that share more of every constriction's interval
            score += (max(fast.values()) - 1.0) * sum(ends[g.segment] - starts[g.segment] for g in goals)
            corrected = kn.leads.copy(), kn.press.copy(), kn.drive.copy()
            culprit = fastest_switch(fast, traj, model, starts - tried[0])
            if not slowing:  # first the round as it was, its presses softer, else its fastest movement's pulse
                kn.leads, kn.press, kn.drive = (a.copy() for a in tried)
                slowed = kn.too_hard(drives=False) or kn.drive_less(culprit)
            if slowed:
                changed = True
            else:  # ... then, when that did not do, corrected as any round, and softer
                kn.leads, kn.press, kn.drive = corrected
                changed |= kn.too_hard(drives=False) | kn.drive_less(culprit)
        else:  # a vowel not reached: aimed further and its pulse harder
            p, reaimed = vowels_missed(p, given, shares, heard_hz, targets, aiming, aim, kn)
            changed |= reaimed
        key = (bool(fast), score)  # a round within the speed limits before any beyond them
        if best is None or key < best[0]:
            best = (key, r, tried, late, early, held, traj, *physical)
        changed &= bool(aiming.moved_since(physical[1])) or not all(  # all bound
            np.array_equal(a, b) for a, b in zip((kn.leads, kn.press, kn.drive), tried))
        slowing = slowed
        if not changed or score == 0.0:
            break
    if best is None:  # no round was physical: the last, for the caller to refuse
        return with_leads(u, kn.leads, kn.press, kn.drive), None
    _, _, (leads, press, drive), late, early, held, traj, kept, kept_aims = best
    return with_leads(u, leads, press, drive), Timing(
        leads_ms=leads.tolist(), press=press.tolist(), rounds=r + 1, onset_late_ms=late, released_early_ms=early,
        held_late_ms=held, trajectory=traj, drive=drive.tolist(), plan=kept,
        aims_hz={k: [float(v) for v in a] for k, a in kept_aims.aims.items()})


def measure(goals: list[Goal], joined: set[int], t: np.ndarray, areas: dict, starts: np.ndarray, ends: np.ndarray
            ) -> tuple[dict, dict, dict, dict]:
    """Per constriction segment, what a round made of it (ms): how late it was made, how early released, how
    long held past its end, how long made before its start."""
    late, early, held, soon = {}, {}, {}, {}
    for g in goals:
        k = g.segment
        area = areas[k]
        late[k], early[k] = onset_and_release(t, area, g.reach_cm2, starts[k] / 1e3, ends[k] / 1e3, g.floor_cm2)
        # made early only while there is sound (an utterance-initial closure may shut before it starts), and
        # not at all the second of one constriction over two segments (Q and its consonant) ...
        soon[k] = 0.0 if k - 1 in joined else min(
            made_before(t, area, g.reach_cm2, starts[k] / 1e3, g.floor_cm2), float(starts[k]))
        # ... whose first is held into it by design
        held[k] = held_after(t, area, g.reach_cm2, ends[k] / 1e3, g.floor_cm2) if (
            np.isfinite(late[k]) and k not in joined) else 0.0
    return late, early, held, soon


def correct(kn: Leads, g: Goal, segs, t: np.ndarray, area: np.ndarray, measured: tuple, end_ms: float) -> bool:
    """One constriction's corrections of the leads and presses ``kn`` (the module's list), from what a round
    measured of it: (ms late, released early, made before its start, held after its end); whether any moved."""
    k = g.segment
    on, off, ahead, held = measured
    changed = False
    nxt = k + 1 < len(segs)
    if not np.isfinite(on):
        inside = area[(t >= kn.starts[k] / 1e3) & (t < end_ms / 1e3)]
        if len(inside) and inside.max() <= g.floor_cm2:  # a channel too narrow: earlier and softer
            changed |= kn.press_less(k)
            return kn.lead_more(k, LEAD_STEP_MS) or changed
        changed |= kn.press_more(k)
        changed |= kn.lead_more(k, LEAD_STEP_MS)
        if not changed:
            changed = kn.further(k)
        if nxt and segs[k + 1].continues:  # nor let its own next part (an affricate's release) cut it short
            changed |= kn.lead_less(k + 1, LEAD_STEP_MS)
    elif on > SLACK_MS:
        changed |= kn.lead_more(k, on) or kn.press_more(k) or kn.further(k, on)
    if off > SLACK_MS and nxt:
        changed |= kn.lead_less(k + 1, off)
    if ahead > EARLY_MS and not segs[k].continues:
        changed |= kn.lead_less(k, ahead - WINDOW_MS)
    if held > HELD_MS and nxt and not segs[k + 1].continues:
        changed |= kn.lead_more(k + 1, held)
    return changed


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


def with_leads(u: Utterance, leads, press, drive=None) -> Utterance:
    """The utterance with each segment's lead (ms), press and drive (None: each its own)."""
    drive = [s.drive for s in u.segments] if drive is None else drive
    segs = [s.model_copy(update={"lead_ms": round(float(a), 3), "press": round(float(b), 4),
                                 "drive": round(float(c), 4)})
            for s, a, b, c in zip(u.segments, leads, press, drive)]
    return u.model_copy(update={"segments": segs})


__all__ = ["Goal", "Timing", "goals_of", "onset_and_release", "timed", "with_leads"]
