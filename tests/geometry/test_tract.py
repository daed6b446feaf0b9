"""The tract's moving inner contour: the larynx front moved by the tongue root."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.geometry.tract import larynx_front

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
