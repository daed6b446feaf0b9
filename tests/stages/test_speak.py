"""`artic speak`: bad utterances are one line and exit 2 with nothing written; a spoken sequence gives a WAV,
a TextGrid Praat reads and a record; a lip closure is silent and its release noisy; a narrow channel makes
frication that the noise switch takes away; the force course ramps and holds as the paper's controller."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from artic_cli.acoustics.aerodynamics import flow, noise_rms, reynolds
from artic_cli.io.wav import read_wav
from artic_cli.speech.course import course
from artic_cli.speech.measures import measures
from artic_cli.speech.plan import Plan
from artic_cli.stages import speak

from conftest import ROOT, need, praat_f0, praat_level_db, praat_silences, run_cli

_run = run_cli


def _write(path, doc):
    path.write_text(yaml.safe_dump(doc))
    return path


A = {"forces_n": {"JO": 2.5, "HG": 1.0}, "duration_ms": 150, "label": "a"}  # the jaw open, the tongue back


@pytest.mark.parametrize("doc, says", [
    ({"segments": [dict(A, duration_ms=0)]}, "segments.0.duration_ms"),
    ({"segments": [dict(A, duration_ms=-20)]}, "segments.0.duration_ms"),
    ({"segments": [A], "f0_hz": [[0, 40]]}, "outside 50-500 Hz"),
    ({"segments": [A], "f0_hz": [[0, 120], [0.3, 600]]}, "outside 50-500 Hz"),
    ({"segments": [A], "f0_hz": [[0.2, 120], [0.1, 110]]}, "rise strictly"),
    ({"segments": [A], "f0_hz": [[0.1, 120], [0.1, 110]]}, "rise strictly"),
    ({"segments": [A], "f0_hz": [[0.0, float("nan")]]}, "f0_hz"),
    ({"segments": []}, "segments"),
    ({"segments": [{"duration_ms": 100}]}, "either 'target'"),
    ({"segments": [dict(A, target="configs/targets/velar.yaml")]}, "either 'target'"),
    ({"segments": [{"target": "no/such/target.yaml", "duration_ms": 100}]}, "target file not found"),
    ({"segments": [dict(A, forces_n={"XYZ": 1.0})]}, "'XYZ' is unknown"),
    ({"segments": [dict(A, forces_n={"GGp": -1.0})]}, "forces_n.GGp"),
    ({"segments": [dict(A, press=1.5)]}, "'press' scales a solved target's forces"),
    ({"lead_ms": 0, "prepare_ms": 0, "segments": [A, dict(A, lead_ms=200)]}, "shorten its lead_ms"),
    ({"segments": [dict(A, lead_ms=-10)]}, "segments.0.lead_ms"),
    ({"segments": [{"target": {"name": "x", "crucial": {"point": "tip", "at_cm": [0, 0]}, "acoustic":
                                {"formants_hz": [500, 1500]}}, "duration_ms": 100}]}, "one of them"),
])
def test_a_bad_utterance_is_one_line_and_exit_2_with_nothing_written(tmp_path, mesh_file, doc, says):
    u = _write(tmp_path / "u.yaml", doc)
    res = _run("speak", u, "--mesh", mesh_file, "--out", tmp_path / "out" / "u.wav", "--maps", tmp_path / "none.h5")
    assert res.exit_code == 2, res.output
    assert says in res.output and "Traceback" not in res.output, res.output
    assert not (tmp_path / "out").exists()


def test_the_force_course_ramps_from_where_it_got_and_holds():
    f = course([0.0, 0.1, 0.12], np.array([[4.0], [0.0], [2.0]]), 0.03)
    assert f(0.0)[0] == 0.0 and f(0.015)[0] == pytest.approx(2.0) and f(0.05)[0] == 4.0 and f(0.099)[0] == 4.0
    # the second ramp is cut short at 0.12 s (two thirds of the way: 4 -> 1); the third starts from there
    at = f(0.12 - 1e-9)[0]
    assert at == pytest.approx(4.0 * (0.5 + 0.5 * np.cos(np.pi * 2 / 3)), abs=1e-6)
    assert f(0.135)[0] == pytest.approx(at + (2.0 - at) * 0.5) and f(0.5)[0] == 2.0


def test_the_air_stops_at_a_closure_and_is_turbulent_in_a_narrow_channel():
    rho, mu = 1.14e-3, 1.86e-4
    ps = 8000.0  # dyn/cm^2 (0.8 kPa)
    assert flow(ps, 0.3, 0.0, rho) == 0.0
    u = flow(ps, 0.3, 0.08, rho)
    assert 250 < u < 320  # Bernoulli through both orifices: about 290 cm^3/s
    assert reynolds(u, 0.08, rho, mu) > 1800 > reynolds(flow(ps, 0.05, 3.0, rho), 3.0, rho, mu)
    assert noise_rms(u, 0.08, rho, mu, 1800.0, 0.05) > 100 * noise_rms(flow(ps, 0.05, 3.0, rho), 3.0, rho, mu,
                                                                       1800.0, 0.05)


LAB = {"name": "lab", "f0_hz": [[0.0, 125], [0.75, 100]], "force_course": "static", "lead_ms": 0, "prepare_ms": 0,
       "segments": [dict(A, duration_ms=200), {"forces_n": {"JO": 0.5}, "duration_ms": 100, "label": "p",
                                                 "voiced": False},
                    dict(A), {"forces_n": {"JO": 0.5}, "duration_ms": 150, "label": "f", "voiced": False},
                    dict(A), {"forces_n": {"JO": 0.5, "GGp": 4.0, "SL": 1.0}, "duration_ms": 250, "label": "i"}],
       "tract": [{"at_ms": 200, "ramp_ms": 15, "lip_area_cm2": 0.0}, {"at_ms": 300, "ramp_ms": 10, "lip_area_cm2": 3.0},
                 {"at_ms": 450, "ramp_ms": 20, "lip_area_cm2": 0.08},
                 {"at_ms": 600, "ramp_ms": 20, "lip_area_cm2": 3.0}]}


@pytest.fixture(scope="module")
def spoken(tmp_path_factory, mesh_file):
    """/apa/ and a bilabial fricative between open-jaw vowels (the lips closed, then a narrow lip channel), then
