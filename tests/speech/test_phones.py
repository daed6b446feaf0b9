"""Phonemes made articulation (issue 45): each phoneme segment becomes its targets, holds and tract controls,
from features alone."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.control.solver import parse_target
from artic_cli.errors import ArticError
from artic_cli.schedule import tract_controls
from artic_cli.speech.inventory import load_inventory
from artic_cli.speech.phones import realise
from artic_cli.speech.plan import Plan
from artic_cli.speech.text import utterance_of_text
from artic_cli.speech.textgrid import intervals

LIPS = (3.0, 1.0)  # a neutral lip tube (cm^2, cm)


@pytest.fixture(scope="module")
def inv():
    return load_inventory()


def spoken(text, inv):
    return realise(utterance_of_text(text, inv), inv, LIPS)


def courses(u, t_ms):
    start = {"lip_area_cm2": LIPS[0], "lip_length_cm": LIPS[1], "velum_port_cm2": 0.0, "glottis_cm2": 0.05}
    return tract_controls(u.tract, start, np.asarray(t_ms, float) / 1e3)


def test_a_velar_stop_is_a_closure_target_at_the_velum_between_two_formant_targets(inv):
    u = spoken("aga", inv)
    a, g, a2 = u.segments
    assert a.target["acoustic"]["formants_hz"] == [753, 1385] and a2.target == a.target
    assert g.target["constriction"] == {"place": "velum", "area_cm2": 0.0, "tolerance_cm2": 0.01}
    assert g.voiced and g.label == "g" and not g.continues
    parse_target(g.target, "g", 10.0)  # a target the solver takes
    assert u.tract == []  # neither the lips, nor the port, nor the glottis move for /g/


def test_a_voiceless_alveolar_stop_abducts_the_glottis_and_closes_at_the_ridge(inv):
    t = spoken("ata", inv).segments[1]
    assert not t.voiced and t.target["constriction"]["place"] == "alveolar"
    assert t.target["jaw"] == {"forces_n": {"JC": 1.5}}


def test_a_bilabial_nasal_holds_the_tongue_closes_the_lips_and_opens_the_port_around_it(inv):
    u = spoken("ama", inv)
    a, m, _ = u.segments
    assert m.hold and m.target is None and m.label == "m"
    start, end = a.duration_ms, a.duration_ms + m.duration_ms
    c = courses(u, [start - 31, start - 15, start + 1, end - 1, end + 29, end + 31])
    assert c["lip_area_cm2"][2] == pytest.approx(0.0) and c["lip_area_cm2"][3] == pytest.approx(0.0)
    assert c["lip_area_cm2"][5] > 1.0  # open again for the /a/
    port = c["velum_port_cm2"]
    assert port[0] == pytest.approx(0.0) and 0 < port[1] < 0.5  # opening 30 ms before the nasal
    assert port[2] == pytest.approx(0.5) and port[3] == pytest.approx(0.5)
    assert port[4] > 0 and port[5] == pytest.approx(0.0)  # ... and shut 30 ms after it


def test_an_affricate_is_a_closure_then_a_channel_in_one_interval(inv):
    u = spoken("atsu", inv)
    ts = [s for s in u.segments if s.label == "ts" or s.continues]
    assert [s.target["constriction"]["area_cm2"] for s in ts] == [0.0, 0.1]
    given = utterance_of_text("atsu", inv).segments[1]
    assert ts[1].continues and given.phoneme == "ts" and sum(s.duration_ms for s in ts) == pytest.approx(
        given.duration_ms)
    p = _plan(u)
    assert [lab for _, _, lab in intervals(p)] == ["a", "ts", "u"]


def test_the_moraic_nasal_takes_the_next_consonant_s_place_and_the_geminate_its_closure(inv):
    assert spoken("aNka", inv).segments[1].target["constriction"]["place"] == "velum"
    assert spoken("aNta", inv).segments[1].target["constriction"]["place"] == "alveolar"
    aNpa = spoken("aNpa", inv)
    assert aNpa.segments[1].hold and aNpa.segments[1].voiced  # /m/: the lips close, the tongue is held
    q = spoken("aQta", inv).segments[1]
    assert q.label == "Q" and not q.voiced and q.target["constriction"] == spoken("ata", inv).segments[1].target[
        "constriction"]
    with pytest.raises(ArticError, match="the geminate Q needs a consonant after it"):
        spoken("aQ", inv)


def test_a_palatalized_stop_glides_to_the_palate_after_its_closure(inv):
    u = spoken("kya", inv)
    k, y = u.segments[:2]
    assert k.target["constriction"]["area_cm2"] == 0.0 and y.continues
    assert y.target["constriction"] == {"place": "hard palate", "area_cm2": 0.3, "tolerance_cm2": 0.09}
    assert y.press == 1.0 and "press" in y.model_fields_set  # a glide is not pressed by the timing


def test_ch_closes_at_the_ridge_and_releases_behind_it(inv):
    ch = [s for s in spoken("acha", inv).segments if s.label == "ch" or s.continues]
    assert [s.target["constriction"]["place"] for s in ch] == ["alveolar", "postalveolar"]
    assert [s.target["constriction"]["area_cm2"] for s in ch] == [0.0, 0.15]


def test_a_glide_like_a_vowel_keeps_that_vowel_s_tongue_where_it_is_told(inv):
    asked = []

    def tongue_of(v):
        asked.append(v)
        return {"tip": [-0.8, -0.55], "dorsum": [-4.1, 1.54]}

    y = realise(utterance_of_text("aya", inv), inv, LIPS, tongue_of).segments[1].target
    assert asked == ["i"] and y["constriction"]["area_cm2"] == inv.phonemes["y"].channel_cm2
    assert y["indecisive"] == [{"point": "tip", "at_cm": [-0.8, -0.55]}, {"point": "dorsum", "at_cm": [-4.1, 1.54]}]
    parse_target(y)  # a valid target
    kya = realise(utterance_of_text("kya", inv), inv, LIPS, tongue_of).segments[1].target
    assert "indecisive" not in kya  # a palatalized consonant's glide: a secondary narrowing of its own
    assert "indecisive" not in spoken("aya", inv).segments[1].target  # told nothing: none
    assert "indecisive" not in realise(utterance_of_text("awa", inv), inv, LIPS, tongue_of).segments[1].target


def test_h_opens_the_glottis_and_leaves_the_tongue_to_its_vowels(inv):
    h = spoken("aha", inv).segments[1]
    assert h.hold and not h.voiced and h.glottis_cm2 == 0.3


def test_an_unknown_phoneme_segment_names_it_and_lists_the_inventory(inv):
    from artic_cli.speech.utterance import parse_utterance

    u = parse_utterance({"name": "x", "segments": [{"phoneme": "a", "duration_ms": 90},
                                                   {"phoneme": "q", "duration_ms": 60}]})
    with pytest.raises(ArticError, match=r"segments\[1\].phoneme: 'q' is not in the inventory; symbols: a i u"):
        realise(u, inv, LIPS)


@pytest.mark.parametrize("text, says", [("", "give some romaji"), ("  ", "give some romaji"),
                                        ("ax", "'x' at position 2 is not romaji")])
def test_bad_text_is_one_line(inv, text, says):
    with pytest.raises(ArticError, match=says):
        utterance_of_text(text, inv)


def _plan(u) -> Plan:
    starts = np.cumsum([0.0] + [s.duration_ms for s in u.segments[:-1]]) / 1e3
    n = len(u.segments)
    return Plan(labels=[s.label or "" for s in u.segments], starts_s=starts,
                durations_s=np.array([s.duration_ms for s in u.segments]) / 1e3, forces_n=[{}] * n,
                lips=[LIPS] * n, ports=[0.0] * n, voiced=np.ones(n, bool), glottis_cm2=np.zeros(n), notes=[""] * n,
                solutions=[""] * n, continues=[s.continues for s in u.segments])


def _keys(node):
    if isinstance(node, dict):
        for k, v in node.items():
            yield k
            yield from _keys(v)
    elif isinstance(node, list):
        for v in node:
            yield from _keys(v)


def test_no_utterance_or_phoneme_entry_in_configs_types_forces_a_press_or_a_lead():
    from pathlib import Path

    import yaml

    root = Path(__file__).resolve().parents[2] / "configs"
    files = sorted((root / "utterances").glob("*.yaml")) + sorted((root / "phonemes").glob("*.yaml"))
    assert len(files) >= 43  # 42 utterances and the inventory
    typed = {f.name: sorted(set(_keys(yaml.safe_load(f.read_text()))) & {"forces_n", "press", "lead_ms", "drive"})
             for f in files}
    assert {k: v for k, v in typed.items() if v} == {}
