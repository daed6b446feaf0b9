"""Which articulator made a consonant (speech/articulation.py), on made-up records whose answer is known."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from artic_cli.speech.articulation import LIMIT_CM, articulators

T = np.arange(0.0, 0.6, 0.005)
MANNERS = {"a": "vowel", "t": "stop", "k": "stop", "m": "nasal"}
IV = [(0.0, 0.25, "a"), (0.25, 0.32, "t"), (0.32, 0.6, "a")]


def _record(dorsum_lift: float, tip_lift: float, closed=(0.27, 0.30)):
    bump = np.exp(-((T - 0.285) / 0.03) ** 2)
    pts = lambda y0, lift: np.stack([np.full(len(T), -2.0), y0 + lift * bump, np.zeros(len(T))], axis=1)  # noqa
    area = np.ones((len(T), 4))
    area[(T >= closed[0]) & (T <= closed[1]), 2] = 0.0
    return SimpleNamespace(time_s=T, area_cm2=area, control_points={"tip": pts(-1.0, tip_lift),
                                                                     "dorsum": pts(0.0, dorsum_lift)})


@pytest.mark.parametrize("lift, ok", [(0.3, True), (LIMIT_CM + 0.2, False)])
def test_a_tip_consonant_is_made_by_the_tip_only_if_the_dorsum_stays_with_the_vowels(lift, ok):
    (m,) = articulators(_record(lift, 1.2), IV, MANNERS)
    assert m["symbol"] == "t" and m["by"] == "tip" and m["ok"] is ok
    assert m["dorsum_cm"] == pytest.approx(lift, abs=0.02) and 0.27 <= m["at_s"] <= 0.30


@pytest.mark.parametrize("rise, ok", [(0.2, True), (1.0, False)])
def test_a_dorsum_consonant_keeps_the_tip_low(rise, ok):
    iv = [(a, b, "k" if lab == "t" else lab) for a, b, lab in IV]
    (m,) = articulators(_record(1.0, rise), iv, MANNERS)
    assert m["by"] == "dorsum" and m["ok"] is ok and m["tip_rise_cm"] == pytest.approx(rise, abs=0.02)


def test_only_the_tongue_s_consonants_between_vowels_are_judged():
    assert articulators(_record(0.3, 1.0), [(0.0, 0.25, "a"), (0.25, 0.32, "m"), (0.32, 0.6, "a")], MANNERS) == []
    assert articulators(_record(0.3, 1.0), [(0.0, 0.3, "t"), (0.3, 0.6, "k")], MANNERS) == []
