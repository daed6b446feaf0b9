"""The tract's contours: the larynx front moved by the tongue root; the outer wall the contact wall's own."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.tract.area_function import point_segment_distance
from artic_cli.tract.outline import larynx_front, outer_contour

WALL = np.array([[-7.8, 0.0], [-7.6, -5.0], [-7.2, -8.0], [-7.15, -8.3]])  # posterior wall, top to bottom


def test_the_epiglottis_follows_the_root_and_the_glottis_stays(cfg):
    vt = cfg.vocal_tract
    base = np.asarray(vt.larynx_front_cm, float)
    shift = np.array([[0.8, 0.3], [-0.3, 0.0], [0.0, 0.0]])  # forward and up, a little back, none
    out = larynx_front(vt, shift, 3, WALL)
    share = vt.larynx_follows_root
    assert share > 0
    assert out[0, -1, 0] - base[-1, 0] == pytest.approx(share * 0.8)  # the tip: the share of the root's move
    assert out[1, -1, 0] - base[-1, 0] == pytest.approx(share * -0.3)
    for k in range(3):
        np.testing.assert_allclose(out[k, :, 1], base[:, 1])  # heights kept
        np.testing.assert_allclose(out[k, 0], base[0])  # the glottis stays
    moved = out[0, :, 0] - base[:, 0]
    assert (np.diff(moved) >= -1e-12).all()  # more with height
    np.testing.assert_allclose(out[2], base)


def test_pushed_back_the_larynx_stops_short_of_the_posterior_wall(cfg):
    vt = cfg.vocal_tract
    base = np.asarray(vt.larynx_front_cm, float)
    out = larynx_front(vt, np.array([[-3.0, 0.0]]), 1, WALL)[0]
    wall_x = np.interp(base[:, 1], WALL[::-1, 1], WALL[::-1, 0])
    gap = out[:, 0] - wall_x
    assert gap.min() >= min(vt.larynx_wall_gap_cm, (base[:, 0] - wall_x).min()) - 1e-9
    assert gap[-1] == pytest.approx(vt.larynx_wall_gap_cm)  # the tip, pushed furthest, stops at the gap
    assert (out[:, 0] <= base[:, 0] + 1e-12).all()


def test_a_share_of_zero_keeps_the_larynx_fixed(cfg):
    vt = cfg.vocal_tract.model_copy(update={"larynx_follows_root": 0.0})
    out = larynx_front(vt, np.array([[1.0, 0.0]]), 1, WALL)
    np.testing.assert_allclose(out[0], np.asarray(vt.larynx_front_cm, float))


def test_the_tract_s_palate_and_pharynx_are_the_contact_wall_s_midsagittal_section(cfg):
    """A tongue node resting on the contact wall lies on the tract's outer contour: the contact wall's
    triangles in the midsagittal plane (their edges along the z = 0 slice) are the outline's segments, and the
    hard palate and velum meet at one point."""
    from artic_cli.geometry.wall import PARTS, wall_surface

    wall = wall_surface(cfg.speaker.wall)
    skull = np.unique(wall.triangles[np.isin(wall.part, [PARTS.index("palate"), PARTS.index("pharynx")])])
    out = outer_contour(cfg.vocal_tract, cfg.speaker.wall)
    segs = np.concatenate([np.stack([p[:-1], p[1:]], axis=1) for p in out.values() if len(p) > 1])
    mid = skull[np.abs(wall.vertices[skull, 2]) < 1e-12]
    assert len(mid) >= 2 * cfg.speaker.wall.points_per_outline
    d = point_segment_distance(wall.vertices[mid, :2][None], segs)[0]
    assert d.max() < 1e-9
    # ... and the other way: the outline's corners lie on the wall's midsagittal edges (the config's own
    # polylines have corners that the wall's resampled slices cut by up to 0.03 cm)
    tri = wall.triangles[np.isin(wall.part, [PARTS.index("palate"), PARTS.index("pharynx")])]
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    flat = edges[(np.abs(wall.vertices[edges, 2]) < 1e-12).all(axis=1)]
    wall_segs = wall.vertices[flat][:, :, :2]
    corners = np.concatenate([out[k] for k in ("hard_palate", "velum")] + [out["pharynx"][:-len(
        cfg.vocal_tract.pharynx_lower_cm)]])
    assert point_segment_distance(corners[None], wall_segs)[0].max() < 1e-9
    np.testing.assert_allclose(out["hard_palate"][-1], out["velum"][0])
    assert out["hard_palate"][-1, 0] == pytest.approx(cfg.vocal_tract.hard_palate_end_x_cm)
