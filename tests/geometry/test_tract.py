"""The tract's moving inner contour: the larynx front pulled forward by the tongue root."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.geometry.tract import larynx_front


def test_the_epiglottis_follows_the_root_forward_and_the_glottis_stays(cfg):
    vt = cfg.vocal_tract
    base = np.asarray(vt.larynx_front_cm, float)
    shift = np.array([[0.8, 0.3], [-0.6, 0.0], [0.0, 0.0]])  # forward and up, back, none
    out = larynx_front(vt, shift, 3)
    share = vt.larynx_follows_root
    assert share > 0
    assert out[0, -1, 0] - base[-1, 0] == pytest.approx(share * 0.8)  # the tip: the share of the forward move
    np.testing.assert_allclose(out[0, :, 1], base[:, 1])  # heights kept
    np.testing.assert_allclose(out[0, 0], base[0])  # the glottis stays
    moved = out[0, :, 0] - base[:, 0]
    assert (np.diff(moved) >= -1e-12).all()  # more with height
    np.testing.assert_allclose(out[1], base)  # a root moving back pushes nothing (a ligament only pulls)
    np.testing.assert_allclose(out[2], base)


def test_a_share_of_zero_keeps_the_larynx_fixed(cfg):
    vt = cfg.vocal_tract.model_copy(update={"larynx_follows_root": 0.0})
    out = larynx_front(vt, np.array([[1.0, 0.0]]), 1)
    np.testing.assert_allclose(out[0], np.asarray(vt.larynx_front_cm, float))