an /i/-like front vowel (GGp 4 N, SL 1 N, the jaw nearly closed)."""
    tmp = tmp_path_factory.mktemp("speak")
    u = _write(tmp / "lab.yaml", LAB)
    res = _run("speak", u, "--mesh", mesh_file, "--out", tmp / "lab.wav", "--plot", tmp / "lab.png")
    assert res.exit_code == 0, res.output
    return tmp


def test_a_spoken_sequence_writes_its_sound_textgrid_and_record(spoken, mesh_file):
    rec = speak.read(spoken / "lab.h5")
    assert rec.labels == ["a", "p", "a", "f", "a", "i"]
    y, rate = read_wav(spoken / "lab.wav")
    assert len(y) / rate == pytest.approx(1.0, abs=0.002)
    assert (spoken / "lab.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert np.nanmax(np.abs(rec.volume_change)) <= 0.003 and rec.attrs["max_beyond_wall_cm"] <= 0.01
    assert rec.attrs["inverted_bricks_max"] == 0
    # the jaw opens for each /a/ (JO 2.5 N) and closes between them
    jaw = rec.control_points["jaw"][:, 1]
    t = rec.time_s
    open_, shut = jaw[np.searchsorted(t, 0.19)], jaw[np.searchsorted(t, 0.29)]
    assert open_ < jaw[0] - 0.2 and shut > open_
    # the TextGrid: one interval per segment, read by praatio (and by Praat when the test extra is there)
    from praatio import textgrid

    tg = textgrid.openTextgrid(str(spoken / "lab.TextGrid"), includeEmptyIntervals=False)
    tier = tg.getTier("phones")
    assert [e.label for e in tier.entries] == rec.labels
    assert [round(e.start, 6) for e in tier.entries] == pytest.approx(rec.starts_s.tolist())
    # a second run finds everything up to date
    res = _run("speak", spoken / "lab.yaml", "--mesh", mesh_file, "--out", spoken / "lab.wav")
    assert res.exit_code == 0 and "up to date" in res.output
    parselmouth = need("parselmouth")  # and Praat reads the TextGrid
    grid = parselmouth.read(str(spoken / "lab.TextGrid"))
    assert parselmouth.praat.call(grid, "Get number of intervals", 1) == 6


def test_the_rest_posture_and_held_forces_are_kept_and_give_the_same_record(spoken, mesh_file):
    """A second speaking reads the articulator, its rest posture and each set of held forces' end from the cache
    beside the solutions, and writes the same record; a damaged entry is made again."""
    cache = spoken / "solutions" / speak.CACHE
    kept = sorted(p.name for p in cache.glob("*.npz"))
    first = speak.read(spoken / "lab.h5")
    distinct = len(np.unique(first.eps_cm.reshape(len(first.labels), -1), axis=0))  # a, the lips' sets, i
    assert sum(n.startswith("rest-") for n in kept) == 1 and sum(n.startswith("ep-") for n in kept) == distinct >= 3
    damaged = next(cache.glob("ep-*.npz"))
    damaged.write_bytes(b"not an npz file")
    res = _run("speak", spoken / "lab.yaml", "--mesh", mesh_file, "--out", spoken / "again.wav",
               "--solutions", spoken / "solutions")
    assert res.exit_code == 0, res.output
    again = speak.read(spoken / "again.h5")
    assert sorted(p.name for p in cache.glob("*.npz")) == kept and damaged.read_bytes()[:2] == b"PK"
    assert np.array_equal(again.eps_cm, first.eps_cm, equal_nan=True)
    for name in first.control_points:
        assert np.array_equal(again.control_points[name], first.control_points[name])


def test_the_articulator_is_kept_once_built_and_read_back_the_same(tmp_path, mesh_file, cfg):
    from artic_cli.io.result_cache import ResultCache
    from artic_cli.stages import mesh as mesh_stage

    m = mesh_stage.read(mesh_file, cfg)
    cache = ResultCache(tmp_path / "cache", "model", {"mesh": m.content_sha256})
    built = speak.articulator(cfg, m, cache)
    assert not (tmp_path / "cache").exists()  # nothing written before the run commits
    cache.commit()
    kept, = (tmp_path / "cache").glob("model-*.pickle")
    back = speak.articulator(cfg, m, ResultCache(tmp_path / "cache", "model", {"mesh": m.content_sha256}))
    assert back is not built and np.array_equal(back.rest, built.rest) and back.muscle_names == built.muscle_names
    kept.write_bytes(b"damaged")  # a damaged entry is built again
    assert np.array_equal(speak.articulator(cfg, m, ResultCache(tmp_path / "cache", "model",
                                                                {"mesh": m.content_sha256})).rest, built.rest)


def _praat_stop(wav, vowel: tuple[float, float], window: tuple[float, float]) -> tuple[float, float, float]:
    """A stop as Praat hears it: the one silence (30 dB or more below the vowel's intensity, measured over
    ``vowel``) inside ``window``, 40-120 ms long (a stop closure, the utterances' goal); returns its start and
    end (s) and its release burst's level above 3 kHz in the first 15 ms against the silence's (dB)."""
    vowel_db = praat_level_db(wav, *vowel)
    quiet = praat_silences(wav, vowel_db - 30.0, *window)
    assert len(quiet) == 1, (quiet, vowel_db)
    (t0, t1), = quiet
    assert 0.040 <= t1 - t0 <= 0.120, (t0, t1)
    burst = praat_level_db(wav, t1, t1 + 0.015, 3000.0) - praat_level_db(wav, t0 + 0.005, t1 - 0.005, 3000.0)
    return t0, t1, burst


def test_praat_hears_the_requested_f0_contour(spoken):
    """The utterance asks for F0 falling linearly from 125 Hz at 0 s to 100 Hz at 0.75 s (then held): Praat's
    pitch in the middle of each voiced vowel is the requested F0 within 2 %."""
    u = yaml.safe_load((spoken / "lab.yaml").read_text())
    (t0, f0), (t1, f1) = u["f0_hz"]
    times = np.array([0.1, 0.375, 0.675, 0.875])  # /a/, /a/, /a/, /i/: mid-segment, away from the consonants
    asked = np.interp(times, [t0, t1], [f0, f1])
    heard = praat_f0(spoken / "lab.wav", times)
    assert np.all(np.abs(heard / asked - 1) <= 0.02), (heard, asked)


def test_a_closure_is_silent_and_its_release_makes_a_burst(spoken):
    """/apa/'s lips close at 200 ms (a 15-ms ramp) and open at 300 ms: Praat hears one silence there, 30 dB or
    more below the vowel, and a burst above 3 kHz at its release 40 dB above the silence."""
    t0, t1, burst = _praat_stop(spoken / "lab.wav", (0.05, 0.15), (0.15, 0.35))
    assert t0 == pytest.approx(0.21, abs=0.015) and burst >= 40.0, (t0, t1, burst)
    rec = speak.read(spoken / "lab.h5")  # the tract is closed there, so it has no formants
    assert np.all(np.isnan(rec.formants_hz[(rec.time_s > t0 + 0.01) & (rec.time_s < t1 - 0.01)]))


def _vcv(tmp_path, mesh_file, name: str, f0_end_s: float, vowel: dict, first_ms: float, consonant: dict,
         last_ms: float):
    """Speak vowel-consonant-vowel (the forces given; the second vowel 40 ms ahead): record, sound, measures."""
    doc = {"name": name, "f0_hz": [[0.0, 125], [f0_end_s, 100]],
           "segments": [dict(vowel, duration_ms=first_ms), dict(consonant, voiced=False),
                        dict(vowel, duration_ms=last_ms, lead_ms=40)]}
    res = _run("speak", _write(tmp_path / f"{name}.yaml", doc), "--mesh", mesh_file, "--out", tmp_path / f"{name}.wav")
    assert res.exit_code == 0, res.output
    rec = speak.read(tmp_path / f"{name}.h5")
    y, rate = read_wav(tmp_path / f"{name}.wav")
    return rec, y, rate, measures(rec, y, rate)


def test_a_velar_stop_closes_on_the_palate_silently_then_bursts(tmp_path, mesh_file):
    """/aka/ as configs/utterances/aka.yaml times it, the forces given: /a/'s as solved (GGp 0.54 N, JO 6 N),
    /k/'s as solved (GGp 2 N + SG 1.89 N, JO 0.5 N) pressed by 1.3; the tongue on the palate closes the tract
    (contact read as closure), the closure is silent (no clicks as it slides) and its release bursts."""
    a = {"forces_n": {"GGp": 0.54, "JO": 6.0}, "label": "a"}
    k = {"forces_n": {"GGp": 2.6, "SG": 2.457, "JO": 0.5}, "duration_ms": 90, "label": "k", "lead_ms": 130}
    rec, y, rate, m = _vcv(tmp_path, mesh_file, "aka", 0.6, a, 250, k, 260)
    t0, _, burst = _praat_stop(tmp_path / "aka.wav", (0.08, 0.2), (0.2, 0.4))
    assert 0.23 <= t0 <= 0.28 and burst >= 40.0, (t0, burst)
    assert rec.attrs["max_beyond_wall_cm"] <= 0.01 and np.nanmax(np.abs(rec.volume_change)) <= 0.003
    assert m["peak_speed_cm_s"]["dorsum"] <= 48.0


A_ALVEOLAR = {"forces_n": {"GGm": 2.2293, "JO": 4.0}, "label": "a"}  # a_alveolar.yaml as solved: jaw less open


def test_a_laminal_stop_seals_the_blade_on_the_ridge_silently(tmp_path, mesh_file):
    """/ata/ as configs/utterances/ata.yaml speaks it: /t/'s transversus and GGp with the jaw raised (JC 1.5 N)
    seal the blade on the alveolar ridge within the segment: one closure of 40-120 ms, >= 30 dB below the
    vowels, behind the incisors (not between them), the tip no faster than EMA's 40 cm/s + 50 %."""
    t = {"forces_n": {"JC": 1.5, "GGp": 6.0, "T": 8.0}, "duration_ms": 90, "label": "t", "lead_ms": 150}
    rec, y, rate, m = _vcv(tmp_path, mesh_file, "ata", 0.63, A_ALVEOLAR, 280, t, 260)
    t0, _, _ = _praat_stop(tmp_path / "ata.wav", (0.08, 0.22), (0.22, 0.42))
    assert 0.27 <= t0 <= 0.34, t0
    closed = rec.area_cm2.min(axis=1) <= 0
    behind = rec.length_cm[closed][:, ::-1].cumsum(axis=1)[:, ::-1]  # each section's distance from the lips' end
    where = behind[np.arange(closed.sum()), np.argmin(rec.area_cm2[closed], axis=1)]
    assert where[0] > 2.0, where  # the lips 1 cm, the incisors' section 0.15 cm: the blade closes on the ridge
    # the closure is the tongue's, not the teeth's: while closed, the lower incisor edge stays >= 0.1 cm from the
    # upper incisor (JC 3 N puts it on the upper one and the tract then closes between them)
    from artic_cli.control.solver import polyline_nearest

    upper = np.array(yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())["vocal_tract"]["upper_incisor_cm"])
    assert min(polyline_nearest(upper, p)[0] for p in rec.control_points["jaw"][closed][:, :2]) >= 0.1
    assert m["peak_speed_cm_s"]["tip"] <= 60.0 and m["peak_speed_cm_s"]["jaw"] <= 18.0
    assert rec.attrs["max_beyond_wall_cm"] <= 0.01 and np.nanmax(np.abs(rec.volume_change)) <= 0.003


