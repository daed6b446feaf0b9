"""Area functions from contours: distances on grid lines, power laws, section lengths, closures."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.tract.area_function import area_functions, segments, touched_lines
from artic_cli.config import AreaRegion
from artic_cli.tract.outline import tract_grid
from artic_cli.schedule import TractEntry, tract_controls


def _channel_tract(cfg, regions, spine=((0.0, 0.0), (3.0, 0.0), (7.0, 0.0))):
    vt = cfg.vocal_tract
    return vt.model_copy(update={"grid": vt.grid.model_copy(update={"spine_cm": [list(p) for p in spine]}),
                                 "area_law": regions})


def _run(vt, inner, outer, lip_area=2.0, lip_length=1.0):
    grid = tract_grid(vt)
    law = vt.area_law
    return grid, area_functions(grid, segments(inner)[None], segments(outer), np.array([r.alpha for r in law]),
                                np.array([r.beta for r in law]), tuple(r.name for r in law), np.array([lip_length]),
                                np.array([lip_area]), vt.lip_sections, vt.grid.penetration_cm)


def test_a_straight_channel_gives_the_power_law_exactly_and_its_length(cfg):
    vt = _channel_tract(cfg, [AreaRegion(name="all", until_cm=99.0, alpha=1.7, beta=1.3)])
    inner = [np.array([[-1.0, -0.3], [8.0, -0.3]])]
    outer = [np.array([[-1.0, 0.5], [8.0, 0.5]])]
    grid, af = _run(vt, inner, outer)
    n = grid.n_lines
    assert n == int(np.ceil(7.0 / vt.grid.spacing_cm)) + 1
    np.testing.assert_allclose(af.distance_cm[0], 0.8, atol=1e-12)
    np.testing.assert_allclose(af.area_cm2[0, :n], 1.7 * 0.8 ** 1.3, rtol=1e-12)
    assert af.length_cm[0, :n].sum() == pytest.approx(7.0, abs=1e-9)
    assert af.tract_length_cm[0] == pytest.approx(8.0, abs=1e-9)  # plus the 1-cm lip tube
    np.testing.assert_allclose(af.area_cm2[0, n:], 2.0)


def test_regions_use_their_own_coefficients(cfg):
    vt = _channel_tract(cfg, [AreaRegion(name="back", until_cm=3.0, alpha=1.0, beta=1.0),
                              AreaRegion(name="front", until_cm=99.0, alpha=3.0, beta=2.0)])
    grid, af = _run(vt, [np.array([[-1.0, -0.5], [8.0, -0.5]])], [np.array([[-1.0, 0.5], [8.0, 0.5]])])
    back = grid.arc_cm <= 3.0
    np.testing.assert_allclose(af.area_cm2[0, :grid.n_lines][back], 1.0)
    np.testing.assert_allclose(af.area_cm2[0, :grid.n_lines][~back], 3.0)


def test_a_tongue_through_the_wall_reads_a_closure_and_a_missing_contour_reads_nan(cfg):
    vt = _channel_tract(cfg, [AreaRegion(name="all", until_cm=99.0, alpha=1.7, beta=1.3)])
    # the inner contour rises through the wall between x = 3 and 4, and stops at x = 6
    inner = [np.array([[-1.0, -0.3], [3.0, -0.3], [3.2, 0.6], [3.8, 0.6], [4.0, -0.3], [6.0, -0.3]])]
    grid, af = _run(vt, inner, [np.array([[-1.0, 0.5], [8.0, 0.5]])])
    x = grid.origin[:, 0]
    assert (af.area_cm2[0, :grid.n_lines][(x > 3.25) & (x < 3.75)] == 0.0).all()
    assert np.isnan(af.distance_cm[0][x > 6.05]).all()
    assert np.isfinite(af.distance_cm[0][x < 2.9]).all()


def test_tract_controls_follow_a_smooth_ramp():
    start = {"lip_area_cm2": 3.0, "lip_length_cm": 1.0, "velum_port_cm2": 0.0, "glottis_cm2": 0.05}
    t = np.linspace(0.0, 0.3, 301)
    c = tract_controls([TractEntry(at_ms=100, ramp_ms=60, lip_area_cm2=0.5),
                        TractEntry(at_ms=200, ramp_ms=20, glottis_cm2=0.3)], start, t)
    a = c["lip_area_cm2"]
    assert (a[t < 0.1] == 3.0).all() and (a[t >= 0.16] == pytest.approx(0.5))
    assert a[np.argmin(abs(t - 0.13))] == pytest.approx(1.75, abs=1e-9)  # half-way at half the ramp
    assert (np.diff(a) <= 1e-12).all()  # monotone, no overshoot
    assert (c["velum_port_cm2"] == 0.0).all() and (c["lip_length_cm"] == 1.0).all()
    g = c["glottis_cm2"]  # the glottis is a control like the others: held, then ramped to its new opening
    assert (g[t < 0.2] == 0.05).all() and g[np.argmin(abs(t - 0.21))] == pytest.approx(0.175) and g[-1] == 0.3


def test_the_band_area_of_a_uniform_slab_is_its_width_times_its_depth(cfg):
    from artic_cli.tract.area_function import band_areas

    vt = _channel_tract(cfg, [AreaRegion(name="all", until_cm=99.0, alpha=1.7, beta=1.3)])
    inner = [np.array([[-1.0, -0.3], [8.0, -0.3]])]
    outer = [np.array([[-1.0, 0.5], [8.0, 0.5]])]
    grid, af = _run(vt, inner, outer)
    # the same channel in every plane, the lateral wall 0.2 cm lower: depth 0.8 in the middle, 0.6 at the side
    side = [np.array([[-1.0, 0.3], [8.0, 0.3]])]
    planes = [segments(inner)[None]] * 3
    outers = [segments(outer), segments([(outer[0] + side[0]) / 2]), segments(side)]
    band = band_areas(grid, planes, outers, np.array([0.0, 0.5, 1.0]), af.inner_s_cm, af.wall_s_cm)
    np.testing.assert_allclose(band, 2 * (0.25 * 0.8 + 0.5 * 0.7 + 0.25 * 0.6), rtol=1e-12)


def test_a_node_on_the_wall_between_two_lines_closes_both_and_one_below_it_does_not(cfg):
    """Contact is a point: a tongue node on the wall half-way between two grid lines, the chords to its
    neighbours 0.3 cm below, leaves both lines open by their crossings; the touch rule closes them."""
    vt = _channel_tract(cfg, [AreaRegion(name="all", until_cm=99.0, alpha=1.7, beta=1.3)])
    grid = tract_grid(vt)
    x = grid.origin[:, 0]
    mid = 0.5 * (x[10] + x[11])
    outer = [np.array([[-1.0, 0.5], [8.0, 0.5]])]
    law = vt.area_law
    for gap, closed in ((0.0, True), (0.005, True), (0.05, False)):
        node = np.array([mid, 0.5 - gap])
        inner = [np.array([[-1.0, 0.2], [mid - 1.0, 0.2], node, [mid + 1.0, 0.2], [8.0, 0.2]])]
        af = area_functions(grid, segments(inner)[None], segments(outer), np.array([r.alpha for r in law]),
                            np.array([r.beta for r in law]), tuple(r.name for r in law), np.array([1.0]),
                            np.array([2.0]), vt.lip_sections, vt.grid.penetration_cm, node[None, None], 0.01)
        d = af.distance_cm[0]
        assert (d[[10, 11]] == 0.0).all() == closed, (gap, d[[10, 11]])
        far = np.abs(x - mid) > 1.0
        np.testing.assert_allclose(d[far], 0.3)  # nothing else closes: the chords' lines read their gap
        assert (d[~far & (np.abs(x - mid) > 0.3)] > 0.0).all()
        if not closed:
            assert (d[[10, 11]] > gap).all()
    # without the rule the lines read the chords' gap however close the node
    plain = touched_lines(grid, np.array([[[mid, 0.5]]]), segments(outer), 0.0)
    assert not plain.any()
