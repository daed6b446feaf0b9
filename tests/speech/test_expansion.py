"""A voiced stop's cavity enlarging while the model holds its closure (speech/expansion.py): asked for by the
inventory's voiced stops, affricates and taps only, timed to the closure the simulation made, bounded."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.schedule import tract_controls
from artic_cli.speech.expansion import GIVE_BACK_MS, MAX_CM3, expansion_entries
from artic_cli.speech.inventory import load_inventory
from artic_cli.speech.phones import realise
from artic_cli.speech.text import utterance_of_text
from artic_cli.speech.utterance import Segment

T = np.arange(0.0, 0.6, 0.005)  # s


def _closed(t0, t1):
    return np.where((T >= t0) & (T <= t1), 0.0, 1.0)  # the narrowest area, cm^2


def _course(entries):
    return tract_controls(entries, {"cavity_expansion_cm3": 0.0}, T)["cavity_expansion_cm3"]


@pytest.mark.parametrize("text, asks", [("aba", True), ("ada", True), ("aga", True), ("aja", False), ("apa", False),
                                         ("aza", False), ("ana", False), ("ara", True)])
def test_only_voiced_closures_ask_for_it(text, asks):
    inv = load_inventory()
    u = realise(utterance_of_text(text, inv), inv, (3.0, 1.0))
    rates = [s.cavity_expansion_cm3_s for s in u.segments]
    assert (rates[1] == inv.realisation.voiced_stop_expansion_cm3_s) if asks else rates[1] is None
    assert rates[0] is None and rates[-1] is None  # never the vowels


def test_it_grows_at_the_rate_over_the_model_s_closure_not_the_interval_and_is_given_back():
    segs = [Segment(phoneme="a", duration_ms=250), Segment(phoneme="d", duration_ms=60, cavity_expansion_cm3_s=120),
            Segment(phoneme="a", duration_ms=250)]
    starts = np.array([0.0, 0.25, 0.31])
    v = _course(expansion_entries(segs, starts, T, _closed(0.22, 0.28)))  # the closure starts 30 ms early
    at = lambda s: float(np.interp(s, T, v))  # noqa: E731
    assert at(0.215) == 0.0 and at(0.25) == pytest.approx(0.120 * 30, abs=0.05)  # 120 cm^3/s from 220 ms
    assert at(0.28) == pytest.approx(0.120 * 60, abs=0.05)
    assert at(0.28 + GIVE_BACK_MS / 1e3 + 0.01) == 0.0 and 0 < at(0.30) < at(0.28)


def test_a_long_closure_stops_growing_at_the_largest_enlargement():
    segs = [Segment(phoneme="a", duration_ms=200), Segment(phoneme="g", duration_ms=150, cavity_expansion_cm3_s=120),
            Segment(phoneme="a", duration_ms=250)]
    v = _course(expansion_entries(segs, np.array([0.0, 0.2, 0.35]), T, _closed(0.2, 0.35)))
    assert v.max() == pytest.approx(MAX_CM3) and float(np.interp(0.34, T, v)) == pytest.approx(MAX_CM3)  # held


def test_no_closure_near_the_interval_asks_for_nothing():
    segs = [Segment(phoneme="a", duration_ms=250), Segment(phoneme="d", duration_ms=60, cavity_expansion_cm3_s=120),
            Segment(phoneme="a", duration_ms=250)]
    assert expansion_entries(segs, np.array([0.0, 0.25, 0.31]), T, np.ones(len(T))) == []
    assert expansion_entries(segs, np.array([0.0, 0.25, 0.31]), T, _closed(0.0, 0.1)) == []  # 150 ms before it
