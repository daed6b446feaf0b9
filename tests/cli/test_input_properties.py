"""Property-based: malformed and extreme schedules, targets and configs, in the real formats, through the real
commands.  Whatever comes in: a documented exit status, no traceback, nothing written outside the output
folder, no partial file."""

from __future__ import annotations

import contextlib
import math
import os
import tempfile
from pathlib import Path

import h5py
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from artic_cli.cli.main import app

from conftest import ROOT

RUNNER = CliRunner()
SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                           HealthCheck.too_slow])

numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64), st.integers(-10**9, 10**9),
                    st.sampled_from([0.0, -0.0, 1e-300, 50.0, 50.0001, 1e6, -1.0]))
anything = st.one_of(numbers, st.text(max_size=8), st.none(), st.booleans(), st.lists(numbers, max_size=4))
muscles = st.sampled_from(["SG", "GGp", "JO", "T-SL", "XX", "", "sg"])
node_sets = st.sampled_from(["tip", "blade", "dorsum_region", "nowhere", ""])


def _maybe(value_strategy):
    return st.one_of(value_strategy, anything)


muscle_entry = st.fixed_dictionaries(
    {"muscle": _maybe(muscles), "force_n": _maybe(numbers)},
    optional={"onset_ms": _maybe(numbers), "duration_ms": _maybe(numbers), "forse_n": numbers})
load_entry = st.fixed_dictionaries(
    {"nodes": _maybe(node_sets), "force_n": st.one_of(st.lists(numbers, min_size=3, max_size=3), anything)},
    optional={"onset_ms": _maybe(numbers), "duration_ms": _maybe(numbers)})
schedules = st.one_of(
    st.fixed_dictionaries({}, optional={"duration_ms": _maybe(numbers), "muscles": st.lists(muscle_entry, max_size=3),
                                        "loads": st.lists(load_entry, max_size=2), "musles": st.just([])}),
    anything)
names = st.one_of(st.sampled_from(["ok", "../../escaped", "/tmp/abs", ".hidden", "a/b", "..", "x" * 150, "é", ""]),
                  st.text(max_size=12))
jaws = st.one_of(st.fixed_dictionaries({"forces_n": st.dictionaries(st.sampled_from(["JO", "JC", "XX"]), numbers,
                                                                     max_size=2)}),
                 st.fixed_dictionaries({"opening_cm": numbers}), anything)
lips = st.one_of(st.sampled_from(["rounded", "compressed", "neutral", "pursed", ""]),
                 st.fixed_dictionaries({"area_cm2": _maybe(numbers), "length_cm": _maybe(numbers)}), anything)
targets = st.one_of(
    st.fixed_dictionaries(
        {"crucial": st.fixed_dictionaries({"point": _maybe(st.sampled_from(["tip", "dorsum", "lip"])),
                                           "at_cm": st.one_of(st.lists(numbers, min_size=2, max_size=2), anything)},
                                          optional={"tolerance_cm": _maybe(numbers)})},
        optional={"name": names, "jaw": jaws, "force_weight": _maybe(numbers)}),
    st.fixed_dictionaries(  # a vowel: formants, lips, port
        {"acoustic": st.fixed_dictionaries(
            {"formants_hz": st.one_of(st.lists(_maybe(numbers), min_size=1, max_size=4), anything)},
            optional={"tolerance_pct": st.one_of(numbers, st.lists(numbers, max_size=3), anything)})},
        optional={"name": names, "jaw": jaws, "lips": lips, "velum_port_cm2": _maybe(numbers)}),
    anything)


def _invoke(args: list[str]):
    res = RUNNER.invoke(app, [str(a) for a in args])
    assert res.exception is None or isinstance(res.exception, SystemExit), repr(res.exception)
    assert "Traceback" not in res.output
    return res


def _files(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()}


def _no_partials(folder: Path) -> None:
    assert not [p for p in folder.rglob("*") if p.name.startswith(".") and p.name.endswith(".tmp")]


@contextlib.contextmanager
def _sandbox():
    """A working folder (the command's cwd) with an output folder inside; cwd restored after."""
    old = os.getcwd()
    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        (root / "work" / "out").mkdir(parents=True)
        os.chdir(root / "work")
        try:
            yield root, root / "work" / "out"
        finally:
            os.chdir(old)


def _dump(path: Path, data) -> None:
    try:
        path.write_text(yaml.safe_dump(data, allow_unicode=True))
    except yaml.YAMLError:
        path.write_text("{not: yaml: at all")


@pytest.fixture(scope="module")
def tiny_maps(tmp_path_factory, mesh_file):
    from artic_cli.stages.dynamic import build_dynamic_map
    from artic_cli.stages.epmap import build_ep_maps

    tmp = tmp_path_factory.mktemp("tiny-maps")
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d["epmap"] = dict(jaw_positions={"rest": {}, "JO_0.5": {"JO": 0.5}, "JO_2.5": {"JO": 2.5}}, typical_jaw="JO_0.5",
                      net_jaw_positions=["JO_0.5"], muscles=["SG", "GGa"], levels_n=[0.0, 2.0], pair_levels_n=[2.0],
                      pairs_tip=[["SG", "GGa"]], pairs_dorsum=[], groups=[], duration_ms=60.0,
                      convergence_window_ms=20.0, convergence_tol_cm=1.0)
    (tmp / "c.yaml").write_text(yaml.safe_dump(d))
    build_ep_maps(mesh_file, tmp / "c.yaml", tmp / "maps.h5", cache=tmp / "cache")
    build_dynamic_map(tmp / "maps.h5", tmp / "dynamic.h5")
    return tmp


