"""Acoustic targets (issue 16): formants in, muscle forces out, checked and refined by simulation."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from artic_cli.control.acoustic_solver import solve_acoustic_on, within
from artic_cli.control.epmap import JawMaps, Net
from artic_cli.control.solver import parse_target
from artic_cli.errors import ArticError, UnreachableTarget
from artic_cli.stages.solve import add_formants, load_context, simulator, solve_target

from conftest import ROOT, praat_formants_near, need


def _acoustic(formants, tol=5.0, **extra):
    return parse_target({"name": "v", "jaw": {"forces_n": {}}, "acoustic": {"formants_hz": list(formants),
                                                                           "tolerance_pct": tol}, **extra})


@pytest.mark.parametrize("data,needle", [
    ({"acoustic": {"formants_hz": [500, 1500]}, "crucial": {"point": "tip", "at_cm": [0, 0]}}, "one of them"),
    ({}, "give either 'crucial'"),
    ({"acoustic": {"formants_hz": [1500, 500]}}, "formants must increase"),
    ({"acoustic": {"formants_hz": [500, float("nan")]}}, "acoustic.formants_hz"),
    ({"acoustic": {"formants_hz": [500]}}, "acoustic.formants_hz"),
    ({"acoustic": {"formants_hz": [500, 1500], "tolerance_pct": 0}}, "acoustic.tolerance_pct"),
    ({"acoustic": {"formants_hz": [500, 1500]}, "lips": "pursed"}, "lips"),
    ({"acoustic": {"formants_hz": [500, 1500]}, "lips": {"area_cm2": -1, "length_cm": 1}}, "lips"),
    ({"acoustic": {"formants_hz": [500, 1500]}, "jaw": {"opening_cm": -0.3}}, "mapped jaw position"),
    ({"crucial": {"point": "tip", "at_cm": [0, 0]}, "lips": "rounded"}, "belong to acoustic targets"),
    ({"crucial": {"point": "tip", "at_cm": [0, 0]}, "tongue_highest": {"tongue": "high-back"}},
     "'tongue_highest' belongs to acoustic targets"),
    ({"acoustic": {"formants_hz": [500, 1500]}, "tongue_highest": {"tongue": "up-back"}}, "tongue_highest.tongue"),
    ({"acoustic": {"formants_hz": [500, 1500]}, "tongue_highest": {"tongue": "high-back", "margin_cm": -1}},
     "tongue_highest.margin_cm"),
])
def test_bad_acoustic_targets_are_refused_naming_the_key(data, needle):
    data = {"name": "v", "jaw": {"forces_n": {}}, **data}
    with pytest.raises(ArticError, match=None) as err:
        parse_target(data)
    assert needle in str(err.value), str(err.value)


def _linear_net():
    """A pair net whose formants vary linearly with the two forces (a known inverse)."""
    lv = np.array([0.0, 1.0, 2.0, 4.0])
    a, b = np.meshgrid(lv, lv, indexing="ij")
    f = np.stack([400 + 20 * a + 5 * b, 1500 + 10 * a + 60 * b, 2500 + 0 * a, 3500 + 0 * a], axis=-1)
    x = np.zeros((4, 4, 3, 3))
    x[..., 0, 0], x[..., 0, 1] = -0.7 + 0.05 * a, -0.6 + 0.05 * b
    x[..., 1, 0], x[..., 1, 1] = -4.3, 0.8
    net = Net(muscles=("A", "B"), levels=(lv, lv), x=x, converged=np.ones((4, 4), bool), drift_cm=np.zeros((4, 4)))
    jm = JawMaps(forces={}, rest=x[0, 0], single={}, pair={"A+B": net})
    return jm, {"pair/A+B": f}


def _two_vectors():
    """Two single vectors that both pass 500 / 1500 Hz: A at 1 N (cheaper), B at 2 N, whose tongue top rises and
    moves back with its force (A's stays at the rest's)."""
    lv = np.array([0.0, 1.0, 2.0, 4.0])
    x = np.zeros((4, 3, 3))
    nets = {m: Net(muscles=(m,), levels=(lv,), x=x, converged=np.ones(4, bool), drift_cm=np.zeros(4)) for m in "AB"}
    fa = np.stack([400 + 100 * lv, 1400 + 100 * lv, 2500 + 0 * lv, 3500 + 0 * lv], axis=-1)
    fb = np.stack([400 + 50 * lv, 1400 + 50 * lv, 2500 + 0 * lv, 3500 + 0 * lv], axis=-1)
    rest = np.array([-3.5, 1.3])
    tops = {"single/A": np.tile(rest, (4, 1)), "single/B": rest + np.outer(lv, [-0.15, 0.15])}
    return JawMaps(forces={}, rest=x[0], single=nets), {"single/A": fa, "single/B": fb}, (tops, rest)


def test_a_tongue_class_chooses_the_force_set_whose_tongue_is_highest_where_it_names():
    jm, formants, tops = _two_vectors()
    plain = solve_acoustic_on(jm, _acoustic((500, 1500)), formants, tops=tops)
    assert plain[0].forces == pytest.approx({"A": 1.0})  # the cheapest, no class asked
    t = _acoustic((500, 1500), tongue_highest={"tongue": "high-back", "margin_cm": 0.25})
    best = solve_acoustic_on(jm, t, formants, tops=tops)[0]
    assert best.forces == pytest.approx({"B": 2.0})
    assert best.detail["tongue_top_cm"] == pytest.approx([-3.8, 1.6])
    low = _acoustic((500, 1500), tongue_highest={"tongue": "low-front", "margin_cm": 0.25})
    assert solve_acoustic_on(jm, low, formants, tops=tops)[0].forces == pytest.approx({"A": 1.0})  # B is worse


def test_a_tongue_class_measures_its_shortfall_from_the_rest_tongue():
    from artic_cli.control.solver import TongueHighest

    rest = np.array([-3.5, 1.3])
    hb = TongueHighest(tongue="high-back", margin_cm=0.2)
    assert hb.shortfall_cm(np.array([-3.5, 1.3]), rest) == pytest.approx([0.2, 0.2])
    assert hb.shortfall_cm(np.array([-3.8, 1.6]), rest) == pytest.approx([0.0, 0.0])
    assert TongueHighest(tongue="low-front", margin_cm=0.2).shortfall_cm(np.array([-3.4, 1.2]), rest) \
        == pytest.approx([0.1, 0.1])
    assert TongueHighest(tongue="mid-central").shortfall_cm(np.array([-5.0, 3.0]), rest) == pytest.approx([0, 0])


def test_formants_inside_a_net_give_the_forces_that_make_them():
    jm, formants = _linear_net()
    fa, fb = 1.7, 2.3
    goal = (400 + 20 * fa + 5 * fb, 1500 + 10 * fa + 60 * fb)
    cands = solve_acoustic_on(jm, _acoustic(goal, tol=1.0), formants)
    best = cands[0]
    assert best.forces == pytest.approx({"A": fa, "B": fb}, abs=0.02)
    assert within(_acoustic(goal, tol=0.2), best.detail["formants_hz"])
    with pytest.raises(UnreachableTarget, match="nearest mapped formants are F1 .* Hz"):
        solve_acoustic_on(jm, _acoustic((300, 2600), tol=5.0), formants)


@pytest.fixture(scope="module")
def found_vowel(small_maps, mesh_file):
    """A vowel simulated off the maps' grid (GGp 2 N + HG 1.5 N, the config's lips, port closed), solved from
    its F1 / F2 (2 %) and refined: (the answer, its file, the simulated vowel, the context)."""
    tmp, cfg = small_maps
    voicer = simulator(mesh_file, cfg, voiced=True)
    made = voicer.voice({}, {"GGp": 2.0, "HG": 1.5}, (3.0, 1.0), 0.0)
    target = _acoustic(made["formants_hz"][:2], tol=2.0, name="found")
    ctx = add_formants(load_context(tmp / "maps.h5", None, mesh_file), tmp / "maps.h5", mesh_file, cfg)
    doc, path, _ = solve_target(target, ctx, tmp / "found.yaml", voicer, refine=True, budget=6, config=cfg,
                                mesh_sha256=voicer.mesh_sha256)
    return doc, path, made, ctx


def test_a_simulated_vowel_is_found_again_and_refined_within_its_tolerance(small_maps, mesh_file, found_vowel):
    tmp, cfg = small_maps
    doc, path, made, ctx = found_vowel
    assert doc["refined"]["converged"] and doc["refined"]["within_tolerance"]
    assert all(abs(e) <= 2.0 for e in doc["refined"]["errors_pct"][:2])
    af = doc["refined"]["area_function"]
    assert len(af["length_cm"]) == len(af["area_cm2"]) and 14.0 < sum(af["length_cm"]) < 22.0
    assert doc["lips"] == {"area_cm2": 3.0, "length_cm": 1.0}
    # rounded lips lengthen and narrow the lip tube at the radiating end, where every mode's volume velocity
    # peaks: no formant rises, and while the tract is open every EP's F1-F3 fall, the formant of the cavity in
    # front of the tongue's constriction by 50 Hz or more (F2 with the tongue back, SG and HG; F3 with it
    # fronted, GGp, whose F2 is the back cavity's).  Where SG closes the velar tract (2.5 and 4 N: the dorsum
    # on the palate) the cavities decouple: the front one's resonance is F1 and falls, the back one's stay.
    from artic_cli.config import load_config
    from artic_cli.stages import acoustic_map as am_stage, epmap as epmap_stage, mesh as mesh_stage

    c = load_config(cfg)
    nets = am_stage.compute(c, mesh_stage.read(mesh_file, c).mesh, epmap_stage.read(tmp / "maps.h5"), jaws=["rest"],
                            bandwidths=False).jaws["rest"]
    neutral, rounded = ctx.formants("rest", 3.0, 1.0, 0.0), ctx.formants("rest", 0.6, 1.5, 0.0)
    for vector in ("single/GGp", "single/SG", "single/HG"):
        fall = neutral[vector][:, :3] - rounded[vector][:, :3]
        is_open = nets[vector].min_area_cm2 > 0.05
        assert (fall > -1.0).all(), (vector, fall)  # the back cavity's, behind a closure: within 1 Hz
        assert (fall[is_open] > 0).all(), (vector, fall)
        front = 2 if vector == "single/GGp" else 1
        assert (fall[is_open, front] > 50).all(), (vector, fall)
        assert (fall[~is_open, 0] > 50).all(), (vector, fall)
        assert is_open.sum() >= 2, vector
    assert (~(nets["single/SG"].min_area_cm2 > 0.05)).any()  # SG does close the tract


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_held_out_random_force_sets_round_trip_through_their_formants(small_maps, mesh_file, seed):
    """Forces off the maps' grid -> simulation -> formants -> solve -> forces -> simulation: within 3 %."""
    tmp, cfg = small_maps
    ggp, hg = np.random.default_rng(seed).uniform(0.3, 3.8, size=2)
    voicer = simulator(mesh_file, cfg, voiced=True)
    made = voicer.voice({}, {"GGp": float(ggp), "HG": float(hg)}, (3.0, 1.0), 0.0)
    ctx = add_formants(load_context(tmp / "maps.h5", None, mesh_file), tmp / "maps.h5", mesh_file, cfg)
    target = _acoustic(made["formants_hz"][:2], tol=3.0, name=f"held_out_{seed}")
    doc, _, _ = solve_target(target, ctx, tmp / f"held_out_{seed}.yaml", voicer, refine=True, budget=6, config=cfg,
                             mesh_sha256=voicer.mesh_sha256)
    assert doc["refined"]["within_tolerance"], (ggp, hg, made["formants_hz"][:2], doc["refined"])
    assert all(abs(e) <= 3.0 for e in doc["refined"]["errors_pct"][:2])


