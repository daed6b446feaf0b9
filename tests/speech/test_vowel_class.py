"""Which vowel a vowel interval sounds like (speech/vowel_class.py): the nearest male Japanese mean in Bark."""

from __future__ import annotations

import numpy as np

from artic_cli.speech.inventory import load_inventory
from artic_cli.speech.vowel_class import heard_vowels, nearest_vowel

MEANS = {v: tuple(p.formants_hz[:2]) for v, p in load_inventory().phonemes.items() if p.manner == "vowel"}


def test_each_mean_is_heard_as_itself_and_a_raised_a_as_e():
    assert all(nearest_vowel(*MEANS[v], MEANS) == v for v in MEANS)
    assert nearest_vowel(700, 1450, MEANS) == "a"
    assert nearest_vowel(600, 1700, MEANS) == "e"  # /a/ with the jaw half shut and the tongue forward
    assert nearest_vowel(380, 1888, MEANS) == "e" and nearest_vowel(355, 1891, MEANS) == "i"


def test_each_vowel_interval_is_judged_on_its_middle_half():
    t = np.arange(0.0, 0.6, 0.005)
    f = np.where(t[:, None] < 0.25, [753.0, 1385.0], [315.0, 2172.0])  # /a/ then /i/
    f[(t > 0.20) & (t < 0.25)] = [400.0, 2000.0]  # the /a/'s last 50 ms already glide toward the /i/
    heard = heard_vowels([(0.0, 0.25, "a"), (0.25, 0.35, "k"), (0.35, 0.6, "i")], t, f, MEANS)
    assert [(h["label"], h["heard"], h["ok"]) for h in heard] == [("a", "a", True), ("i", "i", True)]
    assert heard[0]["f1_hz"] == 753.0
    wrong = heard_vowels([(0.0, 0.25, "u")], t, f, MEANS)
    assert wrong[0]["heard"] == "a" and not wrong[0]["ok"]


def test_a_vowel_with_no_formants_says_its_tract_was_closed():
    from artic_cli.speech.vowel_class import heard_text

    t = np.arange(0.0, 0.2, 0.005)
    f = np.full((len(t), 2), np.nan)
    h = heard_vowels([(0.0, 0.2, "a")], t, f, MEANS)[0]
    assert not h["ok"] and heard_text(h) == "no formants: the tract closed through its middle half"
    f[:] = [600.0, 1700.0]
    assert heard_text(heard_vowels([(0.0, 0.2, "a")], t, f, MEANS)[0]) == "heard /e/ (600 / 1700 Hz)"
