"""The sources of every manner (issue 44), heard by Praat in utterances driven by tract courses alone (the lips,
the port and the glottis; the tongue's forces given): a nasal murmur, a voiced and a voiceless closure, a
glottal fricative, a release burst; the nasal branch against the transfer function; the line bit for bit as
it was with the port closed and the new sources off; bad inputs."""

from __future__ import annotations

import sys

import numpy as np
import pytest
import yaml

from artic_cli.acoustics.model import air_of, tract_of
from artic_cli.acoustics.nasal import nasal_line
from artic_cli.acoustics.synthesis import Extra, resample_tube, sections_for, side_branch, synthesize
from artic_cli.acoustics.transfer import nostril_transfer, transfer
from artic_cli.acoustics.tube import Tube, uniform
from artic_cli.config import load_config
from artic_cli.stages import speak

from conftest import ROOT, need, praat_f0, praat_level_db, run_cli

A = {"forces_n": {"JO": 2.5, "HG": 1.0}, "label": "a"}  # the jaw open, the tongue back
TIP = {"forces_n": {"JC": 1.5, "GGp": 6, "T": 8}}  # the laminal alveolar seal of configs/utterances/ata.yaml
V1, V2 = (0.08, 0.20), (0.34, 0.46)  # the vowels' middles
C0, C1 = 0.22, 0.30  # the consonant's segment
LIPS = [{"at_ms": 220, "ramp_ms": 10, "lip_area_cm2": 0.0}, {"at_ms": 300, "ramp_ms": 10, "lip_area_cm2": 3.0}]
PORT = [{"at_ms": 190, "ramp_ms": 20, "velum_port_cm2": 0.5}, {"at_ms": 310, "ramp_ms": 20, "velum_port_cm2": 0.0}]


def _vcv(label: str, mid: dict, tract: list, voiced: bool = True, tongue: bool = False) -> dict:
    seg = dict(mid, duration_ms=80, label=label, voiced=voiced)
    last = dict(A, duration_ms=220)
    if tongue:  # the tip's closure takes the tongue 150 ms to make (configs/utterances/ata.yaml)
        seg["lead_ms"], last["lead_ms"] = 150, 40
    return {"name": f"a{label}a", "f0_hz": [[0.0, 125], [0.5, 105]], "force_course": "static", "lead_ms": 0,
            "prepare_ms": 0, "segments": [dict(A, duration_ms=220), seg, last], "tract": tract}


UTTERANCES = {"m": _vcv("m", A, LIPS + PORT), "n": _vcv("n", TIP, PORT, tongue=True), "b": _vcv("b", A, LIPS),
              "p": _vcv("p", A, LIPS, voiced=False), "h": _vcv("h", A, [], voiced=False),
              "t": _vcv("t", TIP, [], voiced=False, tongue=True),
              # the /b/ with the cavity enlarging while closed, as the inventory's voiced stops ask (120 cm^3/s)
              "bx": dict(_vcv("b", dict(A, cavity_expansion_cm3_s=120), LIPS), name="abxa")}


@pytest.fixture(scope="module")
def spoken(tmp_path_factory, mesh_file):
    tmp = tmp_path_factory.mktemp("sources")
    for c, doc in UTTERANCES.items():
        (tmp / f"a{c}a.yaml").write_text(yaml.safe_dump(doc))
        res = run_cli("speak", tmp / f"a{c}a.yaml", "--mesh", mesh_file, "--out", tmp / f"a{c}a.wav")
        assert res.exit_code == 0, res.output
    return tmp


def _band_db(wav, t0, t1, lo, hi) -> float:
    parselmouth = need("parselmouth")
    from parselmouth.praat import call

    part = call(parselmouth.Sound(str(wav)).extract_part(from_time=t0, to_time=t1), "Filter (pass Hann band)", lo, hi,
                100)
    level = call(part, "Get intensity (dB)")
    return float(level) if np.isfinite(level) else -300.0


def _vowels_db(wav, lo=None, hi=None) -> float:
    if lo is None:
        return float(np.mean([praat_level_db(wav, *v) for v in (V1, V2)]))
    return float(np.mean([_band_db(wav, *v, lo, hi) for v in (V1, V2)]))


