"""Constriction targets (issue 45): an area at a place of the tract in, muscle forces out, checked and refined
by simulation."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.control.constriction_solver import solve_constriction_on
from artic_cli.control.epmap import JawMaps, Net
from artic_cli.control.solver import parse_target
from artic_cli.errors import ArticError, UnreachableTarget
from artic_cli.stages.solve import add_formants, load_context, simulator, solve_target
from artic_cli.tract.places import place_area, place_index, section_places

from conftest import run_cli


def _target(place="hard palate", area=0.0, tol=0.01, **extra):
    return parse_target({"name": "c", "jaw": {"forces_n": {}},
                         "constriction": {"place": place, "area_cm2": area, "tolerance_cm2": tol}, **extra})


@pytest.mark.parametrize("data, needle", [
    ({"constriction": {"place": "velum", "area_cm2": -0.1}}, "constriction.area_cm2"),
    ({"constriction": {"place": "velum", "area_cm2": float("nan")}}, "constriction.area_cm2"),
    ({"constriction": {"place": "velum"}}, "constriction.area_cm2"),
    ({"constriction": {"place": "velum", "area_cm2": 0}, "crucial": {"point": "tip", "at_cm": [0, 0]}}, "one of them"),
    ({"constriction": {"place": "velum", "area_cm2": 0}, "jaw": {"opening_cm": -0.3}}, "mapped jaw position"),
])
def test_bad_constriction_targets_are_refused_naming_the_key(data, needle):
    with pytest.raises(ArticError) as err:
        parse_target({"name": "c", "jaw": {"forces_n": {}}, **data})
    assert needle in str(err.value), str(err.value)


def test_a_place_is_a_region_of_the_tract_and_its_area_its_narrowest_section(cfg):
    region, names = section_places(cfg.vocal_tract)
    assert names[-1] == "lips" and "alveolar" in names and "velum" in names
    a = np.full((2, len(region)), 3.0)
    k = place_index(names, "velum")
    a[1, np.flatnonzero(region == k)[1]] = 0.2
    assert place_area(a, region, k).tolist() == [3.0, 0.2]
    with pytest.raises(ArticError, match="'ridge' is not a place of the tract; places: larynx"):
        place_index(names, "ridge")


def _vector_and_net():
    """A vector whose place area falls 2, 1.2, 0.4, 0 cm^2 with 0, 1, 2.5, 4 N, and a pair net falling with
    both forces (twice as fast)."""
    lv = np.array([0.0, 1.0, 2.5, 4.0])
    x = np.zeros((4, 3, 3))
    vec = Net(muscles=("A",), levels=(lv,), x=x, converged=np.ones(4, bool), drift_cm=np.zeros(4))
    a, b = np.meshgrid(lv, lv, indexing="ij")
    net = Net(muscles=("A", "B"), levels=(lv, lv), x=np.zeros((4, 4, 3, 3)), converged=np.ones((4, 4), bool),
              drift_cm=np.zeros((4, 4)))
    jm = JawMaps(forces={}, rest=x[0], single={"A": vec}, pair={"A+B": net})
    areas = {"single/A": np.array([2.0, 1.2, 0.4, 0.0]), "pair/A+B": np.clip(2.0 - 0.8 * a - 0.8 * b, 0.0, None)}
    return jm, areas


def test_the_least_force_that_meets_the_area_is_chosen():
    jm, areas = _vector_and_net()
    cands = solve_constriction_on(jm, _target(area=0.8, tol=0.01), areas)
    single = [c for c in cands if c.family == "single"][0]
    assert single.forces["A"] == pytest.approx(1.0 + 1.5 * (1.2 - 0.81) / 0.8, abs=1e-6)  # where 1.2 -> 0.4 meets 0.81
    assert abs(single.detail["place_area_cm2"] - 0.81) < 1e-6
    best = cands[0]  # in the net, A = B = 0.75 N (0.8 cm^2) costs 1.125 N^2, less than A alone (3.0)
    assert best.family == "pair" and sum(v * v for v in best.forces.values()) < single.forces["A"] ** 2
    assert abs(best.detail["place_area_cm2"] - 0.8) <= 0.01
    with pytest.raises(UnreachableTarget, match="nearest mapped area there is"):
        solve_constriction_on(jm, _target(area=2.5, tol=0.01), areas)


@pytest.fixture(scope="module")
def context(small_maps, mesh_file):
    tmp, cfg = small_maps
    voicer = simulator(mesh_file, cfg, voiced=True)
    ctx = add_formants(load_context(tmp / "maps.h5", None, mesh_file), tmp / "maps.h5", mesh_file, cfg)
    return ctx, voicer, cfg


@pytest.mark.parametrize("area, tol", [(0.0, 0.01), (0.3, 0.05)], ids=["closure", "channel"])
def test_a_dorsal_closure_and_channel_are_solved_and_hold_in_simulation(context, tmp_path, area, tol):
    """At the rest jaw the dorsum closes on the hard palate (SG) and narrows it to a channel; the answer,
    refined by simulation, holds there; the tip stays low."""
    ctx, voicer, cfg = context
    t = _target(area=area, tol=tol, name=f"dorsal_{area:g}")
    doc, path, _ = solve_target(t, ctx, tmp_path / "c.yaml", voicer, refine=True, budget=8, config=cfg,
                                mesh_sha256=voicer.mesh_sha256)
    r = doc["refined"]
    assert r["converged"] and abs(r["place_area_cm2"] - area) <= tol, r
    region, names = ctx.places
    simulated = voicer.voice({}, r["forces_n"], ctx.lips_default, ctx.port_default)
    got = float(place_area(np.asarray(simulated["area_function"]["area_cm2"]), region, place_index(names,
                                                                                                 "hard palate")))
    assert abs(got - area) <= tol
    assert simulated["reached_cm"]["dorsum"][1] > simulated["reached_cm"]["tip"][1] + 0.5
    again, _, fresh = solve_target(t, ctx, path, voicer, refine=True, budget=8, config=cfg,
                                   mesh_sha256=voicer.mesh_sha256)
    assert fresh and again["refined"] == r  # written, and found up to date the second time


def test_an_unknown_place_is_one_line_and_exit_2(context, tmp_path, small_maps, mesh_file):
    tmp, cfg = small_maps
    t = tmp_path / "t.yaml"
    t.write_text("name: x\njaw: {forces_n: {}}\nconstriction: {place: ridge, area_cm2: 0}\n")
    res = run_cli("solve-target", t, "--maps", tmp / "maps.h5", "--mesh", mesh_file, "--config", cfg,
                  "--out", tmp_path / "x.yaml", "--acoustic-maps", tmp_path / "none.h5", "--dynamic", tmp_path / "no.h5")
    assert res.exit_code == 2 and "'ridge' is not a place of the tract" in res.output, res.output
    assert len(res.output.strip().splitlines()) == 1 and not (tmp_path / "x.yaml").exists()
