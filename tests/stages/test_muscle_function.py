"""Muscle function from scattered starts (section IV.A.1, Figs. 5 and 6) on a thinned grid."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from artic_cli.experiments.muscle_function import convergence
from artic_cli.stages.muscle_function import build_muscle_function, load_muscle_function

from conftest import ROOT

pytestmark = pytest.mark.slow


def test_starts_scatter_and_each_muscle_gathers_them(tmp_path, mesh_file):
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d["muscle_function"] = {"start_levels_n": [0.0, 3.0], "muscles": ["GGp", "SG"]}
    cfg = tmp_path / "mf.yaml"
    cfg.write_text(yaml.safe_dump(d))
    mf, _, cached, distinct, _ = build_muscle_function(mesh_file, cfg, tmp_path / "mf.h5", jobs=2,
                                                    cache=tmp_path / "cache")
    assert len(mf.starts) == 4 * 2 ** 3 and cached == 0
    assert distinct == 18  # the four combinations share GGa (and GGp, GGm, HG, SG pairwise)
    back = load_muscle_function(tmp_path / "mf.h5")
    assert np.array_equal(back.ends, mf.ends) and back.ends.shape == (2, 32, 3, 3)
    rows = {(r["muscle"], r["point"]): r for r in convergence(mf)}
    for key, r in rows.items():
        assert r["end_spread_cm"] < 0.25 * r["start_spread_cm"], key  # scattered starts, gathered ends
    # GGp drives the tip forward, SG drives it back (section IV.A.1)
    assert rows[("GGp", "tip")]["mean_end_from_rest_cm"][0] > 0.1
    assert rows[("SG", "tip")]["mean_end_from_rest_cm"][0] < -0.1


def test_held_jaw_keeps_the_mandible_and_mh_lifts_the_dorsum(tmp_path, mesh_file):
    """muscle_function.hold_jaw: the mandible stays at its rest (MH, whose fibres end on it, then drives the dorsum
    forward-up as the paper's Fig. 6 has it; with the jaw free MH 4 N drops the mandible and the tongue with it)."""
    from artic_cli.experiments.paper import PAPER_DIRECTIONS

    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d["muscle_function"] = {"start_levels_n": [0.0, 3.0], "muscles": ["MH"], "hold_jaw": True}
    cfg = tmp_path / "mf.yaml"
    cfg.write_text(yaml.safe_dump(d))
    mf = build_muscle_function(mesh_file, cfg, tmp_path / "mf.h5", jobs=2, cache=tmp_path / "cache")[0]
    jaw = 2
    assert np.abs(mf.ends[0, :, jaw, :] - mf.rest[jaw]).max() < 0.01  # cm: held
    move = {r["point"]: np.array(r["mean_end_from_rest_cm"]) for r in convergence(mf)}["dorsum"]
    ref = np.asarray(PAPER_DIRECTIONS["MH"]["dorsum"], dtype=float)
    cos = move @ ref / (np.linalg.norm(move) * np.linalg.norm(ref))
    assert np.linalg.norm(move) >= 0.05 and np.degrees(np.arccos(cos)) <= 45.0