def test_an_alveolar_channel_makes_s_frication_20_db_above_the_vowels(tmp_path, mesh_file):
    """/asa/ as configs/utterances/asa.yaml speaks it, /s/'s forces as solved (T-SL 3.88 N, i.e. T and SL 1.94 N
    each, + GGp 4.91 N, JC 1.5 N):
    a channel of about 0.1 cm^2 behind the incisors for the whole /s/, no closure, and the sound above 3 kHz
    during it at least 20 dB above the vowels' (the utterances issue's goal)."""
    fric = {"forces_n": {"JC": 1.5, "T-SL": 3.8839, "GGp": 4.9116}, "duration_ms": 150, "label": "s", "lead_ms": 150}
    rec, y, rate, m = _vcv(tmp_path, mesh_file, "asa", 0.7, A_ALVEOLAR, 280, fric, 270)
    during = (rec.time_s >= 0.28) & (rec.time_s < 0.43)
    assert 0.02 <= rec.area_cm2[during].min() and rec.area_cm2[during].min(axis=1).max() <= 0.3
    wav = tmp_path / "asa.wav"  # Praat: no silence in the /s/, and its band above 3 kHz 20 dB over the vowels'
    assert praat_silences(wav, praat_level_db(wav, 0.08, 0.22) - 30.0, 0.28, 0.43) == []
    s_hf = praat_level_db(wav, 0.28 + 0.0375, 0.43 - 0.0375, 3000.0)  # the middle half of the /s/
    vowels_hf = np.mean([praat_level_db(wav, 0.08, 0.22, 3000.0), praat_level_db(wav, 0.5, 0.64, 3000.0)])
    assert s_hf >= vowels_hf + 20, (s_hf, vowels_hf)