def _closure(rec, below_cm2: float = 1e-3) -> tuple[float, float]:
    """The consonant's closure in the record: the frames whose narrowest area is (nearly) zero."""
    shut = rec.time_s[(rec.area_cm2.min(axis=1) <= below_cm2) & (rec.time_s > 0.15) & (rec.time_s < 0.4)]
    return float(shut[0]), float(shut[-1])


def _voiced(wav, t0, t1) -> float:
    times = np.arange(t0 + 0.0025, t1, 0.005)
    return float(np.mean(np.isfinite(praat_f0(wav, times))))


@pytest.mark.parametrize("c", ["m", "n"])
def test_a_nasal_murmur_is_voiced_and_low_and_as_loud_as_a_murmur(spoken, c):
    """The /m/ (lips) and /n/ (the tip's closure) with the port open 0.5 cm^2: voiced in >= 70 % of the
    closure's frames, 25 dB below the vowels to 5 dB above, its energy below 500 Hz against 500-4000 Hz at
    least 6 dB above the vowels' ratio."""
    wav = spoken / f"a{c}a.wav"
    t0, t1 = _closure(speak.read(spoken / f"a{c}a.h5"))
    assert t1 - t0 >= 0.04, (t0, t1)  # the lips shut 80 ms, the tip 45 ms (its forces take 150 ms to seal)
    inside = (t0 + 0.01, t1 - 0.01)
    assert _voiced(wav, *inside) >= 0.7
    level = praat_level_db(wav, *inside) - _vowels_db(wav)
    assert -25.0 <= level <= 5.0, level
    ratio = _band_db(wav, *inside, 0, 500) - _band_db(wav, *inside, 500, 4000)
    assert ratio >= _vowels_db(wav, 0, 500) - _vowels_db(wav, 500, 4000) + 6.0


def test_a_voiceless_closure_is_silent_and_its_voice_starts_after_aspiration(spoken):
    """/apa/: the closure at least 25 dB below the vowels, the voice back 15-40 ms after the release."""
    wav = spoken / "apa.wav"
    rec = speak.read(spoken / "apa.h5")
    t0, t1 = _closure(rec)
    assert praat_level_db(wav, t0 + 0.01, t1 - 0.01) <= _vowels_db(wav) - 25.0
    after = np.arange(t1, t1 + 0.1, 0.0025)
    f0 = praat_f0(wav, after)
    vot = float(after[np.argmax(np.isfinite(f0))] - t1)
    assert np.isfinite(f0).any() and 0.015 <= vot <= 0.040, vot
    # aspiration before the voice: noise above 1 kHz in the first 10 ms after the release
    assert _band_db(wav, t1, t1 + 0.01, 1000, 8000) > _band_db(wav, t0 + 0.01, t1 - 0.01, 1000, 8000) + 20


def test_a_voiced_closure_keeps_voicing_until_the_air_behind_it_stops_it(spoken):
    """/aba/: the voice goes on into the closure while the transglottal pressure holds (the record's voice
    gain), and fades as the cavity fills: the closure at least 12 dB below the vowels, the oral pressure
    rising toward the lungs'."""
    wav = spoken / "aba.wav"
    rec = speak.read(spoken / "aba.h5")
    t0, t1 = _closure(rec)
    assert praat_level_db(wav, t0 + 0.01, t1 - 0.01) <= _vowels_db(wav) - 12.0
    import h5py

    with h5py.File(spoken / "aba.h5") as f:
        gain, pressure = f["aerodynamics/voice_gain"][()], f["aerodynamics/oral_pressure"][()]
    inside = (rec.time_s >= t0) & (rec.time_s <= t1)
    assert np.mean(gain[inside] > 0.05) >= 0.4  # voiced in the model for at least 40 % of the closure
    assert pressure[inside][-1] > 0.8 * 8000.0 > pressure[inside][0]  # filling toward 0.8 kPa


