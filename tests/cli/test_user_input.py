"""The three holes found by trying artic as a new user, each closed: NaN in a target, a target name that
escapes the output folder, and an unphysical simulation that looked like any other."""

from __future__ import annotations

import h5py
import pytest
import yaml

from artic_cli.errors import ArticError
from artic_cli.stages.simulate import read

from conftest import ROOT, run_cli

_run = run_cli


def test_a_nan_in_a_target_is_refused_before_any_search(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.yaml").write_text("crucial: {point: tip, at_cm: [.nan, -0.45]}\n")
    res = _run("solve-target", tmp_path / "t.yaml", "--maps", "missing.h5")
    assert res.exit_code == 2 and "crucial.at_cm.0" in res.output and "not a finite number" in res.output
    assert not (tmp_path / "data").exists()
    (tmp_path / "t.yaml").write_text("crucial: {point: tip, at_cm: [-0.95, .inf]}\n")
    res = _run("solve-target", tmp_path / "t.yaml", "--maps", "missing.h5")
    assert res.exit_code == 2 and "crucial.at_cm.1" in res.output


def test_a_target_name_cannot_choose_a_path_outside_the_output_folder(tmp_path, monkeypatch):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    for name in ("../../escaped", "/tmp/escaped", ".hidden", "a/b"):
        (work / "t.yaml").write_text(yaml.safe_dump({"name": name, "crucial": {"point": "tip", "at_cm": [-1, -0.4]}}))
        res = _run("solve-target", work / "t.yaml", "--maps", "missing.h5")
        assert res.exit_code == 2 and "not a safe file name" in res.output, res.output
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a", "b", "t.yaml"]


def test_an_unphysical_simulation_is_written_marked_invalid_and_refused_downstream(tmp_path, mesh_file):
    sched = tmp_path / "big.yaml"
    sched.write_text("duration_ms: 50\nmuscles:\n  - {muscle: SL, force_n: 1000000, duration_ms: 50}\n")
    res = _run("simulate", "--schedule", sched, "--mesh", mesh_file, "--out", tmp_path / "big.h5")
    assert res.exit_code == 2 and "above the 50-N cap" in res.output and not (tmp_path / "big.h5").exists()
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d["muscles"] = {"max_force_n": 2e6}
    (tmp_path / "cap.yaml").write_text(yaml.safe_dump(d))
    res = _run("simulate", "--schedule", sched, "--mesh", mesh_file, "--config", tmp_path / "cap.yaml",
               "--out", tmp_path / "big.h5")
    assert res.exit_code == 4 and "marked invalid" in res.output and "inverted bricks" in res.output, res.output
    with h5py.File(tmp_path / "big.h5") as f:
        assert not f.attrs["valid"] and "inverted bricks" in f.attrs["invalid_reason"]
    with pytest.raises(ArticError, match="marked invalid"):
        read(tmp_path / "big.h5")
    assert read(tmp_path / "big.h5", allow_invalid=True).inverted_bricks.max() > 0
    res = _run("simulate", "--schedule", sched, "--mesh", mesh_file, "--config", tmp_path / "cap.yaml",
               "--out", tmp_path / "big.h5")
    assert res.exit_code == 4 and "up to date" in res.output  # still says so when nothing is recomputed


def test_help_lists_the_exit_statuses():
    res = _run("--help")
    for status in ("0 done", "2 bad input", "3 target not reached", "4 result not physical", "130 interrupted"):
        assert status in " ".join(res.output.split()), status
