"""The frequency-domain tube model on tubes with known answers."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from artic_cli.acoustics.chain import LOSSLESS, Air
from artic_cli.acoustics.formants import formants
from artic_cli.acoustics.model import air_of, tract_of
from artic_cli.acoustics.transfer import Tract, transfer
from artic_cli.acoustics.tube import from_pieces, uniform
from artic_cli.cli.main import app
from artic_cli.config import load_config


def _formants(tract, air, lossless=False):
    return formants(lambda f: np.abs(transfer(tract, f, air)), lossless=lossless)


def test_uniform_lossless_tube_resonates_at_odd_quarter_wavelengths():
    f, b = _formants(Tract(uniform(17.5, 4.0)), LOSSLESS, lossless=True)
    expect = (2 * np.arange(1, 5) - 1) * 35000.0 / (4 * 17.5)
    assert np.all(np.abs(f[:4] / expect - 1) < 0.005), f
    assert np.all(np.abs(f[:4] / expect - 1) < 1e-5)  # in fact to a thousandth of a per cent
    assert np.all(b[:4] == 0)


@pytest.mark.parametrize("pieces, expect", [(((9, 1), (8, 7)), (789, 1276, 2808)), (((9, 8), (6, 1)), (257, 1904, 2917))])
def test_two_tube_vowels_match_the_exact_lossless_formants(pieces, expect):
    f, _ = _formants(Tract(from_pieces(*pieces)), LOSSLESS, lossless=True)
    assert np.all(np.abs(f[:3] / np.array(expect) - 1) < 0.01), f


def test_losses_set_the_first_bandwidth():
    tube = Tract(uniform(17.5, 4.0))
    f, b = _formants(tube, Air())
    assert 480 <= f[0] <= 530 and 30 <= b[0] <= 100, (f[0], b[0])
    f, b = _formants(tube, Air(walls=False))
    assert b[0] < 20, b[0]


def test_bandwidths_are_the_half_power_width_of_the_peaks():
    tract, air = Tract(from_pieces((9, 8), (6, 1))), Air()
    f, b = _formants(tract, air)
    for fk, bk in zip(f[:3], b[:3]):
        g = np.linspace(fk - 80, fk + 80, 160001)
        m = np.abs(transfer(tract, g, air))
        top = np.argmax(m)
        above = np.flatnonzero(m >= m[top] / np.sqrt(2))
        assert abs(g[top] - fk) < 0.01 and abs((g[above[-1]] - g[above[0]]) - bk) < 0.02


def test_the_piriform_fossae_lower_the_formants_the_more_the_larger_they_are():
    ac = load_config().acoustics
    air, tube = air_of(ac), uniform(17.5, 4.0)
    plain, _ = _formants(Tract(tube), air)
    fossa, _ = _formants(tract_of(tube, ac), air)
    bigger = ac.model_copy(update={"piriform_fossa": ac.piriform_fossa.model_copy(update={"volume_cm3": 3.0})})
    more, _ = _formants(tract_of(tube, bigger), air)
    assert np.all(fossa[:3] < plain[:3]) and np.all(more[:3] < fossa[:3]) and np.all(fossa[:3] > 0.8 * plain[:3])


def test_an_open_velum_adds_a_nasal_resonance():
    ac = load_config().acoustics
    air, tube = air_of(ac), uniform(17.5, 4.0)
    closed, _ = _formants(tract_of(tube, ac, 0.0), air)
    nasal, _ = _formants(tract_of(tube, ac, 0.5), air)
    assert len(np.flatnonzero(nasal < 1600)) > len(np.flatnonzero(closed < 1600))  # an extra peak below F2


def _tube_file(tmp_path, text):
    p = tmp_path / "t.csv"
    p.write_text(text)
    return p


def test_the_command_prints_formants_and_writes_its_file(tmp_path):
    t = _tube_file(tmp_path, "length_cm,area_cm2\n" + "0.875,4\n" * 20)
    res = CliRunner().invoke(app, ["acoustics", "--tube", str(t), "--lossless", "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    assert [round(v) for v in doc["formants_hz"][:4]] == [500, 1500, 2500, 3500] and doc["bandwidths_hz"][0] == 0
    res = CliRunner().invoke(app, ["acoustics", "--tube", str(t), "--out", str(tmp_path / "a.h5"), "--plot",
                                   str(tmp_path / "a.png")])
    assert res.exit_code == 0 and (tmp_path / "a.h5").is_file() and (tmp_path / "a.png").stat().st_size > 20000
    from artic_cli.stages.acoustics import read

    r = read(tmp_path / "a.h5")
    assert r.transfer_db.shape == (1, len(r.frequency_hz)) and r.formants_hz.shape == (1, 5)


@pytest.mark.parametrize("text, needle", [
    ("length,area\n1,2\n1,2\n", "header must be 'length_cm,area_cm2'"),
    ("length_cm,area_cm2\n1,2\n", "at least two sections"),
    ("length_cm,area_cm2\n1,2\n1,2,3\n", "line 3"),
    ("length_cm,area_cm2\n1,2\n0,2\n", "line 3: key 'length_cm'"),
    ("length_cm,area_cm2\n1,2\n1,-1\n", "greater than or equal to 0"),
    ("length_cm,area_cm2\n1,2\n1,nan\n", "finite"),
    ("length_cm,area_cm2\n1,2\n1,x\n", "must be a number"),
    ("", "header"),
])
def test_bad_tubes_are_one_line_and_write_nothing(tmp_path, text, needle):
    t = _tube_file(tmp_path, text)
    res = CliRunner().invoke(app, ["acoustics", "--tube", str(t), "--out", str(tmp_path / "a.h5")])
    assert res.exit_code == 2 and needle in res.output and "Traceback" not in res.output, res.output
    assert not (tmp_path / "a.h5").exists()
    res = CliRunner().invoke(app, ["acoustics", "--tube", str(tmp_path / "none.csv")])
    assert res.exit_code == 2 and "not found" in res.output


@pytest.mark.parametrize("losses", [dict(), dict(viscous=False, heat=False, walls=False)])
def test_the_compiled_chain_is_the_numpy_chain(losses):
    from artic_cli.acoustics.chain import Air, chain, chain_numpy

    air = Air(**losses)
    rng = np.random.default_rng(3)
    length, area = np.full(44, 17.5 / 44), rng.uniform(0.0, 6.0, 44)
    area[7] = 0.0  # a closure
    w = 2 * np.pi * np.linspace(5.0, 5500.0, 300)
    a, b = chain(length, area, w, air), chain_numpy(length, area, w, air)
    np.testing.assert_allclose(a, b, rtol=1e-10, atol=0)


def test_opening_the_velum_lowers_f1_and_the_sinuses_act_only_through_it():
    ac = load_config().acoustics
    air, tube = air_of(ac), uniform(17.5, 4.0)
    closed, _ = _formants(tract_of(tube, ac, 0.0), air)
    nasal, _ = _formants(tract_of(tube, ac, 0.5), air)
    assert nasal[0] <= 0.95 * closed[0]  # the figure: at least 5 % lower
    no_sinus = ac.model_copy(update={"nasal": ac.nasal.model_copy(update={"sinuses_enabled": False})})
    shut, _ = _formants(tract_of(tube, no_sinus, 0.0), air)
    np.testing.assert_array_equal(shut, closed)  # the velum closed: the sinuses change nothing
    plain, _ = _formants(tract_of(tube, no_sinus, 0.5), air)
    assert plain[0] > nasal[0]  # the lowering is the sinuses' (without them the port raises the first peak)
