"""The leads and presses the gesture timing moves (speech/leads.py), and the speed limit it keeps."""

from __future__ import annotations

from types import SimpleNamespace as NS

import numpy as np
import pytest

from artic_cli.speech.leads import (DRIVE_MAX, DRIVE_MIN, DRIVE_STEP, LEAD_MAX_MS, LEAD_STEP_MS, PRESS_MAX, PRESS_STEP,
                                    Leads, lead_bounds)
from artic_cli.speech.measures import SPEED_MARGIN, peak_speeds, too_fast

VOWEL, CONSONANT = NS(acoustic=object()), NS(acoustic=None)


def seg(ms: float, voiced: bool = True, continues: bool = False):
    return NS(duration_ms=ms, voiced=voiced, continues=continues)


def test_a_segment_after_a_vowel_may_lead_only_into_its_second_half_and_one_after_a_consonant_lets_it_sound():
    segs = [seg(80), seg(25), seg(160), seg(70, voiced=False), seg(90)]
    cap, gap = lead_bounds(segs, [VOWEL, CONSONANT, VOWEL, CONSONANT, VOWEL])
    assert cap.tolist() == [LEAD_MAX_MS, 40.0, LEAD_MAX_MS, 80.0, LEAD_MAX_MS]
    assert gap[2] == 25.0 and gap[4] == 70.0  # the tap's forces act as long as it sounds, the stop's too
    # a devoiced vowel is not heard: the consonant after it is not held back
    cap, _ = lead_bounds([seg(80, voiced=False), seg(70)], [VOWEL, CONSONANT])
    assert cap[1] == LEAD_MAX_MS


def knobs(cap_ms: float = 40.0, press: float = 1.0) -> Leads:
    return Leads(leads=np.array([100.0, 40.0]), press=np.array([1.0, press]), starts=np.array([0.0, 80.0]),
                 cap=np.array([LEAD_MAX_MS, cap_ms]), gap=np.array([10.0, 10.0]), ceiling=np.full(2, PRESS_MAX),
                 free_lead=[True, True], free_press=[True, True])


def test_a_late_closure_at_its_vowel_cap_presses_harder_before_it_leads_into_the_vowel():
    kn = knobs()
    assert not kn.lead_more(1, 30.0)  # at its cap
    assert kn.press_more(1) and kn.press[1] == pytest.approx(PRESS_STEP)
    kn.press[1] = PRESS_MAX
    assert not kn.press_more(1)
    assert kn.further(1, 30.0)  # pressing as hard as it may: further into the vowel
    assert kn.leads[1] == pytest.approx(70.0) and kn.cap[1] == pytest.approx(70.0)


def test_a_press_found_too_hard_is_never_reached_again():
    kn = knobs(press=1.5)
    assert kn.too_hard()
    assert kn.press[1] == pytest.approx(1.5 / PRESS_STEP) and kn.ceiling[1] == pytest.approx(1.5 / PRESS_STEP)
    assert not kn.press_more(1)  # at the ceiling: a late closure now leads further instead
    assert kn.further(1) and kn.leads[1] == pytest.approx(40.0 + LEAD_STEP_MS)


def test_leads_stay_in_order_and_within_the_switch_before():
    kn = knobs(cap_ms=LEAD_MAX_MS)
    kn.leads[1] = 500.0
    kn.in_order()
    assert kn.leads[1] == pytest.approx(80.0 + 100.0 - 10.0)  # 10 ms after the first segment's switch


def test_peak_speeds_and_the_articulators_too_fast():
    t = np.arange(0.0, 0.1, 0.005)
    tip = np.zeros((len(t), 3))
    tip[10:, 1] = 0.5  # a 0.5-cm jump in one 5-ms frame: 100 cm/s
    sp = peak_speeds(t, {"tip": tip, "dorsum": np.zeros((len(t), 3))})
    assert sp == {"tip": pytest.approx(100.0), "dorsum": 0.0}
    fast = too_fast(dict(sp, jaw=0.0))
    assert list(fast) == ["tip"] and fast["tip"] == pytest.approx(100.0 / (SPEED_MARGIN * 40.0))


def test_a_vowel_drives_harder_up_to_its_ceiling_and_a_drive_found_too_hard_is_never_reached_again():
    kn = knobs()
    assert kn.drive.tolist() == [1.0, 1.0]
    steps = 0
    while kn.drive_more(1):
        steps += 1
    assert kn.drive[1] == pytest.approx(DRIVE_MAX) and steps == int(np.ceil(np.log(DRIVE_MAX) / np.log(DRIVE_STEP)))
    assert kn.too_hard()  # a round too fast: the drive a step softer, its ceiling there
    assert kn.drive[1] == pytest.approx(DRIVE_MAX / DRIVE_STEP) and not kn.drive_more(1)
    while kn.too_hard():
        pass
    assert kn.drive[1] == 1.0 and kn.press.tolist() == [1.0, 1.0]  # softened to 1, not below


def test_a_movement_too_fast_with_nothing_pressed_slows_its_segments_pulse_for_good():
    kn = knobs()
    assert not kn.too_hard()  # nothing above 1 to soften
    assert kn.drive_less(1) and kn.drive[1] == pytest.approx(1.0 / DRIVE_STEP)
    assert not kn.drive_more(1)  # never harder again
    while kn.drive_less(1):
        pass
    assert kn.drive[1] == pytest.approx(DRIVE_MIN)
    given = Leads(leads=np.array([100.0]), press=np.ones(1), starts=np.zeros(1), cap=np.array([LEAD_MAX_MS]),
                  gap=np.array([10.0]), ceiling=np.full(1, PRESS_MAX), free_lead=[True], free_press=[True],
                  free_drive=[False])
    assert not given.drive_more(0) and not given.drive_less(0)  # a drive the utterance gives is kept


def test_a_round_too_fast_softens_its_presses_and_keeps_its_drives():
    kn = knobs(press=1.5)
    kn.drive[1] = 2.0
    assert kn.too_hard(drives=False)
    assert kn.press[1] == pytest.approx(1.5 / PRESS_STEP) and kn.drive[1] == pytest.approx(2.0)
    kn.press[:] = 1.0
    assert not kn.too_hard(drives=False)  # no press above 1: the drive is the culprit's to soften
    assert kn.drive[1] == pytest.approx(2.0)