@SETTINGS
@given(schedule=schedules)
def test_any_schedule_ends_in_a_documented_status(schedule, mesh_file):
    with _sandbox() as (root, out):
        _dump(root / "s.yaml", schedule)
        before = _files(root) - {"s.yaml"}
        res = _invoke(["simulate", "--schedule", root / "s.yaml", "--mesh", mesh_file, "--out", out / "s.h5",
                       "--tongue-only", "--duration", "0.005"])
        assert res.exit_code in (0, 2, 4), res.output
        written = _files(root) - before - {"s.yaml"}
        if res.exit_code == 2:
            assert written == set(), written
            assert len([ln for ln in res.output.strip().splitlines() if ln.strip()]) <= 2  # one error (wrapped)
        else:
            assert written == {"work/out/s.h5"}
            with h5py.File(out / "s.h5") as f:
                assert f.attrs["kind"] == "simulation" and bool(f.attrs["valid"]) == (res.exit_code == 0)
        _no_partials(root)


@SETTINGS
@given(target=targets)
def test_any_target_ends_in_a_documented_status_and_writes_only_under_its_folder(target, tiny_maps):
    with _sandbox() as (root, out):
        _dump(root / "t.yaml", target)
        res = _invoke(["solve-target", root / "t.yaml", "--maps", tiny_maps / "maps.h5", "--dynamic",
                       tiny_maps / "dynamic.h5"])  # no --out: the target's name picks the file
        assert res.exit_code in (0, 2, 3), res.output
        written = _files(root) - {"t.yaml"}
        if res.exit_code == 2:
            assert written == set(), written
        else:
            assert len(written) == 1 and next(iter(written)).startswith("work/data/solutions/"), written
        _no_partials(root)


def _mutate(data, path, value):
    node = data
    for k in path[:-1]:
        node = node[k] if isinstance(node, dict) and k in node else None
        if node is None:
            return data
    if isinstance(node, dict):
        node[path[-1]] = value
    return data


config_edits = st.tuples(st.sampled_from([
    ("materials", "tongue", "youngs_modulus_kpa"), ("materials", "tongue", "poisson_ratio"),
    ("speaker", "tongue", "radial_sections"), ("speaker", "tongue", "gg_origin_cm"), ("speaker", "name"),
    ("speaker", "wall", "points_per_outline"), ("simulation", "dt_ms"), ("muscles", "max_force_n"),
    ("speaker", "tongue", "half_width_cm"), ("speaker", "tongu"), ("schema_version",), ("contact", "stiffness_n_per_cm")]),
    anything)


@SETTINGS
@given(edit=config_edits)
def test_any_config_edit_builds_a_mesh_or_is_refused_in_one_line(edit):
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    path, value = edit
    with _sandbox() as (root, out):
        _dump(root / "c.yaml", _mutate(d, path, value))
        res = _invoke(["build-mesh", "--config", root / "c.yaml", "--out", out / "m.h5"])
        assert res.exit_code in (0, 2), res.output
        if res.exit_code == 2:
            assert not (out / "m.h5").exists()
            assert "error:" in res.output
        _no_partials(root)


@SETTINGS
@given(value=numbers)
def test_numeric_options_are_checked(value, mesh_file):
    with _sandbox() as (root, out):
        (root / "s.yaml").write_text("duration_ms: 5\n")
        res = _invoke(["simulate", "--schedule", root / "s.yaml", "--mesh", mesh_file, "--out", out / "s.h5",
                       "--tongue-only", "--dt", repr(float(value))])
        ok = math.isfinite(value) and 1e-6 <= value <= 0.005
        assert res.exit_code == (0 if ok else 2), res.output
        assert (out / "s.h5").exists() == ok


segment = st.fixed_dictionaries(
    {"duration_ms": _maybe(numbers)},
    optional={"forces_n": st.one_of(st.dictionaries(muscles, _maybe(numbers), max_size=3), anything),
              "target": st.one_of(st.sampled_from(["configs/targets/velar.yaml", "nowhere.yaml"]), targets),
              "voiced": _maybe(st.booleans()), "label": names})
contours = st.one_of(st.lists(st.lists(numbers, min_size=2, max_size=2), max_size=3), anything)
courses = _maybe(st.sampled_from(["static", "pulse_step", "jerk"]))
utterances = st.one_of(
    st.fixed_dictionaries({"segments": st.one_of(st.lists(segment, max_size=3), anything)},
                          optional={"name": names, "f0_hz": contours, "ramp_ms": _maybe(numbers),
                                    "force_course": courses, "tract": st.lists(anything, max_size=2)}),
    anything)


@SETTINGS
@given(utterance=utterances)
def test_any_utterance_is_read_or_refused_in_one_line(utterance):
    """Every utterance either reads as a valid one (durations positive, F0 50-500 Hz with rising times, one
    source per segment) or is one ArticError naming its key; speaking the valid ones is tested elsewhere."""
    from artic_cli.errors import ArticError
    from artic_cli.speech.utterance import parse_utterance

    try:
        u = parse_utterance(utterance, "u.yaml")
    except ArticError as err:
        assert "\n" not in str(err) and str(err).startswith("u.yaml")
        return
    assert u.segments and all(s.duration_ms > 0 for s in u.segments)
    assert all(50 <= f <= 500 and t >= 0 for t, f in u.f0_hz)
    assert all(b[0] > a[0] for a, b in zip(u.f0_hz, u.f0_hz[1:]))
    assert all((s.target is None) != (s.forces_n is None) for s in u.segments)