@pytest.mark.xfail(strict=True, reason="the voice bar radiated by the yielding walls is about 33 dB below the "
                   "vowels' peak at full voice and fades with the transglottal pressure: below Praat's silence "
                   "threshold (0.03 of the peak), so Praat calls the closure unvoiced (docs/modelling.md, Sources)")
def test_praat_hears_a_passive_voiced_closure_voiced_in_40_percent_of_its_frames(spoken):
    wav = spoken / "aba.wav"
    t0, t1 = _closure(speak.read(spoken / "aba.h5"))
    assert _voiced(wav, t0 + 0.005, t1 - 0.005) >= 0.4


def test_praat_hears_a_closure_with_the_cavity_enlarging_voiced_in_40_percent_of_its_frames(spoken):
    """/aba/ with the cavity enlarging at 120 cm^3/s while closed (speech/expansion.py): the pressure behind
    the lips ends at least 0.1 kPa lower than the passive walls let it rise, and Praat hears the
    closure voiced in at least 40 % of its frames."""
    import h5py

    t0, t1 = _closure(speak.read(spoken / "abxa.h5"))
    assert _voiced(spoken / "abxa.wav", t0 + 0.005, t1 - 0.005) >= 0.4
    ends = []
    for name in ("aba", "abxa"):
        rec = speak.read(spoken / f"{name}.h5")
        a, b = _closure(rec)
        with h5py.File(spoken / f"{name}.h5") as f:
            ends.append(float(np.interp(b, rec.time_s, f["aerodynamics/oral_pressure"][()])))
    assert ends[1] < ends[0] - 1000.0, ends  # dyn/cm^2


def test_a_glottal_fricative_is_voiceless_noise(spoken):
    """/aha/: the /h/ voiceless in at least half its frames (the glottis open 0.3 cm^2), with noise from 1 to
    8 kHz."""
    wav = spoken / "aha.wav"
    inside = (C0 + 0.02, C1 - 0.01)
    assert _voiced(wav, *inside) <= 0.5
    assert _band_db(wav, *inside, 1000, 8000) >= _vowels_db(wav, 1000, 8000) - 15.0


@pytest.mark.xfail(strict=True, reason="Flanagan's aspiration source at a 0.3-cm^2 glottis puts the /h/ "
                   "11.8 dB below the vowels from 1 to 8 kHz, not within 10 dB (docs/modelling.md, Sources)")
def test_a_glottal_fricative_s_noise_is_within_10_db_of_the_vowels_from_1_to_8_khz(spoken):
    wav = spoken / "aha.wav"
    assert _band_db(wav, C0 + 0.02, C1 - 0.01, 1000, 8000) >= _vowels_db(wav, 1000, 8000) - 10.0


def test_a_release_bursts_above_its_closure(spoken):
    """/ata/: the first 10 ms after the tip's release at least 10 dB above the closure from 2 to 8 kHz."""
    wav = spoken / "ata.wav"
    t0, t1 = _closure(speak.read(spoken / "ata.h5"))
    assert t1 - t0 >= 0.02, (t0, t1)
    assert _band_db(wav, t1, t1 + 0.01, 2000, 8000) >= _band_db(wav, t0 + 0.005, t1 - 0.005, 2000, 8000) + 10


# --- the nasal branch ----------------------------------------------------------------------------------------

def _extremes(f, level):
    from scipy.signal import argrelextrema

    return f[argrelextrema(level, np.greater, order=3)[0]], f[argrelextrema(level, np.less, order=3)[0]]


