"""The vocal-tract stage on the default speaker: the rest tract, closures made by loads, controls, bad input."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from artic_cli.acoustics.tube import read_tube_csv
from artic_cli.control.equilibrium import parse_ep
from artic_cli.errors import ArticError
from artic_cli.stages import vocal_tract as vts
from artic_cli.stages.simulate import simulate
from artic_cli.tract.areas import tracts_of
from artic_cli.tract.controls import controls_for
from artic_cli.tract.shapes import shapes_of_simulation

from conftest import ROOT

CONFIG = ROOT / "configs" / "default.yaml"


def _sim(tmp_path, mesh_file, name, loads, tract=()):
    sched = tmp_path / f"{name}.yaml"
    sched.write_text(yaml.safe_dump({"duration_ms": 300, "loads": loads, "tract": list(tract)}))
    out = tmp_path / f"{name}.h5"
    simulate(sched, mesh=mesh_file, config=CONFIG, out=out)
    return out


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("tracts")


@pytest.fixture(scope="module")
def rest(work, mesh_file):
    return vts.vocal_tract(rest=True, mesh=mesh_file, config=CONFIG, out=work / "rest.h5").tracts


@pytest.fixture(scope="module")
def dorsum_sim(work, mesh_file):
    # 6 N up: the dorsum closes on the palate (4 N leaves a slit of 0.005 cm^2 with the GG tendon in the midline)
    return _sim(work, mesh_file, "dorsum", [{"nodes": "dorsum_region", "force_n": [-1.0, 6.0, 0.0], "onset_ms": 0,
                                             "duration_ms": 300}],
                tract=[{"at_ms": 100, "ramp_ms": 80, "lip_area_cm2": 0.5}])


def test_the_rest_tract_is_an_adult_male_s_without_a_constriction(rest):
    assert rest.n_frames == 1
    assert 16.5 <= rest.af.tract_length_cm[0] <= 18.0
    a = rest.af.area_cm2[0]
    assert np.isfinite(a).all() and (a >= 0).all()
    assert a[:rest.grid.n_lines].min() >= 0.15
    assert rest.af.region_names[-1] == "lips" and a[-1] == pytest.approx(3.0)  # the config's lip tube


def test_the_dorsum_pressed_on_the_palate_closes_the_palatal_velar_region(work, mesh_file, dorsum_sim):
    t = vts.vocal_tract(sim=dorsum_sim, mesh=mesh_file, config=CONFIG, out=work / "dorsum_vt.h5").tracts
    from artic_cli.stages.simulate import read

    assert t.n_frames == len(read(dorsum_sim).time_s)
    area, pos, reg = t.af.constriction()
    assert area[-1] <= 0.05
    assert t.af.region_names[int(reg[-1])] in ("velum", "hard palate")
    assert np.isfinite(t.af.area_cm2).all() and (t.af.area_cm2 >= 0).all()
    lips = t.controls["lip_area_cm2"]  # the schedule's tract entry: 3.0 -> 0.5 cm^2 from 100 to 180 ms
    assert lips[0] == pytest.approx(3.0) and lips[-1] == pytest.approx(0.5)
    assert t.af.area_cm2[-1, -1] == pytest.approx(0.5)


def test_the_blade_pressed_on_the_alveolar_ridge_closes_the_front_fifth(work, mesh_file):
    sim = _sim(work, mesh_file, "blade", [{"nodes": "blade", "force_n": [0.5, 3.0, 0.0], "onset_ms": 0,
                                           "duration_ms": 300}])
    t = vts.vocal_tract(sim=sim, mesh=mesh_file, config=CONFIG, out=work / "blade_vt.h5").tracts
    area, length = t.af.area_cm2[-1], t.af.length_cm[-1]
    centre = np.cumsum(length) - 0.5 * length
    front = centre >= 0.8 * t.af.tract_length_cm[-1]
    assert area[front].min() <= 0.05  # the blade closes the front fifth (the body, lifted too, may touch behind)
    assert area[centre < 0.5 * t.af.tract_length_cm[-1]].min() > 0.05  # the pharynx stays open


def test_opening_the_velum_changes_the_port_and_nothing_else(work, mesh_file, dorsum_sim):
    shut = vts.vocal_tract(sim=dorsum_sim, mesh=mesh_file, config=CONFIG, out=work / "shut.h5").tracts
    open_ = vts.vocal_tract(sim=dorsum_sim, mesh=mesh_file, config=CONFIG, out=work / "open.h5", velum_port=0.6).tracts
    assert (shut.controls["velum_port_cm2"] == 0.0).all() and (open_.controls["velum_port_cm2"] == 0.6).all()
    np.testing.assert_array_equal(shut.af.area_cm2, open_.af.area_cm2)
    np.testing.assert_array_equal(shut.af.length_cm, open_.af.length_cm)


def test_the_file_reads_back_and_one_frame_is_a_tube(work, rest):
    back = vts.read(work / "rest.h5")
    np.testing.assert_array_equal(back.af.area_cm2, rest.af.area_cm2)
    path = vts.write_csv(work / "rest.csv", back, vts.pick_frame(back, None))
    assert path.read_text().splitlines()[0] == "length_cm,area_cm2"
    tube = read_tube_csv(path)
    np.testing.assert_allclose(tube.length_cm, rest.af.length_cm[0], rtol=1e-5)
    np.testing.assert_allclose(tube.area_cm2, rest.af.area_cm2[0], rtol=1e-5)


def test_a_second_run_is_up_to_date(work, mesh_file, rest):
    again = vts.vocal_tract(rest=True, mesh=mesh_file, config=CONFIG, out=work / "rest.h5")
    assert again.up_to_date


def test_bad_input_is_one_error_and_no_file(work, mesh_file, other_mesh_file, dorsum_sim, rest):
    with pytest.raises(ArticError, match="another mesh"):
        vts.vocal_tract(sim=dorsum_sim, mesh=other_mesh_file, config=ROOT / "configs" / "speaker_small.yaml",
                        out=work / "bad.h5")
    with pytest.raises(ArticError, match="out of range"):
        vts.pick_frame(rest, 5)
    with pytest.raises(ArticError, match="--lip-area"):
        vts.vocal_tract(rest=True, mesh=mesh_file, config=CONFIG, out=work / "bad.h5", lip_area=-1.0)
    with pytest.raises(ArticError, match="--velum-port"):
        vts.vocal_tract(rest=True, mesh=mesh_file, config=CONFIG, out=work / "bad.h5", velum_port=float("nan"))
    with pytest.raises(ArticError, match="JAW:MUSCLE=N"):
        parse_ep("SG=2")
    with pytest.raises(ArticError, match="exactly one"):
        vts.vocal_tract(mesh=mesh_file, config=CONFIG, out=work / "bad.h5")
    assert not (work / "bad.h5").exists()


def test_the_command_line_says_one_line_and_exits_2(work, mesh_file, dorsum_sim):
    from typer.testing import CliRunner

    from artic_cli.cli.main import app

    res = CliRunner().invoke(app, ["vocal-tract", "--sim", str(dorsum_sim), "--mesh", str(mesh_file), "--config",
                                   str(CONFIG), "--out", str(work / "cli.h5"), "--csv", str(work / "cli.csv"),
                                   "--frame", "999"])
    assert res.exit_code == 2
    assert len(res.output.strip().splitlines()) == 1 and "--frame 999 is out of range" in res.output
    assert "Traceback" not in res.output
    assert not (work / "cli.h5").exists() and not (work / "cli.csv").exists()
    ok = CliRunner().invoke(app, ["vocal-tract", "--sim", str(dorsum_sim), "--mesh", str(mesh_file), "--config",
                                  str(CONFIG), "--out", str(work / "cli.h5"), "--csv", str(work / "cli.csv")])
    assert ok.exit_code == 0, ok.output
    assert (work / "cli.csv").is_file()


def test_a_simulation_of_another_config_or_an_untraceable_shape_is_refused(work, mesh_file, dorsum_sim, cfg):
    other = work / "stiffer_contact.yaml"
    data = yaml.safe_load(CONFIG.read_text())
    data["contact"] = {"stiffness_n_per_cm": 2000.0}
    other.write_text(yaml.safe_dump(data))
    with pytest.raises(ArticError, match="another config"):
        vts.vocal_tract(sim=dorsum_sim, mesh=mesh_file, config=other, out=work / "bad2.h5")
    from artic_cli.stages.simulate import read
    from artic_cli.stages.mesh import read as read_mesh

    shapes = shapes_of_simulation(read(dorsum_sim), read_mesh(mesh_file).mesh)
    shapes.tongue_cm[-1] -= np.array([0.0, 6.0])  # the last frame's tongue dropped out of the grid's reach
    with pytest.raises(ArticError, match="midline cannot be traced"):
        tracts_of(cfg.vocal_tract, cfg.speaker.wall, shapes, controls_for(cfg.vocal_tract, shapes.time_s))
    assert not (work / "bad2.h5").exists()


def test_a_schedule_s_tract_entries_are_validated():
    from artic_cli.schedule import parse_schedule

    for bad in ({"at_ms": 0, "lip_area_cm2": -0.5}, {"at_ms": 0, "velum_port_cm2": float("nan")},
                {"at_ms": -5, "lip_length_cm": 1.0}, {"at_ms": 0, "lip_size": 1.0}):
        with pytest.raises(ArticError, match="tract"):
            parse_schedule({"tract": [bad]}, "s.yaml")


def test_the_acoustics_of_tracts_match_their_tubes_and_follow_the_velum(work, rest):
    from artic_cli.stages.acoustics import read as read_acoustics
    from artic_cli.stages.acoustics import tract_acoustics, tube_acoustics

    path = work / "rest.h5"
    frames = tract_acoustics(path, CONFIG, out=work / "rest_ac.h5")
    tube = tube_acoustics(vts.write_csv(work / "rest_tube.csv", rest, 0), CONFIG)
    f1, f2, f3 = frames.formants_hz[0, :3]
    # the speaker is drawn at [e]: the rest tract sounds within 15 % of a male Japanese /e/ (500 / 1947 Hz)
    assert abs(f1 / 500.0 - 1) <= 0.15 and abs(f2 / 1947.0 - 1) <= 0.15, (f1, f2)
    # the file round trip: the frame written as a tube CSV and read back has the same formants
    np.testing.assert_allclose(frames.formants_hz[0], tube.formants_hz[0], rtol=1e-6)
    back = read_acoustics(work / "rest_ac.h5")
    assert back.formants_hz.shape == (1, 5) and back.time_s is not None
    nasal = tract_acoustics(path, CONFIG, velum_area_cm2=0.5)
    assert abs(nasal.formants_hz[0, 0] - f1) > 10.0  # an open port couples the nasal tract
    with pytest.raises(ArticError, match="out of range"):
        tract_acoustics(path, CONFIG, frame=3)


def test_the_sound_of_a_closing_tract_falls_silent(work, mesh_file, dorsum_sim):
    from scipy.io import wavfile

    from artic_cli.stages.synthesize import synthesize_tracts

    tracts = work / "dorsum_vt.h5"
    vts.vocal_tract(sim=dorsum_sim, mesh=mesh_file, config=CONFIG, out=tracts)
    a = synthesize_tracts(tracts, work / "dorsum.wav", 115.0, config=CONFIG)
    fs, y = wavfile.read(work / "dorsum.wav")
    assert fs == 44100 and len(y) == pytest.approx(0.3 * fs, abs=2)
    assert np.isfinite(a.samples).all()
    y = y.astype(float)
    rms = lambda t0, t1: np.sqrt(np.mean(y[int(t0 * fs):int(t1 * fs)] ** 2))  # noqa: E731
    assert rms(0.15, 0.29) < 0.3 * rms(0.01, 0.04)  # closed from about 60 ms on: the sound falls by > 10 dB
    noisy = synthesize_tracts(tracts, work / "noisy.wav", 115.0, config=CONFIG, aspiration=0.5)
    assert not np.allclose(noisy.samples, a.samples)
    with pytest.raises(ArticError, match="--aspiration"):
        synthesize_tracts(tracts, work / "bad.wav", 115.0, config=CONFIG, aspiration=-1.0)
    assert not (work / "bad.wav").exists()


def test_the_root_pulled_forward_widens_the_low_pharynx_through_the_epiglottis(work, mesh_file):
    sim = _sim(work, mesh_file, "root", [{"nodes": "root", "force_n": [1.0, 0.0, 0.0], "onset_ms": 0,
                                          "duration_ms": 300}])
    follows = vts.vocal_tract(sim=sim, mesh=mesh_file, config=CONFIG, out=work / "root_vt.h5").tracts
    fixed_cfg = work / "larynx_fixed.yaml"
    raw = yaml.safe_load(CONFIG.read_text())
    raw["vocal_tract"]["larynx_follows_root"] = 0.0
    fixed_cfg.write_text(yaml.safe_dump(raw))
    fixed = vts.vocal_tract(sim=sim, mesh=mesh_file, config=fixed_cfg, out=work / "root_fixed.h5").tracts
    low = np.array(follows.af.region_names)[follows.grid.region] == "low pharynx"
    n = follows.grid.n_lines
    grown = follows.af.area_cm2[:, :n][:, low] / fixed.af.area_cm2[:, :n][:, low]
    assert np.median(grown[-1]) >= 1.3
    assert np.median(grown[0]) <= 1.1  # settled at rest: the root where it was drawn, within 0.1 cm