def test_the_acoustic_maps_hold_the_mapped_lip_tubes_formants_as_computed(small_maps, mesh_file, tmp_path):
    """The config's mapped lip tubes (the default speaker's four vowel lips) are looked up in the acoustic maps,
    equal to what a formant target computes without them; other lips are still computed."""
    from artic_cli.stages.acoustic_map import acoustic_map, read

    tmp, cfg = small_maps
    acoustic_map(tmp / "maps.h5", mesh_file, cfg, tmp_path / "am.h5")
    held = read(tmp_path / "am.h5", formants_only=True)
    assert set(held.lips) == {(4.0, 0.5), (2.5, 0.55), (1.0, 1.2), (0.5, 1.0)}
    with_maps = add_formants(load_context(tmp / "maps.h5", None, mesh_file), tmp / "maps.h5", mesh_file, cfg,
                             tmp_path / "am.h5")
    computed = add_formants(load_context(tmp / "maps.h5", None, mesh_file), tmp / "maps.h5", mesh_file, cfg)
    for lips in ((2.5, 0.55), (0.5, 1.0), (0.6, 1.5)):
        a, b = with_maps.formants("rest", *lips, 0.0), computed.formants("rest", *lips, 0.0)
        assert set(a) == set(b) and len(a) == 5
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])
    assert held.formants_with("rest", 0.6, 1.5) is None and held.formants_with("JO_6", 2.5, 0.55) is None


