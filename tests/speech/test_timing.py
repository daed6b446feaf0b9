"""Gesture timing (speech/timing.py): when a constriction is made and released, read off its place's area."""

from __future__ import annotations

import numpy as np
import pytest

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