def test_a_narrow_channel_makes_frication_that_the_noise_switch_removes(spoken, mesh_file, tmp_path):
    """The lip channel of 0.08 cm^2 (450-600 ms): Praat hears the band above 3 kHz 20 dB louder than the same
    utterance without the noise sources (the frication at the channel and the aspiration at the open glottis),
    and louder than the open vowel's there."""
    fric = praat_level_db(spoken / "lab.wav", 0.49, 0.58, 3000.0)
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d["speech"] = {"noise": {"enabled": False}}
    d.setdefault("acoustics", {})["sources"] = {"aspiration": False}
    cfg = _write(tmp_path / "quiet.yaml", d)
    res = _run("speak", spoken / "lab.yaml", "--mesh", mesh_file, "--config", cfg, "--out", tmp_path / "quiet.wav")
    assert res.exit_code == 0, res.output
    # both files are normalised to the same peak (the vowels): the noise is what the switch removed
    assert fric > praat_level_db(tmp_path / "quiet.wav", 0.49, 0.58, 3000.0) + 20
    assert fric > praat_level_db(spoken / "lab.wav", 0.05, 0.15, 3000.0)


def test_activation_dynamics_lag_the_course_by_their_time_constants():
    from artic_cli.speech.course import activated

    step = course([0.0, 0.2], np.array([[2.0], [0.0]]), 0.0)  # a force step on at 0 and off at 200 ms
    g = activated(step, 0.4, 0.015, 0.04)
    assert float(g(0.015)[0]) == pytest.approx(2.0 * (1 - np.exp(-1)), rel=0.02)  # rises with 15 ms
    assert float(g(0.24)[0]) == pytest.approx(float(g(0.2)[0]) * np.exp(-1), rel=0.02)  # falls with 40 ms
    t = np.linspace(0.0, 0.4, 401)
    vals = np.array([float(g(x)[0]) for x in t])
    assert vals.min() >= -1e-12 and vals.max() <= 2.0 + 1e-12  # never beyond the commands
    same = activated(step, 0.4, 0.0, 0.0)
    assert all(float(same(x)[0]) == pytest.approx(float(step(x)[0])) for x in (0.05, 0.19, 0.21, 0.3))


