"""Where the tongue is highest in a vowel, and whether the vowels keep the order their inventory entries name
(``tongue_highest``: high / mid / low x front / central / back; docs/inventory.md, "Vowels").

The highest point is :func:`..tract.tongue_top.highest_point`'s.  A vowel named higher than another
must have its highest point higher (cm, y up), one named fronter must have it further forward (x toward the
lips); vowels of the same class are not compared.
"""

from __future__ import annotations

import numpy as np

from ..tract.tongue_top import highest_point

HEIGHT = {"high": 2, "mid": 1, "low": 0}
FRONTNESS = {"front": 2, "central": 1, "back": 0}


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


__all__ = ["misordered"]
