"""Freshness by content: a rebuilt but identical mesh and edits outside the physics recompute nothing; a
physics change (a materials value, the equilibrium code) recomputes."""

from __future__ import annotations

import os

import h5py
import yaml

from artic_cli.io import fingerprint
from artic_cli.io.fingerprint import code_hash, module_closure, source_hash
from artic_cli.stages import epmap as epmap_stage
from artic_cli.stages.epmap import build_ep_maps
from artic_cli.stages.mesh import build_mesh

from conftest import ROOT

TINY = dict(jaw_positions={"rest": {}}, typical_jaw="rest", net_jaw_positions=[], muscles=["SG"],
            levels_n=[0.0, 1.0], pairs_tip=[], pairs_dorsum=[], groups=[], duration_ms=60.0,
            convergence_window_ms=20.0, convergence_tol_cm=1.0)


def _config(tmp, name, change=None):
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d["epmap"] = dict(TINY)
    for path, value in (change or {}).items():
        node = d
        *head, last = path.split(".")
        for k in head:
            node = node.setdefault(k, {})
        node[last] = value
    p = tmp / f"{name}.yaml"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return p


def _content(path):
    with h5py.File(path, "r") as f:
        return str(f.attrs["content_sha256"]), str(f.attrs["created"])


def test_a_mesh_rebuilt_from_the_same_inputs_has_the_same_content_and_keeps_its_time(tmp_path):
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    build_mesh(None, a)
    build_mesh(None, b)
    assert _content(a)[0] == _content(b)[0]
    before = os.stat(a).st_mtime_ns
    os.utime(a, ns=(before - 10**9, before - 10**9))  # pretend it is a second older
    old = os.stat(a).st_mtime_ns
    s = build_mesh(None, a)
    assert s.up_to_date and os.stat(a).st_mtime_ns == old  # same recipe: not even rewritten
    with h5py.File(a, "r+") as f:
        f.attrs["recipe_sha256"] = "from an older artic"  # forces a rebuild ...
    old = os.stat(a).st_mtime_ns
    s = build_mesh(None, a)
    assert not s.up_to_date and os.stat(a).st_mtime_ns == old  # ... whose equal content keeps the file's time


def test_a_rebuilt_mesh_and_unread_config_sections_recompute_no_equilibrium(tmp_path):
    cfg = _config(tmp_path, "c")
    m1, m2 = tmp_path / "m1.h5", tmp_path / "m2.h5"
    build_mesh(cfg, m1)
    first = build_ep_maps(m1, cfg, tmp_path / "maps.h5", cache=tmp_path / "cache")
    assert first.computed == first.total > 0
    build_mesh(cfg, m2)  # a second, separately built mesh of the same speaker
    again = build_ep_maps(m2, cfg, tmp_path / "maps2.h5", cache=tmp_path / "cache")
    assert again.computed == 0 and again.cached == again.total
    # sections the EP maps do not read: the cuboid test, the muscle-function study
    other = _config(tmp_path, "other", {"cuboid.forces_n": [0.5], "muscle_function.drive_ms": 99.0})
    same = build_ep_maps(m2, other, tmp_path / "maps.h5", cache=tmp_path / "cache")
    assert same.up_to_date  # the file already holds this recipe: nothing is even looked up


def test_a_physics_change_recomputes(tmp_path, monkeypatch):
    cfg = _config(tmp_path, "c")
    mesh = tmp_path / "m.h5"
    build_mesh(cfg, mesh)
    build_ep_maps(mesh, cfg, tmp_path / "maps.h5", cache=tmp_path / "cache")
    stiffer = _config(tmp_path, "stiff", {"materials.tongue.youngs_modulus_kpa": 25.0})
    r = build_ep_maps(mesh, stiffer, tmp_path / "stiff.h5", cache=tmp_path / "cache")
    assert r.computed == r.total and r.cached == 0
    real = epmap_stage.code_hash
    monkeypatch.setattr(epmap_stage, "code_hash", lambda *m: real(*m) + "-edited")  # the equilibrium code changed
    r = build_ep_maps(mesh, cfg, tmp_path / "edited.h5", cache=tmp_path / "cache")
    assert r.computed == r.total and r.cached == 0


def test_code_hash_ignores_comments_and_docstrings_but_not_code():
    code = 'def f(x):\n    """Twice x."""\n    return 2 * x\n'
    assert source_hash(code) == source_hash('def f(x):\n    """Double."""\n    # a comment\n    return 2 * x  # ok\n')
    assert source_hash(code) != source_hash(code.replace("2 * x", "3 * x"))


def test_results_do_not_depend_on_plots_the_cli_or_the_plumbing():
    for stage in ("artic_cli.stages.mesh", "artic_cli.stages.simulate", "artic_cli.stages.epmap",
                  "artic_cli.stages.muscle_function", "artic_cli.control.equilibrium"):
        mods = module_closure(stage)
        assert not [m for m in mods if m.startswith(fingerprint.NOT_RESULTS)], stage
    assert "artic_cli.mechanics.integrator" in module_closure("artic_cli.control.equilibrium")
    assert "artic_cli.geometry.mesh" in module_closure("artic_cli.stages.mesh")
    assert len(code_hash("artic_cli.control.equilibrium")) == 64