def test_a_pulse_step_course_opens_each_segment_with_a_clipped_pulse():
    from artic_cli.speech.course import pulse_step

    starts, sets = pulse_step([0.0, 0.2], [0.2, 0.05], np.array([[4.0, 0.0], [1.0, 3.0]]), 0.04, 1.0, 6.0)
    assert starts.tolist() == pytest.approx([0.0, 0.04, 0.2, 0.225])  # the second pulse: half its 50-ms segment
    assert sets.tolist() == [[6.0, 0.0], [4.0, 0.0], [0.0, 6.0], [1.0, 3.0]]  # 4 + 4 capped at 6; 1 - 3 at 0


def test_each_segment_may_open_with_its_own_pulse_gain():
    from artic_cli.speech.course import pulse_step

    v = np.array([[4.0, 0.0], [1.0, 3.0], [1.0, 1.0]])
    _, sets = pulse_step([0.0, 0.2, 0.4], [0.2, 0.2, 0.2], v, 0.04, np.array([1.0, 0.5, 0.0]), 9.0)
    assert sets[2].tolist() == [0.0, 4.5] and sets[3].tolist() == [1.0, 3.0]  # 1 + 0.5 (1 - 4) clipped; 3 + 1.5
    assert sets[4].tolist() == sets[5].tolist() == [1.0, 1.0]  # a gain of 0: no pulse, the step alone
    _, one = pulse_step([0.0, 0.2, 0.4], [0.2, 0.2, 0.2], v, 0.04, 0.5, 9.0)
    assert one[2].tolist() == sets[2].tolist()  # one gain for all is the same as each its own