@pytest.mark.parametrize("lips", ["open", "closed"])
def test_the_nasal_branch_sounds_the_transfer_function_s_first_pole_and_zero(tmp_path, lips):
    """A frozen frame with the port open 0.5 cm^2 (a nasalised [a]-like tube; the same with the lips shut, an
    /m/): the line's impulse response, read by Praat, has the transfer function's (lips + nostrils) first
    nasal pole and first antiresonance within 5 %."""
    parselmouth = need("parselmouth")
    from parselmouth.praat import call

    from artic_cli.io.wav import write_wav
    from artic_cli.acoustics.resample import half_rate
    from artic_cli.acoustics.voice import Audio

    ac = load_config().acoustics
    air = air_of(ac)
    fs, length = 88200.0, 17.5
    area = uniform(length, 3.0, 44).area_cm2.copy()
    if lips == "closed":
        area[-2:] = 0.0
    tube = Tube(np.full(44, length / 44), area)
    port_at = length - ac.nasal.port_from_lips_cm
    f = np.arange(100.0, 3000.0, 2.0)
    tf = np.abs(2j * np.pi * f * (transfer(t := tract_of(tube, ac, 0.5, port_from_glottis_cm=port_at), f, air)
                                 + nostril_transfer(t, f, air)))
    poles, zeros = _extremes(f, 20 * np.log10(tf))
    n = sections_for(length, ac.sound_speed_cm_s, fs)
    fossa = tract_of(Tube(np.array([length]), np.array([1.0])), ac, velum_area_cm2=0.0).branches[0].tube
    branch = side_branch(ac.piriform_fossa.from_glottis_cm, length, n, fossa.length_cm, fossa.area_cm2,
                         ac.sound_speed_cm_s, fs)
    nl = nasal_line(ac.nasal, int(round(port_at / (length / n))) - 1, ac.sound_speed_cm_s / fs,
                    ac.air_density_g_cm3, ac.sound_speed_cm_s)
    src = np.zeros(int(fs))
    src[0], src[1] = 1.0, -1.0  # a flow impulse
    y = synthesize(resample_tube(tube.length_cm, tube.area_cm2, n)[None], np.array([0.0]), src, fs,
                   ac.synthesis.glottal_reflection, ac.synthesis.section_loss, ac.air_density_g_cm3,
                   ac.sound_speed_cm_s, branch, None, None,
                   (ac.wall_mass_g_cm2, ac.wall_resistance_dyn_s_cm3, ac.wall_stiffness_dyn_cm3),
                   Extra(nasal=nl, frame_ports_cm2=np.array([0.5])))
    y = half_rate(y)
    write_wav(tmp_path / "n.wav", Audio(0.9 * y / np.abs(y).max(), 44100))
    spectrum = call(parselmouth.Sound(str(tmp_path / "n.wav")), "To Spectrum", "no")  # Praat's DFT of the WAV
    re, im = spectrum.values
    heard = np.interp(f, spectrum.xs(), 10 * np.log10(re * re + im * im + 1e-30))
    p2, z2 = _extremes(f, heard)
    assert abs(p2[0] / poles[0] - 1) <= 0.05, (p2[:3], poles[:3])
    assert abs(z2[0] / zeros[0] - 1) <= 0.05, (z2[:3], zeros[:3])


def test_with_the_port_closed_the_line_is_bit_for_bit_what_it_was():
    sys.path.insert(0, str(ROOT / "tests" / "fixtures" / "synthesis"))
    from refresh import line_input, line_output

    before = np.load(ROOT / "tests" / "fixtures" / "synthesis" / "line_before_nasal.npy")
    assert np.array_equal(line_output(), before)
    areas, times, *_ = line_input()
    ac = load_config().acoustics
    nl = nasal_line(ac.nasal, 20, 35000.0 / 88200.0, ac.air_density_g_cm3, ac.sound_speed_cm_s)
    closed = line_output(extra=Extra(nasal=nl, frame_ports_cm2=np.zeros(len(times))))
    assert np.array_equal(closed, before)
    opened = line_output(extra=Extra(nasal=nl, frame_ports_cm2=np.full(len(times), 0.3)))
    assert np.isfinite(opened).all() and not np.array_equal(opened, before)


def test_the_compiled_cavities_are_the_plain_ones_on_the_interpolated_areas():
    from artic_cli.acoustics.airflow import cavities, line_cavities

    rng = np.random.default_rng(1)
    frames = rng.uniform(0, 4, (5, 43))
    frames[2, 30:33] = 0.0  # a closure in the middle frame
    index = np.linspace(0, 4, 333)
    got = line_cavities(frames, 0.4, index)
    k0 = np.clip(index.astype(int), 0, 3)
    w = (index - k0)[:, None]
    want = cavities(np.full((len(index), 43), 0.4), (1 - w) * frames[k0] + w * frames[k0 + 1])
    for name in ("index", "end", "area_cm2", "volume_cm3", "wall_cm2"):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-12, atol=1e-12)


