import numpy as np
import pytest

from artic_cli.control.solver import parse_target
from artic_cli.speech.aims import AIM_GAIN, AIM_SPAN_BARK, aimed, next_aim
from artic_cli.units import hz_to_bark

GOAL = np.array([750.0, 1400.0])


def test_a_vowel_heard_on_its_goal_keeps_its_aim():
    assert next_aim(GOAL, GOAL, GOAL) == pytest.approx(GOAL, abs=0.5)
    assert next_aim([800.0, 1300.0], GOAL, GOAL) == pytest.approx([800.0, 1300.0], abs=0.5)


def test_a_vowel_heard_short_of_its_goal_aims_beyond_it_by_a_share_of_the_shortfall():
    heard = np.array([600.0, 1700.0])  # an /a/ heard toward /e/: F1 low, F2 high
    aim = next_aim(GOAL, GOAL, heard)
    shortfall = hz_to_bark(GOAL) - hz_to_bark(heard)
    assert hz_to_bark(aim) - hz_to_bark(GOAL) == pytest.approx(AIM_GAIN * shortfall, abs=0.01)
    assert aim[0] > GOAL[0] and aim[1] < GOAL[1]
    near = np.array([700.0, 1500.0])
    again = next_aim(aim, GOAL, near, gain=1.0)  # heard short again: further, by all of that shortfall
    assert hz_to_bark(again) - hz_to_bark(aim) == pytest.approx(hz_to_bark(GOAL) - hz_to_bark(near), abs=0.01)


def test_an_aim_stays_within_its_span_of_the_goal_and_a_closed_tract_gives_none():
    far = next_aim(GOAL, GOAL, [200.0, 3000.0], gain=10.0)
    assert np.abs(hz_to_bark(far) - hz_to_bark(GOAL)) == pytest.approx([AIM_SPAN_BARK] * 2, abs=0.01)
    assert next_aim(GOAL, GOAL, [np.nan, np.nan]) is None


def test_an_aimed_target_keeps_everything_but_its_first_two_formants():
    t = parse_target({"name": "a_vowel", "jaw": {"forces_n": {"JO": 6.0}},
                      "acoustic": {"formants_hz": [750, 1400, 2500], "tolerance_pct": [10, 7]},
                      "lips": "open", "tongue_highest": {"tongue": "low-back"}}, "test", 15.0)
    a = aimed(t, [820.0, 1250.0])
    assert a.acoustic.formants_hz == [820.0, 1250.0, 2500.0]
    assert a.acoustic.tolerance_pct == t.acoustic.tolerance_pct
    assert (a.jaw, a.lips, a.tongue_highest, a.velum_port_cm2) == (t.jaw, t.lips, t.tongue_highest, t.velum_port_cm2)
    assert a.name == "a_vowel-aim-820-1250" and t.acoustic.formants_hz == [750, 1400, 2500]


def test_a_vowel_heard_further_off_with_its_aim_goes_back_to_the_aim_before_and_moves_half_as_far_after():
    from artic_cli.speech.aims import Aiming

    a = Aiming()
    moved, first, back = a.step(1, GOAL, [650.0, 1600.0])  # short of /a/: aimed beyond it
    assert moved and not back and first[0] > GOAL[0] and first[1] < GOAL[1]
    moved, second, back = a.step(1, GOAL, [700.0, 1500.0])  # nearer with it: further still
    assert moved and not back and second[0] > first[0] and second[1] < first[1]
    moved, before, back = a.step(1, GOAL, [600.0, 1800.0])  # further off than before: the aim before
    assert moved and back and before == pytest.approx(first) and a.gains[1] == pytest.approx(0.5 * AIM_GAIN)
    heard = np.array([700.0, 1500.0])
    moved, third, back = a.step(1, GOAL, heard)  # aimed again from there, half as far
    assert moved and not back
    assert hz_to_bark(third) - hz_to_bark(first) == pytest.approx(
        0.5 * AIM_GAIN * (hz_to_bark(GOAL) - hz_to_bark(heard)), abs=0.01)
    for _ in range(3):  # taken back again and again: at a gain below 0.1 it is not aimed again
        a.step(1, GOAL, [500.0, 2000.0])
        a.step(1, GOAL, heard)
    assert 1 in a.frozen and a.step(1, GOAL, heard)[0] is False
    moved, closed, back = Aiming().step(2, GOAL, [np.nan, np.nan])  # no formants heard: nothing to aim by
    assert not moved and closed is None and not back
    b = Aiming()
    b.step(3, GOAL, [650.0, 1600.0])
    assert b.step(3, GOAL, [np.nan, np.nan]) == (True, None, True)  # its tract closed by the aim: its own goal
    c = Aiming()
    c.step(4, GOAL, [650.0, 1600.0])
    assert c.take_back(4) is None and 4 in c.frozen and 4 not in c.aims  # taken back for good: its goal, no more aims
    assert c.step(4, GOAL, [650.0, 1600.0]) == (False, None, False)
