"""A voiced closure's active cavity enlargement, timed to the closure the model made.

Speakers keep voicing through a voiced stop's closure by enlarging the cavity behind it,
lowering the larynx and advancing the tongue root (Kent & Moll 1969; Westbury 1983): without it the cavity
fills, the transglottal pressure falls below the phonation threshold and the voice dies within a few tens of
ms.  A segment asks for it with ``cavity_expansion_cm3_s`` (the inventory gives voiced stops, affricates and taps
``realisation.voiced_stop_expansion_cm3_s``; a fricative's channel vents the cavity, its voice needs none);
the enlargement runs over the stretch of frames where the tract is closed around the segment's interval (the
articulators' own timing, not the interval's), and the volume is given back after the release.
"""

from __future__ import annotations

import numpy as np

from ..acoustics.measures import runs
from ..schedule import TractEntry

CLOSED_CM2 = 0.03  # a narrowest area under this is a closure (a fricative's channel, wider, vents the cavity)
GIVE_BACK_MS = 150.0  # the larynx rising again over the vowel after the release (a fast give-back would blow
# its volume out of the opening as a second burst)
MAX_CM3 = 10.0  # a larynx 5 mm lower under a 3-cm^2 pharynx (1.5 cm^3), a tongue root 5 mm forward over a
# 3 x 5 cm pharyngeal wall (7.5), the cheeks and velum (1)
REACH_MS = 60.0  # a constriction starting or ending this far outside the interval still belongs to it


def expansion_entries(segments, starts_s: np.ndarray, time_s: np.ndarray, narrowest_cm2: np.ndarray
                      ) -> list[TractEntry]:
    """The tract entries of every segment asking for an enlargement (its continuing parts one phone with it):
    from the closure's first frame (the narrowest under :data:`CLOSED_CM2`) the volume grows at the rate
    up to :data:`MAX_CM3`, holds to the release and shrinks back over :data:`GIVE_BACK_MS` after."""
    t_ms = np.asarray(time_s, float) * 1e3
    a_min = np.asarray(narrowest_cm2, float)
    closed = [(a, b - 1) for a, b in runs(a_min < CLOSED_CM2)]  # first and last frame
    out: list[TractEntry] = []
    k, n = 0, len(segments)
    while k < n:
        j = k + 1
        while j < n and segments[j].continues:
            j += 1
        rate = segments[k].cavity_expansion_cm3_s
        if rate and closed:
            a = float(starts_s[k]) * 1e3
            b = float(starts_s[j - 1]) * 1e3 + segments[j - 1].duration_ms
            overlap = [min(b + REACH_MS, t_ms[r1]) - max(a - REACH_MS, t_ms[r0]) for r0, r1 in closed]
            best = int(np.argmax(overlap))
            if overlap[best] > 0:
                c0, c1 = t_ms[closed[best][0]], t_ms[closed[best][1]]
                grow_ms = min(c1 - c0, MAX_CM3 / rate * 1e3)
                out.append(TractEntry(at_ms=c0, ramp_ms=grow_ms, ramp="linear",
                                      cavity_expansion_cm3=rate * grow_ms / 1e3))
                out.append(TractEntry(at_ms=c1, ramp_ms=GIVE_BACK_MS, cavity_expansion_cm3=0.0))
        k = j
    return out