# --- bad input -----------------------------------------------------------------------------------------------

@pytest.mark.parametrize("change, says", [
    (lambda d: d["tract"].append({"at_ms": 100, "glottis_cm2": -0.1}), "glottis_cm2"),
    (lambda d: d["tract"].append({"at_ms": 100, "velum_port_cm2": float("nan")}), "velum_port_cm2"),
    (lambda d: d["tract"].append({"at_ms": 100, "velum_port_cm2": -0.5}), "velum_port_cm2"),
    (lambda d: d["segments"][1].update(glottis_cm2=-0.2), "glottis_cm2"),
    (lambda d: d["tract"].append({"at_ms": 900, "glottis_cm2": 0.3}), "not inside the utterance"),
])
def test_a_bad_glottis_or_port_course_is_one_line_and_exit_2_with_no_wav(tmp_path, mesh_file, change, says):
    doc = yaml.safe_load(yaml.safe_dump(UTTERANCES["m"]))
    change(doc)
    u = tmp_path / "u.yaml"
    u.write_text(yaml.safe_dump(doc))
    res = run_cli("speak", u, "--mesh", mesh_file, "--out", tmp_path / "out" / "u.wav")
    assert res.exit_code == 2 and says in res.output and "Traceback" not in res.output, res.output
    assert len(res.output.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("kpa", [0.0, -0.5, 9.0, "nan"])
def test_a_lung_pressure_out_of_range_is_one_line_and_exit_2_with_no_wav(tmp_path, mesh_file, kpa):
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d.setdefault("speech", {})["lung_pressure_kpa"] = float(kpa)
    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump(d))
    u = tmp_path / "u.yaml"
    u.write_text(yaml.safe_dump(UTTERANCES["h"]))
    res = run_cli("speak", u, "--mesh", mesh_file, "--config", cfg, "--out", tmp_path / "out" / "u.wav")
    assert res.exit_code == 2 and "lung_pressure_kpa" in res.output and "Traceback" not in res.output, res.output
    assert not (tmp_path / "out").exists()


def test_every_source_switches_off(tmp_path, mesh_file, spoken):
    """Each source off changes the sound (the config's acoustics.sources), and all off with the port closed
    leaves no nasal, aspiration or burst in the record."""
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d.setdefault("acoustics", {})["sources"] = {"nasal_branch": False, "aerodynamic_voicing": False,
                                                "bursts": False, "voice_bar": False, "aspiration": False}
    cfg = tmp_path / "off.yaml"
    cfg.write_text(yaml.safe_dump(d))
    res = run_cli("speak", spoken / "ama.yaml", "--mesh", mesh_file, "--config", cfg, "--out", tmp_path / "m.wav")
    assert res.exit_code == 0, res.output
    import h5py

    with h5py.File(tmp_path / "m.h5") as f:
        assert not f["aerodynamics/aspiration_rms"][()].any() and not f["aerodynamics/nose_cm2"][()].any()
    from artic_cli.io.wav import read_wav

    on, _ = read_wav(spoken / "ama.wav")
    off, _ = read_wav(tmp_path / "m.wav")
    t0, t1 = _closure(speak.read(tmp_path / "m.h5"))
    # without the nasal branch the /m/ is the closed tract's voice bar alone: far weaker than the murmur
    assert praat_level_db(tmp_path / "m.wav", t0 + 0.01, t1 - 0.01) < praat_level_db(spoken / "ama.wav", t0 + 0.01,
                                                                                     t1 - 0.01) - 10


@pytest.mark.parametrize("c, manner", [("m", "nasal"), ("n", "nasal"), ("b", "stop"), ("p", "stop"),
                                       ("h", "fricative"), ("t", "stop")])
