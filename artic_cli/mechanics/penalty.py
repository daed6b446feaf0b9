"""One-sided penalties with a smoothed onset.

A penalty k * depth switched on at depth 0 has a stiffness that jumps from 0
to k there; a node resting at that point (a condyle on its fossa stop) makes
Newton hop on and off the stop and, with the jaw's stiff links, the hops grow.
Over the first ``width`` of depth the force rises quadratically instead:

    F / k = depth^2 / (2 width)        0 <= depth <= width
          = depth - width / 2          beyond,

so force and stiffness are continuous and the term enters Newton's matrix
with a weight that starts at zero.
"""

from __future__ import annotations

import numpy as np


def ramp(depth: np.ndarray, width: float) -> tuple[np.ndarray, np.ndarray]:
    """Force per unit stiffness and its slope d/d depth for ``depth`` (cm, <= 0 means free)."""
    d = np.maximum(depth, 0.0)
    if width <= 0.0:
        return d, (depth > 0).astype(float)
    inside = d < width
    return np.where(inside, d * d / (2.0 * width), d - 0.5 * width), np.where(inside, d / width, 1.0)
