"""Gesture timing (speech/timing.py): when a constriction is made and released, read off its place's area."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.speech.leads import soften
from artic_cli.speech.timing import onset_and_release

T = np.arange(0.0, 0.4, 0.005)


def test_a_closure_made_late_and_released_early_is_measured_from_its_interval():
    area = np.where((T >= 0.130) & (T < 0.180), 0.0, 0.5)  # shut from 130 to 175 ms
    late, early = onset_and_release(T, area, 0.01, 0.100, 0.200)
    assert late == pytest.approx(30.0) and early == pytest.approx(20.0)


def test_a_closure_made_just_before_its_interval_and_held_is_on_time():
    area = np.where(T >= 0.090, 0.0, 0.5)
    assert onset_and_release(T, area, 0.01, 0.100, 0.200) == (0.0, 0.0)


def test_a_closure_never_made_reports_where_the_area_turned_back():
    area = 0.2 + np.abs(T - 0.150)  # narrowest at 150 ms, never below 0.2 cm^2
    late, early = onset_and_release(T, area, 0.01, 0.100, 0.200)
    assert np.isnan(late) and early == pytest.approx(50.0)


def test_a_channel_is_not_made_by_the_closure_before_it():
    area = np.where(T < 0.160, 0.0, 0.12)  # shut to 155 ms, then open to the channel's 0.1 +- 0.03 cm^2
    late, early = onset_and_release(T, area, 0.13, 0.100, 0.200, floor=0.07)
    assert late == pytest.approx(60.0) and early == 0.0
    late, _ = onset_and_release(T, np.zeros_like(T), 0.13, 0.100, 0.200, floor=0.07)
    assert np.isnan(late)


def test_rounds_are_judged_by_how_much_of_the_constrictions_they_missed():
    from artic_cli.speech.timing import Goal, missed_ms
    starts, ends = np.array([0.0, 100.0, 150.0]), np.array([100.0, 150.0, 200.0])
    goals = [Goal(1, 0, 0.01), Goal(2, 0, 0.13, 0.07)]
    shut_channel = {1: np.zeros_like(T), 2: np.where(T < 0.150, 0.0, 0.035)}  # the channel half its floor
    # a closure on time and a channel never opened beyond 0.035 cm^2 (half way to its 0.07 floor)
    half = missed_ms(goals, {1: 0.0, 2: float("nan")}, {1: 0.0, 2: 0.0}, starts, ends, shut_channel, T)
    assert half == pytest.approx(50.0 * 0.035 / 0.1)
    # a closure never made costs its whole interval, however the channel does
    assert missed_ms(goals, {1: float("nan"), 2: 0.0}, {1: 0.0, 2: 0.0}, starts, ends, shut_channel, T) == 50.0
    # made 20 ms late and released 10 ms early: 17 + 7 ms beyond the slack
    assert missed_ms(goals[:1], {1: 20.0}, {1: 10.0}, starts, ends) == pytest.approx(24.0)


def test_a_closure_held_past_its_interval_is_measured_to_its_release():
    from artic_cli.speech.timing import held_after
    area = np.where((T >= 0.090) & (T < 0.240), 0.0, 0.5)  # shut to 235 ms, its interval ending at 200 ms
    assert held_after(T, area, 0.01, 0.200) == pytest.approx(40.0)
    assert held_after(T, np.where(T < 0.190, 0.0, 0.5), 0.01, 0.200) == 0.0  # open at its end


def test_a_closure_made_long_before_its_interval_is_measured_from_its_making():
    from artic_cli.speech.timing import made_before
    area = np.where((T >= 0.030) & (T < 0.150), 0.0, 0.5)  # shut from 30 ms, its interval starting at 100 ms
    assert made_before(T, area, 0.01, 0.100) == pytest.approx(70.0)
    assert made_before(T, np.where(T >= 0.120, 0.0, 0.5), 0.01, 0.100) == 0.0  # open at its start


def test_an_unphysical_round_softens_every_free_press_above_one_a_step():
    from artic_cli.speech.leads import PRESS_STEP

    press = np.array([1.0, 1.75, 0.8, 1.1, 2.0])
    assert soften(press, [True, True, True, True, False])
    assert press.tolist() == pytest.approx([1.0, 1.75 / PRESS_STEP, 0.8, 1.0, 2.0])  # given presses kept
    assert not soften(np.array([1.0, 0.9]), [True, True])  # nothing left to soften


def test_a_geminate_and_its_consonant_are_one_constriction():
    from artic_cli.speech.timing import Goal, joined_goals
    q, k, next_vowel_k = Goal(2, 4, 0.01), Goal(3, 4, 0.01), Goal(5, 4, 0.01)
    assert joined_goals([q, k, next_vowel_k]) == {2}  # Q then its /k/; the /k/ two segments on is its own
    assert joined_goals([Goal(2, 4, 0.01), Goal(3, 5, 0.01)]) == set()  # another place
    assert joined_goals([Goal(2, 4, 0.01), Goal(3, 4, 0.13, 0.07)]) == set()  # a closure, then a channel


def test_a_vowel_is_missed_by_how_far_its_formants_stay_beyond_its_tolerance(monkeypatch):
    import artic_cli.speech.timing as timing
    from artic_cli.control.solver import AcousticGoal
    from artic_cli.speech.timing import VOWEL_SPAN, heard_formants, shares_missed

    def heard_shares(vowels, *args):
        return shares_missed(vowels, heard_formants(vowels, *args))

    time = np.arange(0.0, 0.2, 0.005)
    goal = AcousticGoal(formants_hz=[750.0, 1400.0], tolerance_pct=[10.0, 7.0])
    starts, ends = np.array([0.0, 100.0]), np.array([100.0, 200.0])
    heard = {"f": None, "frames": None}

    def formants_at(tracts, frames, cfg):
        heard["frames"] = frames
        return heard["f"][frames]

    monkeypatch.setattr(timing, "formants_at", formants_at)

    def share(f1, f2):
        heard["f"] = np.tile([f1, f2, 2500.0], (len(time), 1))
        return heard_shares([(0, goal)], starts, ends, None, time, None)[0]

    assert share(750.0, 1400.0) == 0.0
    assert share(750.0 * 1.09, 1400.0 * 0.94) == 0.0  # within both tolerances
    assert share(750.0, 1400.0 * (1 + 0.07 * (1 + 0.5 * VOWEL_SPAN))) == pytest.approx(0.5)  # F2 half way on
    assert share(615.0, 1729.0) == 1.0  # an /a/ heard /e/: the whole vowel
    assert np.all((time[heard["frames"]] >= 0.025) & (time[heard["frames"]] <= 0.075))  # its middle half only
    share(750.0, 1400.0)
    heard["f"][time >= 0.08] = 5000.0  # off only after its middle half: not missed
    assert heard_shares([(0, goal)], starts, ends, None, time, None)[0] == 0.0
    heard["f"][:, :] = np.nan  # a closed tract: missed whole
    assert heard_shares([(0, goal)], starts, ends, None, time, None)[0] == 1.0


def test_the_segment_slowed_is_the_one_switched_on_last_before_the_fastest_movement():
    from types import SimpleNamespace as NS

    from artic_cli.speech.timing import fastest_switch
    t = np.arange(0.0, 0.5, 0.005)
    x = np.zeros((len(t), 2, 3))
    x[:, 0, 0] = np.clip((t - 0.30) / 0.02, 0.0, 1.0)  # the tip moves 1 cm in 20 ms from 300 ms
    x[:, 1, 0] = 0.5 - 0.5 * np.cos(np.pi * np.clip((t - 0.10) / 0.10, 0.0, 1.0))  # the dorsum fastest at 150 ms
    model = NS(control_points=lambda: {"tip": 0, "dorsum": 1})
    switches = np.array([-100.0, 80.0, 250.0, 320.0])
    assert fastest_switch({"tip": 1.2}, NS(time=t, x=x), model, switches) == 2  # switched on at 250 ms
    assert fastest_switch({"dorsum": 1.1, "tip": 1.05}, NS(time=t, x=x), model, switches) == 1


def test_a_devoiced_vowel_is_not_heard_by_its_formants():
    from artic_cli.control.solver import parse_target
    from artic_cli.speech.timing import vowels_heard
    from artic_cli.speech.utterance import Segment

    vowel = parse_target({"name": "u", "jaw": {"forces_n": {"JO": 0.5}},
                          "acoustic": {"formants_hz": [367.0, 1332.0]}})
    stop = parse_target({"name": "k", "jaw": {"forces_n": {"JO": 0.5}},
                         "constriction": {"place": "velum", "area_cm2": 0.0}})
    segs = [Segment(target="k", duration_ms=75, voiced=False), Segment(target="u", duration_ms=80),
            Segment(target="u", duration_ms=80, voiced=False)]
    assert [k for k, _ in vowels_heard(segs, [stop, vowel, vowel])] == [1]


def test_a_vowel_missed_speaks_the_forces_of_its_aim_and_its_own_again_when_the_aim_closes_its_tract():
    from artic_cli.control.solver import parse_target
    from artic_cli.speech.aims import Aiming
    from artic_cli.speech.plan import Plan
    from artic_cli.speech.timing import aim_vowel

    t = parse_target({"name": "a_vowel", "jaw": {"forces_n": {"JO": 6.0}},
                      "acoustic": {"formants_hz": [750, 1400], "tolerance_pct": [10, 7]}}, "test", 15.0)
    given = Plan(labels=["k", "a"], starts_s=np.array([0.0, 0.075]), durations_s=np.array([0.075, 0.075]),
                 forces_n=[{"GGp": 3.0}, {"JO": 6.0, "GGp": 0.5}], lips=[(2.0, 1.0)] * 2, ports=[0.0, 0.0],
                 voiced=np.array([False, True]), glottis_cm2=np.array([0.3, 0.05]), notes=["solved"] * 2,
                 solutions=["k.yaml", "a.yaml"])
    asked = []

    def aim(target):
        asked.append(target)
        return {"JO": 6.0, "HG": 1.0}, "aimed", "aim.yaml"

    aiming = Aiming()
    p, moved, back = aim_vowel(given, given, 1, t, np.array([600.0, 1700.0]), aiming, aim)
    assert moved and not back and p.forces_n[1] == {"JO": 6.0, "HG": 1.0} and p.solutions[1] == "aim.yaml"
    assert p.forces_n[0] == given.forces_n[0] and given.forces_n[1] == {"JO": 6.0, "GGp": 0.5}
    f1, f2 = asked[0].acoustic.formants_hz[:2]
    assert f1 > 750 and f2 < 1400  # aimed beyond /a/, away from where it was heard
    again, moved, back = aim_vowel(p, given, 1, t, np.array([np.nan, np.nan]), aiming, aim)
    assert moved and back and again.forces_n[1] == given.forces_n[1] and again.notes[1] == "solved"
    assert len(asked) == 1