def test_the_reports_landmarks_measure_what_praat_hears(spoken, c, manner):
    """speech/landmarks.py (numpy, what the report tables) against Praat on the same WAVs: levels within 2 dB,
    band ratios within 3 dB (Praat's Hann band filter has 100-Hz skirts, Welch's bands are sharp: at a 500-Hz
    edge beside a murmur's strong low band the two part by about 2 dB), the closure on the same side of its
    goal."""
    from artic_cli.io.wav import read_wav
    from artic_cli.speech.landmarks import measure

    wav = spoken / f"a{c}a.wav"
    y, rate = read_wav(wav)
    m = measure(y, rate, (C0, C1, c), [V1, V2], manner)
    assert abs(m["level_db"] - (praat_level_db(wav, C0, C1) - _vowels_db(wav))) <= 2.0
    if manner == "nasal":
        a, b = C0 + 0.25 * (C1 - C0), C1 - 0.25 * (C1 - C0)
        praat = (_band_db(wav, a, b, 0, 500) - _band_db(wav, a, b, 500, 4000)
                 - (_vowels_db(wav, 0, 500) - _vowels_db(wav, 500, 4000)))
        assert abs(m["low_ratio_db"] - praat) <= 3.0, (m["low_ratio_db"], praat)
    if manner == "fricative":
        a, b = C0 + 0.2 * (C1 - C0), C1 - 0.2 * (C1 - C0)
        praat = _band_db(wav, a, b, 1000, 8000) - _vowels_db(wav, 1000, 8000)
        assert abs(m["band_1_8k_db"] - praat) <= 2.0, (m["band_1_8k_db"], praat)
    if manner == "stop" and c != "b":
        assert m["closure_ms"] >= 25 and praat_level_db(wav, C0 + 0.02, C1 - 0.02) - _vowels_db(wav) <= -25


@pytest.mark.parametrize("c", ["m", "n", "h", "t", pytest.param("b", marks=pytest.mark.xfail(
    strict=True, reason="our frames call the closure's first 15 ms voiced (25 % of it), Praat's path finder "
                        "6 %: docs/inventory.md, Landmarks")), pytest.param("p", marks=pytest.mark.xfail(
    strict=True, reason="as /b/: 25 % against Praat's 6 %"))])
def test_the_reports_voicing_is_praats_within_0_15(spoken, c):
    from artic_cli.io.wav import read_wav
    from artic_cli.speech.landmarks import share_voiced

    wav = spoken / f"a{c}a.wav"
    y, rate = read_wav(wav)
    ours, praat = share_voiced(y, rate, C0, C1), _voiced(wav, C0, C1)
    assert abs(ours - praat) <= 0.15, (ours, praat)


@pytest.mark.parametrize("c", ["m", "t", "h"])
def test_the_reports_vowel_classes_are_what_praat_hears(spoken, c):
    """speech/vowel_class.py on the model's formant tracks and on Praat's (Burg) over the same vowels' middle
    halves: the same nearest male Japanese mean for each vowel, F1 and F2 within 10 %."""
    from artic_cli.speech.inventory import load_inventory
    from artic_cli.speech.vowel_class import heard_vowels, nearest_vowel

    from conftest import praat_formants_near

    means = {v: tuple(p.formants_hz[:2]) for v, p in load_inventory().phonemes.items() if p.manner == "vowel"}
    rec = speak.read(spoken / f"a{c}a.h5")
    ivs = [(0.0, 0.22, "a"), (0.30, 0.52, "a")]
    ours = heard_vowels(ivs, rec.time_s, rec.formants_hz, means)
    for (t0, t1, _), h in zip(ivs, ours):
        q = 0.25 * (t1 - t0)
        heard, _ = praat_formants_near(spoken / f"a{c}a.wav", np.linspace(t0 + q, t1 - q, 7), [h["f1_hz"], h["f2_hz"]])
        assert nearest_vowel(heard[0], heard[1], means) == h["heard"], (c, t0, heard, h)
        assert abs(heard[0] / h["f1_hz"] - 1) <= 0.10 and abs(heard[1] / h["f2_hz"] - 1) <= 0.10, (heard, h)