def test_unreachable_formants_exit_3_with_the_nearest_and_write_it(small_maps, mesh_file, tmp_path):
    tmp, cfg = small_maps
    target = tmp_path / "far.yaml"
    target.write_text("name: far\njaw: {forces_n: {}}\nacoustic: {formants_hz: [300, 2600], tolerance_pct: 5}\n")
    from typer.testing import CliRunner

    from artic_cli.cli.main import app

    res = CliRunner().invoke(app, ["solve-target", str(target), "--maps", str(tmp / "maps.h5"), "--mesh",
                                   str(mesh_file), "--config", str(cfg), "--acoustic-maps", str(tmp_path / "none.h5"),
                                   "--out", str(tmp_path / "far_sol.yaml")])
    assert res.exit_code == 3 and "Traceback" not in res.output, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "nearest mapped formants" in lines[0]
    sol = yaml.safe_load((tmp_path / "far_sol.yaml").read_text())
    assert "unreachable" in sol and sol["nearest"]["forces_n"] and len(sol["nearest"]["predicted_formants_hz"]) == 4


def test_a_solved_vowel_sounds_with_its_formants(found_vowel, tmp_path):
    """The WAV of a refined solution (0.6 s, F0 falling 125 -> 100 Hz): Praat finds the F1 and F2 the target
    asked for (the simulated vowel's), within the tolerances the vowels are judged by (10 % / 7 %)."""
    need("parselmouth")
    from artic_cli.stages.synthesize import synthesize_solution

    _, sol, made, _ = found_vowel
    audio = synthesize_solution(sol, tmp_path / "v.wav", 0.6, None, ROOT / "configs" / "voice" / "f0_fall_125_100.csv")
    assert abs(len(audio.samples) / audio.sample_rate_hz - 0.6) < 0.01
    asked = made["formants_hz"][:2]
    near, found = praat_formants_near(tmp_path / "v.wav", np.linspace(0.2, 0.4, 9), asked)
    for k, tol in ((0, 0.10), (1, 0.07)):
        assert abs(near[k] / asked[k] - 1) < tol, (k + 1, near[k], asked[k], found)


