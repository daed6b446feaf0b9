"""Where the tongue is highest in a vowel, and whether the vowels keep the order their inventory entries name
(``tongue_highest``: high / mid / low x front / central / back; docs/inventory.md, "Vowels").

The highest point is the midsagittal surface's highest, refined by a parabola through it and its two
neighbours (the surface has a node per radial line, about 0.5 cm apart).  A vowel named higher than another
must have its highest point higher (cm, y up), one named fronter must have it further forward (x toward the
lips); vowels of the same class are not compared.
"""

from __future__ import annotations

import numpy as np

HEIGHT = {"high": 2, "mid": 1, "low": 0}
FRONTNESS = {"front": 2, "central": 1, "back": 0}


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


def misordered(points: dict[str, np.ndarray], named: dict[str, str]) -> list[str]:
    """Each pair of vowels whose highest points (``points``: vowel -> (x, y) cm) break the order their names
    (``named``: vowel -> e.g. 'high-front') give, said in words; empty when every pair keeps it."""
    out = []
    vowels = [v for v in named if v in points]
    for a in vowels:
        for b in vowels:
            ha, fa = named[a].split("-")
            hb, fb = named[b].split("-")
            if HEIGHT[ha] > HEIGHT[hb] and not points[a][1] > points[b][1]:
                out.append(f"/{a}/ ({ha}) not above /{b}/ ({hb}): {points[a][1]:.2f} vs {points[b][1]:.2f} cm")
            if FRONTNESS[fa] > FRONTNESS[fb] and not points[a][0] > points[b][0]:
                out.append(f"/{a}/ ({fa}) not before /{b}/ ({fb}): {points[a][0]:.2f} vs {points[b][0]:.2f} cm")
    return out


__all__ = ["highest_point", "misordered"]
