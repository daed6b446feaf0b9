"""The muscle routing: bilateral muscles stay on their own side."""

from __future__ import annotations

import numpy as np
import pytest

from artic_cli.geometry.anatomy import build_body


@pytest.mark.parametrize("muscle", ["SG", "HG", "IL", "MH", "GH", "posterior_digastric", "masseter"])
def test_a_bilateral_muscle_never_crosses_the_midline(cfg, muscle):
    body = build_body(cfg)
    sides = []
    for fibre in body.fibres[muscle]:
        z = body.nodes[fibre, 2]
        off = z[np.abs(z) > 1e-9]  # midsagittal nodes (MH's and GH's tongue ends) belong to both sides
        assert len(off) and (np.all(off > 0) or np.all(off < 0)), (muscle, z)
        sides.append(np.sign(off[0]))
    assert sides.count(1.0) == sides.count(-1.0)  # as many fibres left as right
