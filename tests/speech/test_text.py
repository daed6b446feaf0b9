"""The front end (issue 46): typed Japanese -> phones of the inventory, mora-timed, devoiced, with a Tokyo pitch
contour and morae and words tiers."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.errors import ArticError
from artic_cli.speech.accent import tones
from artic_cli.speech.inventory import load_inventory
from artic_cli.speech.phones import realise
from artic_cli.speech.text import MAX_MORAE, utterance_of_text

LIPS = (3.0, 1.0)


@pytest.fixture(scope="module")
def inv():
    return load_inventory()


def phones(text, inv):
    return [s.phoneme for s in utterance_of_text(text, inv).segments if s.phoneme is not None]


def morae(text, inv):
    return [i.label for i in utterance_of_text(text, inv).tiers["morae"]]


@pytest.mark.parametrize("text, want", [
    ("konnichiwa", "k o N n i ch i w a"), ("arigatou", "a r i g a t o"), ("tempura", "t e N p u r a"),
    ("kitte", "k i Q t e"), ("gakkou", "g a Q k o"), ("kyou", "ky o"), ("hon'ya", "h o N y a"),
    ("shinbun", "sh i N b u N"), ("matcha", "m a Q ch a"), ("mittsu", "m i Q ts u"), ("fuji", "f u j i"),
    ("sayōnara", "s a y o n a r a"), ("onna", "o N n a"), ("Nagoya", "n a g o y a"), ("aQta", "a Q t a")])
def test_romaji_becomes_the_inventorys_phones(inv, text, want):
    assert phones(text, inv) == want.split()


@pytest.mark.parametrize("kunrei, hepburn", [("sinbun", "shinbun"), ("tikatetu", "chikatetsu"), ("huzi", "fuji"),
                                             ("syasin", "shashin"), ("tyotto", "chotto"), ("zyuu", "juu")])
def test_kunrei_spellings_are_read_as_hepburn(inv, kunrei, hepburn):
    assert phones(kunrei, inv) == phones(hepburn, inv)


@pytest.mark.parametrize("kana, romaji", [("こんにちは", "konnichiha"), ("ありがとう", "arigatou"), ("きって", "kitte"),
                                          ("きょう", "kyou"), ("ラーメン", "raamen"), ("シャツ", "shatsu"),
                                          ("ふぁいと", "faito")])
def test_kana_are_read_as_their_romaji(inv, kana, romaji):
    assert phones(kana, inv) == phones(romaji, inv)
    assert morae(kana, inv) == morae(romaji, inv)


def test_a_long_vowel_is_one_phone_over_two_morae(inv):
    u = utterance_of_text("too", inv)
    assert [s.phoneme for s in u.segments] == ["t", "o"]
    assert [i.label for i in u.tiers["morae"]] == ["to", "o"]
    short = utterance_of_text("to", inv)
    assert u.segments[1].duration_ms > short.segments[1].duration_ms + 0.8 * inv.timing.mora_ms
    assert phones("tō", inv) == phones("tou", inv) == phones("too", inv)


@pytest.mark.parametrize("text, devoiced", [("kita", ["i"]), ("desu", ["u"]), ("kutsu", ["u"]), ("kitte", ["i"]),
                                            ("kiku", ["i"]), ("gita", []), ("kida", []), ("sushi", ["u"]),
                                            ("kii", [])])
def test_high_vowels_devoice_between_voiceless_consonants_and_after_one_at_the_end(inv, text, devoiced):
    u = utterance_of_text(text, inv)
    assert [s.phoneme for s in u.segments if s.devoiced] == devoiced
    # kiku: the second /u/ after a devoiced /i/ keeps its voice; sushi's final /i/ too


def test_a_devoiced_vowel_keeps_its_tongue_and_opens_the_glottis(inv):
    u = realise(utterance_of_text("kita", inv), inv, LIPS)
    i = u.segments[1]
    assert i.target["acoustic"]["formants_hz"] == inv.phonemes["i"].formants_hz and not i.voiced


@pytest.mark.parametrize("text, place", [("sanpo", "bilabial"), ("kanda", "alveolar"), ("manga", "velar")])
def test_the_moraic_nasal_closes_at_the_next_consonants_place(inv, text, place):
    u = realise(utterance_of_text(text, inv), inv, LIPS)
    n = next(s for s in u.segments if s.label == "N")
    if place == "bilabial":  # the lips close: the tongue is held
        assert n.hold and any(e.lip_area_cm2 == 0.0 for e in u.tract)
    else:
        assert n.target["constriction"]["place"] == inv.places[place]


@pytest.mark.parametrize("text", ["hon'ya", "kan'i", "hon", "kansai"])
def test_the_moraic_nasal_is_a_nasalised_vowel_before_a_vowel_glide_fricative_or_the_end(inv, text):
    u = realise(utterance_of_text(text, inv), inv, LIPS)
    k = next(k for k, s in enumerate(u.segments) if s.label == "N")
    assert u.segments[k].hold  # the tongue of the vowel before
    start = sum(s.duration_ms for s in u.segments[:k])
    assert any(e.velum_port_cm2 and e.velum_port_cm2 > 0 and e.at_ms <= start for e in u.tract)


def test_a_geminate_closure_is_the_published_ratio_of_a_single_one(inv):
    u = utterance_of_text("kitte", inv)
    q, t = u.segments[2], u.segments[3]
    assert (q.duration_ms + t.duration_ms) / t.duration_ms == pytest.approx(inv.timing.geminate_ratio, rel=0.05)


def test_morae_keep_their_length_whatever_their_consonant(inv):
    # kaka, tata, rara, aka: different consonants, the same first-mora length (mora timing) ...
    first = [utterance_of_text(t, inv).tiers["morae"][0] for t in ("kaka", "tata", "rara", "aka")]
    assert np.ptp([m.end_ms - m.start_ms for m in first]) < 1e-6
    # ... but a long consonant leaves its vowel at least the inventory's share of a mora (/s/ 100 ms)
    s, a = utterance_of_text("sasa", inv).segments[:2]
    assert a.duration_ms == pytest.approx(inv.timing.vowel_min_share * inv.timing.mora_ms)


def test_the_rate_scales_every_duration(inv):
    slow, fast = (utterance_of_text("arigatou", inv, rate=r).duration_ms for r in (1.0, 2.0))
    assert slow == pytest.approx(2 * fast)


def test_the_phrase_final_mora_lengthens(inv):
    u = utterance_of_text("kaka", inv)
    a, b = u.tiers["morae"]
    assert (b.end_ms - b.start_ms) > (a.end_ms - a.start_ms) * 1.1


def test_a_comma_is_a_silent_pause_and_words_are_a_tier(inv):
    u = utterance_of_text("hai, iie", inv)
    pause = next(s for s in u.segments if s.label == "pause")
    assert pause.hold and not pause.voiced and pause.glottis_cm2 == 0.0
    assert [w.label for w in u.tiers["words"]] == ["hai", "iie"]
    assert u.tiers["words"][1].start_ms - u.tiers["words"][0].end_ms == pytest.approx(inv.timing.pause_ms)


@pytest.mark.parametrize("n, accent, want", [(2, 1, "HL"), (2, 2, "lH"), (2, None, "lH"), (3, 2, "lHL"),
                                             (4, None, "lHHH"), (4, 3, "lHHL")])
def test_tokyo_tones(n, accent, want):
    assert "".join(tones(n, accent)) == want


def f0_at(u, t_s):
    t, f = np.array(u.f0_hz).T
    return float(np.interp(t_s, t, f))


def test_the_pitch_falls_after_the_accented_mora(inv):
    hl, lh = utterance_of_text("ha'shi", inv), utterance_of_text("hashi'", inv)
    (a1, a2), (b1, b2) = ([(m.start_ms + m.end_ms) / 2e3 for m in u.tiers["morae"]] for u in (hl, lh))
    assert f0_at(hl, a1) - f0_at(hl, a2) > 20  # HL
    assert f0_at(lh, b2) - f0_at(lh, b1) > 10  # LH
    lo, hi = 80.0, 160.0
    wide = utterance_of_text("ha'shi", inv, f0_range_hz=(lo, hi))
    assert max(f for _, f in wide.f0_hz) == pytest.approx(hi, abs=2) and min(f for _, f in wide.f0_hz) >= lo - 5


def test_the_high_level_declines_and_downsteps_after_an_accent(inv):
    u = utterance_of_text("a'me ga fu'ru", inv)  # two accented words: the second's high lower
    highs = [f for _, f in u.f0_hz]
    first, second = u.tiers["words"][0], u.tiers["words"][2]
    h1 = f0_at(u, (u.tiers["morae"][0].start_ms + u.tiers["morae"][0].end_ms) / 2e3)
    h2 = max(f0_at(u, t / 1e3) for t in np.linspace(second.start_ms, second.end_ms, 50))
    assert h2 < h1 - 5 and max(highs) == pytest.approx(h1) and first.label == "a'me"


@pytest.mark.parametrize("text, says", [
    ("", "give some romaji"), (" , ", "give some romaji"), ("kax", "'x' at position 3 is not romaji"),
    ("'ka", "accent mark on no mora"), ("ka''ta", "second accent mark"), ("kta", "'k' at position 1 starts 'k' "
                                                                         "with no vowel"),
    ("ka" * (MAX_MORAE + 1), f"{MAX_MORAE + 1} morae is more than the {MAX_MORAE}"), ("ka漢", "'漢' at position 3")])
def test_bad_text_is_one_line_naming_what_and_where(inv, text, says):
    with pytest.raises(ArticError, match=says) as e:
        utterance_of_text(text, inv)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("rate", [0.4, 2.5, float("nan")])
def test_a_rate_outside_half_to_double_is_refused(inv, rate):
    with pytest.raises(ArticError, match="--rate .*: give a factor from 0.5 to 2"):
        utterance_of_text("aka", inv, rate=rate)


def test_the_textgrid_has_phones_morae_and_words_tiers_with_the_pause_silent(inv, tmp_path):
    from praatio import textgrid

    from artic_cli.speech.plan import Plan
    from artic_cli.speech.textgrid import write_textgrid

    u = realise(utterance_of_text("hai, kitte", inv), inv, LIPS)
    starts = np.cumsum([0.0] + [s.duration_ms for s in u.segments[:-1]]) / 1e3
    n = len(u.segments)
    p = Plan(labels=[s.label or "" for s in u.segments], starts_s=starts,
             durations_s=np.array([s.duration_ms for s in u.segments]) / 1e3, forces_n=[{}] * n, lips=[LIPS] * n,
             ports=[0.0] * n, voiced=np.ones(n, bool), glottis_cm2=np.zeros(n), notes=[""] * n, solutions=[""] * n,
             continues=[s.continues for s in u.segments])
    tg = textgrid.openTextgrid(str(write_textgrid(tmp_path / "x.TextGrid", p, u.tiers)), includeEmptyIntervals=True)
    assert list(tg.tierNames) == ["phones", "morae", "words"]
    labels = {name: [e.label for e in tg.getTier(name).entries] for name in tg.tierNames}
    assert labels["phones"] == ["h", "a", "i", "", "k", "i", "Q", "t", "e"]
    assert labels["morae"] == ["ha", "i", "", "ki", "Q", "te"] and labels["words"] == ["hai", "", "kitte"]
    ends = {name: tg.getTier(name).entries[-1].end for name in tg.tierNames}
    assert len(set(ends.values())) == 1
