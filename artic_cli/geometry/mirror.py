"""Left-right mirror images of a body's nodes in the midsagittal plane z = 0."""

from __future__ import annotations

import numpy as np

from ..errors import ArticError

MIRROR = np.array([1.0, 1.0, -1.0])  # the reflection in the midsagittal plane z = 0, per coordinate
_DIGITS = 9  # coordinates agreeing to 1e-9 cm are the same point


def mirror_images(nodes: np.ndarray, names: dict[str, int]) -> np.ndarray:
    """(N,) index of the node at (x, y, -z) of each node (itself on the plane).

    Named bilateral points pair by name (``*_l`` with ``*_r``: two bone points may share a place), the
    others by position.  A node without an image means the body is not symmetric: an error."""
    image = np.full(len(nodes), -1, dtype=np.int64)
    named = np.zeros(len(nodes), dtype=bool)
    for name, i in names.items():
        side = name[-2:]
        other = name[:-2] + {"_l": "_r", "_r": "_l"}[side] if side in ("_l", "_r") else name
        if other not in names:
            raise ArticError(f"the body is not left-right symmetric: '{name}' has no '{other}'")
        image[i] = names[other]
        named[i] = True
    where = {tuple(p): i for i, p in enumerate(np.round(nodes, _DIGITS).tolist()) if not named[i]}
    for i in np.flatnonzero(~named):
        image[i] = where.get(tuple(np.round(nodes[i] * MIRROR, _DIGITS)), -1)
    bad = np.flatnonzero((image < 0) | (np.abs(nodes[image] * MIRROR - nodes).max(axis=1) > 1e-6))
    if len(bad):
        raise ArticError(f"the body is not left-right symmetric: node {bad[0]} at {np.round(nodes[bad[0]], 3).tolist()} "
                         "cm has no mirror image; set simulation.mirror_symmetry: false")
    return image
