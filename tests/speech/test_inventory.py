"""The phoneme inventory (issue 45): every symbol of Japanese as articulatory features, validated on load."""

from __future__ import annotations

import pytest
import yaml

from artic_cli.errors import ArticError
from artic_cli.speech.inventory import DEFAULT, SYMBOLS, load_inventory
from artic_cli.tract.places import section_places


def test_the_inventory_names_every_symbol_with_features_and_places_the_tract_has(cfg):
    inv = load_inventory()
    assert set(SYMBOLS) <= set(inv.phonemes) and len(SYMBOLS) == 34
    inv.check_places(section_places(cfg.vocal_tract)[1])
    p = inv.phonemes
    assert [p[v].tongue_highest for v in "aiueo"] == ["low-back", "high-front", "high-back", "mid-front", "mid-back"]
    assert all(p[s].velum_port_cm2 > 0 for s in ("m", "n", "N", "ny", "my"))
    assert not any(p[s].voiced for s in ("p", "t", "k", "s", "sh", "h", "f", "ts", "ch"))
    assert all(p[s].manner == "stop" for s in ("p", "b", "t", "d", "k", "g"))
    assert p["r"].manner == "tap" and p["r"].duration_ms <= 30
    # features, never muscle forces: a jaw is a mapped jaw position, read as the opener's or closer's force
    assert p["a"].jaw.forces_n == {"JO": 6.0} and p["u"].jaw.forces_n == {"JO": 0.5}
    assert {k for e in p.values() if e.jaw is not None for k in (e.jaw.forces_n or {})} <= {"JO", "JC"}


@pytest.mark.parametrize("change, says", [
    (lambda d: d["phonemes"].pop("ts"), "missing ts"),
    (lambda d: d["phonemes"]["k"].update(manner="click"), "phonemes.k.manner"),
    (lambda d: d["phonemes"]["a"].pop("formants_hz"), "a vowel needs formants_hz"),
    (lambda d: d["phonemes"]["m"].update(velum_port_cm2=0.0), "a nasal needs velum_port_cm2"),
    (lambda d: d["phonemes"]["t"].update(velum_port_cm2=0.3), "only nasals open the port"),
    (lambda d: d["phonemes"]["s"].pop("channel_cm2"), "needs channel_cm2"),
    (lambda d: d["phonemes"]["k"].update(duration_ms=-5), "phonemes.k.duration_ms"),
    (lambda d: d["phonemes"]["k"].update(duration_ms=float("nan")), "phonemes.k.duration_ms"),
    (lambda d: d["phonemes"]["k"].update(forces_n={"SG": 2}), "phonemes.k.forces_n"),
    (lambda d: d["places"].pop("velar"), "'velar' has no entry under 'places'"),
    (lambda d: d["phonemes"]["a"].update(jaw="JO_six"), "phonemes.a.jaw"),
    (lambda d: d["phonemes"]["a"].update(jaw={"forces_n": {"JO": 6}}), "names jaw positions"),
    (lambda d: d["jaws"].update(velar="JX_1"), "jaws.velar"),
    (lambda d: d["phonemes"]["k"].update(like="a"), "like belongs to glides"),
    (lambda d: d["phonemes"]["y"].update(like="k"), "phonemes.y.like: 'k' is not a vowel"),
    (lambda d: d["phonemes"]["s"].update(closure_place="alveolar"), "closure_place belongs to affricates"),
    (lambda d: d["phonemes"]["ch"].update(closure_place="uvular"), "phonemes.ch.closure_place"),
])
def test_a_bad_inventory_is_one_error_naming_the_key(tmp_path, change, says):
    d = yaml.safe_load(DEFAULT.read_text())
    change(d)
    path = tmp_path / "inv.yaml"
    path.write_text(yaml.safe_dump(d))
    with pytest.raises(ArticError) as err:
        load_inventory(path)
    assert says in str(err.value) and "\n" not in str(err.value).strip(), str(err.value)


def test_a_place_the_tract_lacks_is_refused(cfg):
    inv = load_inventory()
    inv.places["velar"] = "uvula"
    with pytest.raises(ArticError, match="places.velar: 'uvula' is not a place of the tract"):
        inv.check_places(section_places(cfg.vocal_tract)[1])


def test_romaji_splits_into_the_inventory_s_symbols_longest_first():
    inv = load_inventory()
    assert inv.phones("shashiN") == ["sh", "a", "sh", "i", "N"]
    assert inv.phones("kyou tsuki") == ["ky", "o", "u", "ts", "u", "k", "i"]
    assert inv.phones("kaQta") == ["k", "a", "Q", "t", "a"]
    with pytest.raises(ArticError, match="'x' at position 3 is not in the inventory"):
        inv.phones("kaxa")