@pytest.mark.parametrize("body,needle", [
    ("target: v\nchosen: {}\n", "records no simulated area function"),
    ("a: 1\n", "is not a solve-target answer"),
    ("target: v\nchosen: {}\nverified: {area_function: {length_cm: [1, -1], area_cm2: [1, 1]}}\n", "length_cm[1]"),
])
def test_a_solution_without_a_usable_area_function_is_refused(tmp_path, body, needle):
    from typer.testing import CliRunner

    from artic_cli.cli.main import app

    sol = tmp_path / "s.yaml"
    sol.write_text(body)
    res = CliRunner().invoke(app, ["synthesize", "--solution", str(sol), "--out", str(tmp_path / "v.wav")])
    assert res.exit_code == 2 and needle in res.output and not (tmp_path / "v.wav").exists(), res.output


def test_a_vowel_answer_is_drawn_without_the_maps(found_vowel, tmp_path):
    from typer.testing import CliRunner

    from artic_cli.cli.main import app

    doc, sol, _, _ = found_vowel
    target = tmp_path / "found_target.yaml"
    target.write_text(yaml.safe_dump({"name": "found", "jaw": {"forces_n": {}},
                                      "acoustic": {"formants_hz": doc["acoustic"]["formants_hz"]}}))
    res = CliRunner().invoke(app, ["plot", "solution", str(sol), "--target", str(target), "--out",
                                   str(tmp_path / "v.png"), "--maps", str(tmp_path / "none.h5")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "v.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_tongue_tops_of_the_rest_jaw_and_the_rest_tongue_are_kept_apart():
    """A jaw position named "rest" and the model's rest tongue (the classes' reference) are two things."""
    from types import SimpleNamespace

    from artic_cli.control.epmap import EPMaps
    from artic_cli.control.tongue_tops import TongueTops

    nodes = np.array([[0.0, 1.0, 0.0], [-1.0, 2.0, 0.0], [-2.0, 1.0, 0.0]])  # tip first, top at (-1, 2)
    mesh = SimpleNamespace(node_sets={"surface": np.array([[9, 0, 9], [9, 1, 9], [9, 2, 9]]).ravel()})
    lv = np.array([0.0, 1.0])
    shapes = np.stack([nodes, nodes + [0.0, 0.5, 0.0]])
    net = Net(muscles=("A",), levels=(lv,), x=np.zeros((2, 3, 3)), converged=np.ones(2, bool), drift_cm=np.zeros(2),
              shapes=shapes)
    maps = EPMaps(jaws={"rest": JawMaps(forces={}, rest=np.zeros((3, 3)), single={"A": net})}, typical_jaw="rest",
                  model_rest=nodes)
    tops = TongueTops(mesh, lambda: maps)
    assert tops("rest")["single/A"] == pytest.approx(np.array([[-1.0, 2.0], [-1.0, 2.5]]))
    assert tops.rest == pytest.approx([-1.0, 2.0])
    assert isinstance(tops("rest"), dict)