def test_a_jaw_pulse_below_zero_drives_the_closers():
    from artic_cli.speech.course import pulse_step

    jo, jc = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.5, 0.5])  # unit shares: an opener, two closers
    starts, sets = pulse_step([0.0, 0.2], [0.2, 0.2], np.array([[4.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), 0.04, 1.5, 6.0,
                              [(jo, jc)])
    assert sets[0].tolist() == [6.0, 0.0, 0.0]  # 4 + 1.5 x 4, capped
    assert sets[2].tolist() == [0.0, 3.0, 3.0]  # 0 - 1.5 x 4 = -6 N of opener: 6 N of closers, by their shares
    assert sets[3].tolist() == [0.0, 0.0, 0.0]
    _, plain = pulse_step([0.0, 0.2], [0.2, 0.2], np.array([[4.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), 0.04, 1.5, 6.0)
    assert plain[2].tolist() == [0.0, 0.0, 0.0]  # without the pair the pulse is clipped at zero


def test_an_unknown_antagonist_is_one_line_naming_the_key_and_writes_nothing(tmp_path, mesh_file):
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d["speech"]["pulse_antagonists"] = [["JO", "XX"]]
    cfg = _write(tmp_path / "cfg.yaml", d)
    u = _write(tmp_path / "u.yaml", {"force_course": "pulse_step", "segments": [A]})
    res = _run("speak", u, "--mesh", mesh_file, "--config", cfg, "--out", tmp_path / "out" / "u.wav")
    assert res.exit_code == 2 and "speech.pulse_antagonists[0]" in res.output and "'XX'" in res.output, res.output
    assert len([ln for ln in res.output.splitlines() if ln.strip()]) == 1
    assert not (tmp_path / "out").exists()


# a jaw opening then a GGp push, forces held (static), for the lead and preparation tests
OPEN_THEN_PUSH = {"force_course": "static", "f0_hz": [[0.0, 120]],
                  "segments": [{"forces_n": {"JO": 2.5}, "duration_ms": 150, "label": "a"},
                               {"forces_n": {"GGp": 2.0}, "duration_ms": 150, "label": "i"}]}


def _spoken_with(tmp_path, mesh_file, doc: dict, key: str, values) -> dict:
    """{value: record} of ``doc`` spoken once for each value of its ``key``."""
    recs = {}
    for value in values:
        u = _write(tmp_path / f"{key}{value}.yaml", dict(doc, name=f"{key}{value}", **{key: value}))
        res = _run("speak", u, "--mesh", mesh_file, "--out", tmp_path / f"{key}{value}.wav")
        assert res.exit_code == 0, res.output
        recs[value] = speak.read(tmp_path / f"{key}{value}.h5")
    return recs


def _commanded_at(rec, t_s: float) -> np.ndarray:
    return rec.commanded_n[np.searchsorted(rec.time_s, t_s)]


def _jaw_height(rec) -> np.ndarray:
    return rec.control_points["jaw"][:, 1]


def test_a_lead_switches_each_segment_s_forces_on_before_its_sound(tmp_path, mesh_file):
    recs = _spoken_with(tmp_path, mesh_file, dict(OPEN_THEN_PUSH, prepare_ms=0), "lead_ms", (0, 100))
    now, ahead = recs[0], recs[100]
    assert ahead.lead_ms == 100.0 and now.lead_ms == 0.0
    import h5py

    with h5py.File(tmp_path / "lead_ms100.h5") as f:
        names = [str(n) for n in f["muscles"].attrs["names"]]
    ggp = [k for k, n in enumerate(names) if n.startswith("GGp")]
    t, t0 = ahead.time_s, now.time_s
    assert _commanded_at(ahead, 0.14)[ggp].sum() > 1.9  # GGp's segment starts at 0.15 s, its forces at 0.05 s
    assert _commanded_at(now, 0.14)[ggp].sum() == 0.0
    assert _jaw_height(ahead)[0] < _jaw_height(now)[0] - 0.1  # the jaw already opening when the sound starts
    assert len(t) == len(t0) and t[0] == pytest.approx(0.0)


def test_preparing_switches_only_the_first_segment_s_forces_on_earlier(tmp_path, mesh_file):
    recs = _spoken_with(tmp_path, mesh_file, dict(OPEN_THEN_PUSH, lead_ms=50), "prepare_ms", (0, 250))
    lead, prepared = recs[0], recs[250]
    assert lead.prepare_ms == 50.0 and prepared.prepare_ms == 250.0  # never less than the lead
    # the jaw 250 ms into its opening when the sound starts
    assert _jaw_height(prepared)[0] < _jaw_height(lead)[0] - 0.1
    # the second segment's forces still switch on 50 ms before its sound (0.10 s), in both (the first's JO
    # differs by its activation's last 0.03 %: 50 ms of rise against 300)
    for t_s in (0.09, 0.11):
        np.testing.assert_allclose(_commanded_at(prepared, t_s), _commanded_at(lead, t_s), atol=1e-3)
    assert not np.allclose(_commanded_at(lead, 0.09), _commanded_at(lead, 0.11))


def test_a_segment_s_own_lead_moves_its_forces_alone_and_press_scales_only_the_tongue(tmp_path, mesh_file, cfg):
    doc = dict(OPEN_THEN_PUSH, lead_ms=0, prepare_ms=0, name="own")
    doc["segments"] = [doc["segments"][0], dict(doc["segments"][1], lead_ms=100)]
    res = _run("speak", _write(tmp_path / "own.yaml", doc), "--mesh", mesh_file, "--out", tmp_path / "own.wav")
    assert res.exit_code == 0, res.output
    rec = speak.read(tmp_path / "own.h5")
    import h5py

    with h5py.File(tmp_path / "own.h5") as f:
        names = [str(n) for n in f["muscles"].attrs["names"]]
        np.testing.assert_allclose(f["segments/lead"][()], [0.0, 100.0])
    ggp = [k for k, n in enumerate(names) if n.startswith("GGp")]
    assert _commanded_at(rec, 0.04)[ggp].sum() == 0.0  # the push's forces switch on at 0.05 s ...
    assert _commanded_at(rec, 0.14)[ggp].sum() > 1.9  # ... not at its sound (0.15 s)
    # press: a solved target's tongue forces times the factor, the jaw's kept (the plan given, nothing solved)
    from artic_cli.stages import mesh as mesh_stage
    from artic_cli.speech.utterance import parse_utterance

    target = {"name": "k", "jaw": {"forces_n": {"JO": 1.0}}, "crucial": {"point": "dorsum", "at_cm": [-4.4, 1.6]}}
    u = parse_utterance({"segments": [{"target": target, "duration_ms": 60, "press": 1.5}], "force_course": "static",
                         "lead_ms": 0, "prepare_ms": 0, "ramp_ms": 0})
    plan = Plan(labels=["k"], starts_s=np.array([0.0]), durations_s=np.array([0.06]),
                      forces_n=[{"JO": 1.0, "SG": 2.0}], lips=[(3.0, 1.0)], ports=[0.0], voiced=np.array([False]),
                      glottis_cm2=np.array([0.3]),
                      notes=["solved"], solutions=[""])
    m = mesh_stage.read(mesh_file, cfg)
    said = speak.compute(u, plan, cfg, m.mesh, m.wall)
    held = said.muscle_force_n[-1]
    sg = said.muscle_names.index("SG")
    jaw = [said.muscle_names.index(n) for n in ("anterior_digastric", "lateral_pterygoid_lower")]
    unpressed = speak.compute(u.model_copy(update={"segments": [u.segments[0].model_copy(update={"press": 1.0})]}),
                              plan, cfg, m.mesh, m.wall).muscle_force_n[-1]
    assert held[sg] == pytest.approx(1.5 * unpressed[sg], rel=1e-9) and unpressed[sg] > 1.9  # SG 2 N pressed
    np.testing.assert_allclose(held[jaw], unpressed[jaw], rtol=1e-9)  # JO's muscles as they were
    assert min(held[jaw]) > 0.1


def test_an_unreachable_target_exits_3_naming_its_segment_and_writes_nothing(tmp_path, mesh_file):
    from artic_cli.stages.epmap import build_ep_maps

    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d["epmap"] = dict(jaw_positions={"rest": {}}, typical_jaw="rest", net_jaw_positions=["rest"], muscles=["SL", "GGa"],
                      levels_n=[0.0, 2.0], pair_levels_n=[2.0], pairs_tip=[["SL", "GGa"]], pairs_dorsum=[], groups=[])
    cfg = _write(tmp_path / "cfg.yaml", d)
    build_ep_maps(mesh_file, cfg, tmp_path / "maps.h5", jobs=1, cache=tmp_path / "cache")
    far = {"name": "far", "jaw": {"forces_n": {}},
           "crucial": {"point": "tip", "at_cm": [2.0, 3.0], "tolerance_cm": 0.05}}
    farther = dict(far, name="farther", crucial=dict(far["crucial"], at_cm=[2.5, 3.0]))
    segments = [dict(A, duration_ms=60), {"target": far, "duration_ms": 60}, {"target": farther, "duration_ms": 20}]
    u = _write(tmp_path / "u.yaml", {"name": "u", "segments": segments})
    args = ("speak", u, "--mesh", mesh_file, "--maps", tmp_path / "maps.h5", "--config", cfg,
            "--out", tmp_path / "out" / "u.wav", "--solutions", tmp_path / "sol")
    res = _run(*args, "--jobs", "2")  # the two targets in two processes: the first one's failure is the answer
    assert res.exit_code == 3 and "segment 1" in res.output and "'far'" in res.output, res.output
    assert "--accept-nearest" in res.output and not (tmp_path / "out").exists()
    res = _run(*args, "--accept-nearest", "--animate", tmp_path / "u.gif")
    assert res.exit_code == 0, res.output
    from PIL import Image

    assert Image.open(tmp_path / "u.gif").n_frames == 29  # every 5-ms frame of 140 ms, and the start
    # a place target at a jaw position the maps hold no nets for needs the dynamic map (read only then)
    opened = dict(far, name="opened", jaw={"forces_n": {"JO": 1.0}})
    v = _write(tmp_path / "v.yaml", {"name": "v", "segments": [{"target": opened, "duration_ms": 60}]})
    res = _run("speak", v, "--mesh", mesh_file, "--maps", tmp_path / "maps.h5", "--config", cfg, "--out",
               tmp_path / "v" / "v.wav", "--solutions", tmp_path / "sol", "--dynamic", tmp_path / "none.h5")
    assert res.exit_code == 2 and "need the dynamic map" in res.output and "artic dynamic-map" in res.output
    assert len(res.output.strip().splitlines()) == 1 and not (tmp_path / "v").exists()
    rec = speak.read(tmp_path / "out" / "u.h5")
    assert rec.how == ["forces given", "unreachable: nearest answer", "unreachable: nearest answer"]
    # the nearest answer aims at the nearest reachable point the unreachable answer names, with the tolerance kept
    answer = yaml.safe_load(next((tmp_path / "sol").glob("far-[0-9a-f]*.yaml")).read_text())
    nearest = yaml.safe_load(next((tmp_path / "sol").glob("far-nearest-*.yaml")).read_text())
    assert nearest["crucial"]["at_cm"] == pytest.approx(answer["nearest_point_cm"])
    assert nearest["crucial"]["tolerance_cm"] == 0.05 and nearest["chosen"]["crucial_error_cm"] <= 0.05


def test_praat_finds_our_formant_tracks_in_the_spoken_sound(spoken):
    """The time-varying line carries the tracts' formants: Praat (Burg) on the WAV, mid-segment, against our
    transfer function's tracks, for the open /a/ and the front vowel after it (F1 within 10 %, F2 within 7 %);
    and Praat hears the front vowel fronter and closer than the open one: F2 higher and F1 lower, each by more
    than 15 %, several times the 3-5 % a listener can just tell apart (Flanagan 1955)."""
    parselmouth = need("parselmouth")
    rec = speak.read(spoken / "lab.h5")
    fm = parselmouth.Sound(str(spoken / "lab.wav")).to_formant_burg(0.01, 5, 5000, 0.025, 50)
    heard = {}
    for lab, (t0, t1) in (("a", (0.06, 0.18)), ("i", (0.85, 0.97))):
        times = np.linspace(t0, t1, 9)
        ours = [float(np.nanmedian(np.interp(times, rec.time_s, rec.formants_hz[:, k]))) for k in (0, 1)]
        found = [np.nanmedian([fm.get_value_at_time(j, x) for x in times]) for j in range(1, 6)]
        heard[lab] = []
        for k, tol in ((0, 0.10), (1, 0.07)):  # Burg may insert spurious peaks: take the one nearest ours
            nearest = min(found, key=lambda v: abs(v - ours[k]))
            assert abs(nearest / ours[k] - 1) < tol, (lab, k + 1, nearest, ours[k], found)
            heard[lab].append(nearest)
    assert heard["i"][1] >= 1.15 * heard["a"][1] and heard["i"][0] <= heard["a"][0] / 1.15, heard


def test_a_spoken_utterance_gets_a_page_to_look_at_and_listen_to(spoken, mesh_file, tmp_path):
    """`artic speak ... --html PAGE.html`: a page that parses strictly, whose pictures (spectrogram with tiers
    and movement, the animation) load and whose sound decodes in headless Chromium, opened from the file
    system."""
    from conftest import browser_check

    html5lib = need("html5lib")
    page = spoken / "lab_page.html"
    res = _run("speak", spoken / "lab.yaml", "--mesh", mesh_file, "--out", spoken / "lab.wav", "--html", page)
    assert res.exit_code == 0 and page.is_file(), res.output
    text = page.read_text()
    html5lib.HTMLParser(strict=True).parse(text)
    got = browser_check(page, tmp_path, tmp_path / "page.png")
    assert [src for src, _ in got["images"]] == ["lab_page.png", "lab_page.gif"] and all(w > 0 for _, w in got["images"])
    assert got["audio"] == [["lab.wav", pytest.approx(1.0, abs=0.01), 0]]
    assert text.count("<tr>") == 7  # a header and the six segments


@pytest.mark.parametrize("args, says", [(["--text", "ax"], "'x' at position 2 is not romaji"),
                                        (["--text", "   "], "give some romaji"), ([], "give an utterance file or --text"),
                                        (["--text", "ka" * 201], "201 morae is more than the 200"),
                                        (["--text", "'aka"], "accent mark on no mora"),
                                        (["--text", "aka", "--rate", "3"], "--rate 3: give a factor from 0.5 to 2"),
                                        (["--text", "aka", "--f0-range", "140,90"], "50 <= LOW < HIGH <= 500"),
                                        (["--text", "aka", "--f0-range", "x"], "give LOW,HIGH in Hz"),
                                        (["--rate", "1.5"], "give an utterance file or --text")])
def test_bad_text_is_one_line_and_exit_2_with_nothing_written(tmp_path, mesh_file, args, says):
    res = _run("speak", *args, "--mesh", mesh_file, "--out", tmp_path / "out" / "x.wav", "--maps", tmp_path / "none.h5")
    assert res.exit_code == 2 and says in res.output and "Traceback" not in res.output, res.output
    assert not (tmp_path / "out").exists()
