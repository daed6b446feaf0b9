"""The command line: stages, provenance, and one-line errors for bad input."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np
import pytest

from conftest import ROOT


def artic(*args, cwd=None):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "artic_cli.cli.main", *map(str, args)], capture_output=True,
                          text=True, cwd=cwd or ROOT, env=env, timeout=300)


def assert_one_line_error(res, *needles):
    assert res.returncode == 2, (res.stdout, res.stderr)
    assert "Traceback" not in res.stderr + res.stdout
    lines = [ln for ln in res.stderr.strip().splitlines() if ln.strip()]
    assert len(lines) == 1, res.stderr
    for n in needles:
        assert n in lines[0], lines[0]


def test_help_lists_every_stage():
    res = artic("--help")
    assert res.returncode == 0
    for stage in ("build-mesh", "simulate", "validate"):
        assert stage in res.stdout


def test_build_mesh_writes_provenance_and_a_figure(tmp_path):
    out, png = tmp_path / "m.h5", tmp_path / "m.png"
    res = artic("build-mesh", "--out", out, "--plot", png)
    assert res.returncode == 0, res.stderr
    assert "231 nodes, 120 bricks" in res.stdout
    with h5py.File(out) as f:
        assert f.attrs["kind"] == "mesh" and f.attrs["schema_version"] == 2
        assert len(f.attrs["content_sha256"]) == 64 and f.attrs["package_version"]
        assert f["tongue/nodes"].attrs["units"] == "cm"
        assert f["tongue/nodes"].shape == (231, 3)
    assert png.stat().st_size > 20_000
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


@pytest.fixture(scope="module")
def schedule(tmp_path_factory):
    p = tmp_path_factory.mktemp("sched") / "pull.yaml"
    p.write_text("duration_ms: 60\nloads:\n  - nodes: blade\n    force_n: [1.0, 1.0, 0]\n    onset_ms: 0\n"
                 "    duration_ms: 60\n")
    return p


def test_simulate_writes_trajectories_volume_and_metadata(mesh_file, schedule, tmp_path):
    out = tmp_path / "sim.h5"
    res = artic("simulate", "--tongue-only", "--schedule", schedule, "--mesh", mesh_file, "--out", out,
                "--plot", tmp_path / "s.png")
    assert res.returncode == 0, res.stderr
    assert "max |volume change|" in res.stdout
    with h5py.File(out) as f:
        assert f.attrs["kind"] == "simulation"
        inputs = json.loads(f.attrs["inputs_json"])
        assert len(inputs["mesh"]) == 64 and len(inputs["schedule"]) == 64 and len(f.attrs["recipe_sha256"]) == 64
        assert f.attrs["dt_s"] == pytest.approx(0.005) and f.attrs["scheme"] == "houbolt"
        x = f["nodes/positions"][()]
        assert x.shape == (13, 231, 3)
        assert f["time"][-1] == pytest.approx(0.06)
        assert np.abs(f["volume_change"][()]).max() < 0.003
        tip = f["control_points/tip/position"][()]
        assert tip[-1, 0] > tip[0, 0]  # pulled forward
    assert (tmp_path / "s.png").stat().st_size > 20_000


def test_simulate_without_constraint_reports_the_drift(mesh_file, schedule, tmp_path):
    res = artic("simulate", "--tongue-only", "--schedule", schedule, "--mesh", mesh_file, "--out", tmp_path / "o.h5",
                "--no-volume-constraint")
    assert res.returncode == 0, res.stderr
    assert "constraint off" in res.stdout


def test_simulate_drives_muscles_of_the_whole_articulator(mesh_file, tmp_path):
    sched = tmp_path / "sg.yaml"
    sched.write_text("duration_ms: 30\nmuscles:\n  - {muscle: SG, force_n: 4, onset_ms: 0, duration_ms: 30}\n"
                     "  - {muscle: JO, force_n: 3, onset_ms: 0, duration_ms: 30}\n")
    out, gif = tmp_path / "sg.h5", tmp_path / "sg.gif"
    res = artic("simulate", "--schedule", sched, "--mesh", mesh_file, "--out", out, "--animate", gif)
    assert res.returncode == 0, res.stderr
    assert gif.read_bytes()[:6] == b"GIF89a" and gif.stat().st_size > 10_000
    with h5py.File(out) as f:
        names = list(f["muscles"].attrs["names"])
        force = f["muscles/force"][()][:, names.index("SG")]
        length = f["muscles/length"][()][:, names.index("SG")]
        assert force[0] == pytest.approx(4.0, rel=0.05)  # at rest length the force is the input
        assert length[-1] < length[0] and force[-1] < force[0]  # shortening lowers it (Eq. 9)
        tip = f["control_points/tip/position"][()]
        jaw = f["control_points/jaw/position"][()]
        assert tip[-1, 0] < tip[0, 0]  # SG draws the tip back
        assert jaw[-1, 1] < jaw[0, 1]  # JO lowers the jaw
        assert f["contacts/count"].shape == (7,)


BAD_SCHEDULES = {
    "unknown muscle": ("muscles:\n  - {muscle: GGz, force_n: 1, onset_ms: 0, duration_ms: 10}\n", "GGa, GGm"),
    "negative force": ("muscles:\n  - {muscle: SG, force_n: -1, onset_ms: 0, duration_ms: 10}\n", "force_n"),
    "overlap": ("muscles:\n  - {muscle: SG, force_n: 1, onset_ms: 0, duration_ms: 30}\n"
                "  - {muscle: SG, force_n: 2, onset_ms: 10, duration_ms: 30}\n", "overlap"),
    "nan force": ("loads:\n  - {nodes: tip, force_n: [.nan, 0, 0], onset_ms: 0, duration_ms: 10}\n", "force_n"),
    "unknown node set": ("loads:\n  - {nodes: nose, force_n: [1, 0, 0], onset_ms: 0, duration_ms: 10}\n", "nose"),
    "unknown key": ("loads:\n  - {nodes: tip, force: [1, 0, 0], onset_ms: 0, duration_ms: 10}\n", "force"),
    "malformed": ("loads: [\n", "malformed YAML"),
    "late onset": ("loads:\n  - {nodes: tip, force_n: [1, 0, 0], onset_ms: 500, duration_ms: 10}\n", "onset_ms"),
}


@pytest.mark.parametrize("case", sorted(BAD_SCHEDULES))
def test_bad_schedules_fail_in_one_line_without_output(case, mesh_file, tmp_path):
    text, needle = BAD_SCHEDULES[case]
    sched = tmp_path / "bad.yaml"
    sched.write_text(text)
    out = tmp_path / "never.h5"
    res = artic("simulate", "--schedule", sched, "--mesh", mesh_file, "--duration", "0.05", "--out", out)
    assert_one_line_error(res, needle)
    assert not out.exists()


@pytest.mark.parametrize("flag,value", [("--dt", "0"), ("--dt", "-0.001"), ("--duration", "0"), ("--duration", "nan")])
def test_non_positive_times_are_refused(flag, value, mesh_file, schedule, tmp_path):
    res = artic("simulate", "--schedule", schedule, "--mesh", mesh_file, flag, value, "--out", tmp_path / "x.h5")
    assert_one_line_error(res, flag)


def test_missing_corrupt_stale_and_foreign_meshes_are_refused(mesh_file, schedule, tmp_path, cfg):
    res = artic("simulate", "--schedule", schedule, "--mesh", tmp_path / "none.h5")
    assert_one_line_error(res, "not found", "build-mesh")

    broken = tmp_path / "broken.h5"
    broken.write_bytes(mesh_file.read_bytes()[:5000])
    res = artic("simulate", "--schedule", schedule, "--mesh", broken)
    assert_one_line_error(res, "corrupted or truncated")

    old = tmp_path / "old.h5"
    shutil.copy(mesh_file, old)
    with h5py.File(old, "a") as f:
        f.attrs["schema_version"] = 0
    res = artic("simulate", "--schedule", schedule, "--mesh", old)
    assert_one_line_error(res, "schema version")

    import yaml

    other = cfg.model_dump(mode="json")
    other["speaker"]["tongue"]["inner_fraction"] = 0.25
    cfile = tmp_path / "other.yaml"
    cfile.write_text(yaml.safe_dump(other))
    res = artic("simulate", "--schedule", schedule, "--mesh", mesh_file, "--config", cfile)
    assert_one_line_error(res, "another speaker geometry")


def test_bad_config_is_one_line(tmp_path):
    bad = tmp_path / "c.yaml"
    bad.write_text((ROOT / "configs" / "default.yaml").read_text().replace("viscosity_kpa_s", "viscosty_kpa_s", 1))
    res = artic("build-mesh", "--config", bad, "--out", tmp_path / "m.h5")
    assert_one_line_error(res, "viscosty_kpa_s", "did you mean")
    assert not (tmp_path / "m.h5").exists()


def test_validate_cuboid_json():
    res = artic("validate", "cuboid", "--force", "0.1", "--force", "1", "--json")
    assert res.returncode == 0, res.stderr
    rows = json.loads(res.stdout)
    assert [r["force_n"] for r in rows] == [0.1, 1.0]
    assert {"axial_strain", "lateral_strain", "poisson_ratio", "volume_change"} <= set(rows[0])
    res = artic("validate", "cuboid", "--force", "-1")
    assert_one_line_error(res, "--force")


def test_failed_write_leaves_no_file(tmp_path):
    from artic_cli.io.store import atomic_h5

    target = tmp_path / "a.h5"
    with pytest.raises(RuntimeError):
        with atomic_h5(target, "test") as f:
            f.create_dataset("x", data=np.arange(3))
            raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_export_writes_paraview_files_and_ema_csv(mesh_file, tmp_path):
    import meshio

    sched = tmp_path / "sl.yaml"
    sched.write_text("duration_ms: 20\nmuscles:\n  - {muscle: SL, force_n: 2, onset_ms: 0, duration_ms: 20}\n")
    sim = tmp_path / "sl.h5"
    assert artic("simulate", "--schedule", sched, "--mesh", mesh_file, "--out", sim).returncode == 0
    res = artic("export", "--mesh", mesh_file, "--sim", sim, "--vtk", tmp_path / "vtk", "--csv", tmp_path / "sl.csv")
    assert res.returncode == 0, res.stderr
    tongue = meshio.read(tmp_path / "vtk" / "mesh.vtu")
    assert tongue.cells_dict["hexahedron"].shape == (120, 8)
    frame = meshio.read(tmp_path / "vtk" / "sl_0004.vtu")
    assert frame.points.shape[0] > 231 and "line" in frame.cells_dict  # tongue + jaw and hyoid
    with meshio.xdmf.TimeSeriesReader(tmp_path / "vtk" / "sl.xdmf") as r:
        r.read_points_cells()
        assert r.num_steps == 5
        t, pd, _ = r.read_data(4)
        assert t == pytest.approx(0.02) and np.abs(pd["displacement"]).max() > 0.01
    assert "sl_0004.vtu" in (tmp_path / "vtk" / "sl.pvd").read_text()
    rows = (tmp_path / "sl.csv").read_text().splitlines()
    assert rows[0] == "time_s," + ",".join(f"{p}_{a}_cm" for p in ("tip", "dorsum", "jaw") for a in "xyz")
    assert len(rows) == 6
    bad = artic("export", "--mesh", mesh_file, "--csv", tmp_path / "x.csv")
    assert_one_line_error(bad, "--sim")


def test_a_ctrl_c_inside_compiled_code_counts_as_an_interrupt():
    """numba turns a KeyboardInterrupt that lands during a callback into SystemError (cause: the interrupt);
    the CLI must still exit with 130 and its one line, and must not swallow genuine SystemErrors."""
    from artic_cli.cli.app import interrupted

    def raised(inner):
        try:
            try:
                raise inner
            except BaseException as err:
                raise SystemError("returned a result with an exception set") from err
        except SystemError as outer:
            return outer

    assert interrupted(KeyboardInterrupt())
    assert interrupted(raised(KeyboardInterrupt()))
    assert not interrupted(SystemError("compiled code failed"))
    assert interrupted(raised(raised(KeyboardInterrupt())))
    assert not interrupted(raised(ValueError("a real bug")))
