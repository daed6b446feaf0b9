"""Where the tongue is highest: the midsagittal surface's highest point, refined by a parabola through it and
its two neighbours (the surface has a node per radial line, about 0.5 cm apart), x toward the lips, y up (cm)."""

from __future__ import annotations

import numpy as np


def highest_point(surface_cm: np.ndarray) -> np.ndarray:
    """(2,) the highest point (x, y cm) of a midsagittal tongue surface (n, 2), tip first."""
    s = np.asarray(surface_cm, float)
    k = int(np.argmax(s[:, 1]))
    if 0 < k < len(s) - 1:
        y0, y1, y2 = s[k - 1, 1], s[k, 1], s[k + 1, 1]
        bend = y0 - 2.0 * y1 + y2
        if bend < 0:
            u = 0.5 * (y0 - y2) / bend  # the parabola's vertex, in node steps from k (within +-0.5)
            side = k + 1 if u > 0 else k - 1
            a = abs(u)
            return np.array([(1 - a) * s[k, 0] + a * s[side, 0], y1 - 0.25 * (y0 - y2) * u])
    return s[k].copy()


def highest_points(shapes_cm: np.ndarray, surface: np.ndarray) -> np.ndarray:
    """(..., 2) the highest point of every shape (..., N, 3) whose midsagittal surface nodes are ``surface``."""
    s = np.asarray(shapes_cm, float)
    flat = s.reshape(-1, *s.shape[-2:])[:, surface, :2]
    return np.array([highest_point(x) for x in flat]).reshape(*s.shape[:-2], 2)


__all__ = ["highest_point", "highest_points"]
