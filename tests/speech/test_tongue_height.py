"""Where the tongue is highest (speech/tongue_height.py): the surface's top, and the inventory's order."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.speech.tongue_height import misordered
from artic_cli.tract.tongue_top import highest_point

NAMED = {"a": "low-back", "i": "high-front", "u": "high-back", "e": "mid-front", "o": "mid-back"}


def test_the_highest_point_lies_on_the_parabola_through_the_top_three_nodes():
    x = np.linspace(0.0, -6.0, 13)
    surface = np.stack([x, 1.5 - (x + 2.2) ** 2 / 4.0], axis=1)  # a dome topping at x = -2.2 cm, 1.5 cm high
    top = highest_point(surface)
    assert top[0] == pytest.approx(-2.2, abs=0.03) and top[1] == pytest.approx(1.5, abs=0.01)
    assert highest_point(surface[::-1])[1] == pytest.approx(1.5, abs=0.01)  # root first alike
    flat_tip_up = np.array([[0.0, 2.0], [-0.5, 1.0], [-1.0, 0.5]])  # the top at an end: that node
    assert highest_point(flat_tip_up).tolist() == [0.0, 2.0]


def test_vowels_out_of_their_named_order_are_named():
    good = {"a": (-4.6, 0.4), "i": (-3.0, 1.6), "u": (-4.2, 1.5), "e": (-2.9, 1.0), "o": (-4.7, 1.2)}
    assert misordered({k: np.array(v) for k, v in good.items()}, NAMED) == []
    bad = dict(good, u=(-2.8, 0.9))  # the rest [e] tongue: as front as /e/ and below /o/
    said = misordered({k: np.array(v) for k, v in bad.items()}, NAMED)
    assert any(s.startswith("/u/ (high) not above /o/ (mid)") for s in said)
    assert any(s.startswith("/e/ (front) not before /u/ (back)") for s in said)
    assert any(s.startswith("/i/ (front) not before /u/ (back)") for s in said)
