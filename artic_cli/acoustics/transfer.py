"""The volume-velocity transfer function U_lips / U_glottis of a tube with optional side branches, and the
radiated pressure spectrum.

The glottis is an ideal flow source (the tract's far end seen from the lips: no glottal load); a branch joins
the tube at its distance from the glottis (a section there is cut in two).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .chain import Air, chain, input_impedance, radiation_impedance, shunt
from .tube import Tube


@dataclass(frozen=True)
class Branch:
    """A side tube from a junction ``at_cm`` above the glottis: sections from the junction outward, ending
    closed (the piriform fossae) or radiating through its last area (the nostrils); ``count`` alike."""

    at_cm: float
    tube: Tube
    radiating: bool = False
    count: int = 1
    branches: tuple = ()  # its own side branches (the paranasal sinuses on the nasal tract), at_cm along it


@dataclass
class Tract:
    tube: Tube
    branches: list[Branch] = field(default_factory=list)
    _plan: tuple | None = field(default=None, init=False, repr=False, compare=False)  # split tube, cuts

    def plan(self) -> tuple:
        """The tube cut at the branches' junctions and where each branch joins (computed once)."""
        if self._plan is None:
            t = split_at(self.tube, [b.at_cm for b in self.branches])
            edges = np.concatenate([[0.0], np.cumsum(t.length_cm)])
            cut = sorted((int(np.argmin(np.abs(edges - b.at_cm))), j) for j, b in enumerate(self.branches))
            self._plan = (t, cut)
        return self._plan


def _branch_admittance(b: Branch, w: np.ndarray, air: Air) -> np.ndarray:
    k = tract_chain(Tract(b.tube, list(b.branches)), w, air) if b.branches else \
        chain(b.tube.length_cm, b.tube.area_cm2, w, air)
    load = radiation_impedance(b.tube.area_cm2[-1], w, air) if b.radiating else None
    return b.count / input_impedance(k, load)


def split_at(tube: Tube, points_cm) -> Tube:
    """The same tube with section boundaries at ``points_cm`` from the glottis (a section is cut in two)."""
    lengths, areas = list(tube.length_cm), list(tube.area_cm2)
    for p in sorted(points_cm):
        edges = np.concatenate([[0.0], np.cumsum(lengths)])
        k = int(np.searchsorted(edges, p)) - 1
        if 0 <= k < len(lengths) and 1e-9 < p - edges[k] < lengths[k] - 1e-9:
            first = p - edges[k]
            lengths[k:k + 1] = [first, lengths[k] - first]
            areas[k:k + 1] = [areas[k], areas[k]]
    return Tube(np.array(lengths), np.array(areas))


def tract_chain(tract: Tract, w: np.ndarray, air: Air) -> np.ndarray:
    """(F, 2, 2) glottis-to-lips chain matrix with the branches' shunts."""
    t, cut = tract.plan()
    total = None
    start = 0
    for idx, j in cut + [(len(t.length_cm), None)]:
        if idx > start:
            k = chain(t.length_cm[start:idx], t.area_cm2[start:idx], w, air)
            total = k if total is None else total @ k
            start = idx
        if j is not None:
            s = shunt(_branch_admittance(tract.branches[j], w, air))
            total = s if total is None else total @ s
    return total


def transfer(tract: Tract, f_hz: np.ndarray, air: Air) -> np.ndarray:
    """(F,) complex U_lips / U_glottis at ``f_hz``."""
    w = 2.0 * np.pi * np.maximum(np.asarray(f_hz, dtype=float), 1e-3)
    k = tract_chain(tract, w, air)
    z_lips = radiation_impedance(tract.tube.area_cm2[-1], w, air)
    return 1.0 / (k[:, 1, 0] * z_lips + k[:, 1, 1])


def radiated_pressure(h: np.ndarray, f_hz: np.ndarray, air: Air, distance_cm: float = 100.0) -> np.ndarray:
    """(F,) far-field pressure per unit glottal flow: j w rho H / (4 pi r) (a simple source at the lips)."""
    w = 2.0 * np.pi * np.asarray(f_hz, dtype=float)
    return 1j * w * air.rho * h / (4.0 * np.pi * distance_cm)


def _chain_between(tract: Tract, w: np.ndarray, air: Air, first: int, last: int, skip: int | None) -> np.ndarray:
    """(F, 2, 2) the split tube's sections ``first:last`` with the shunts of the branches on them (the
    branch ``skip`` left out)."""
    t, cut = tract.plan()
    total = np.broadcast_to(np.eye(2, dtype=complex), (len(w), 2, 2)).copy()
    start = first
    for idx, j in [c for c in cut if first <= c[0] <= last] + [(last, None)]:
        if idx > start:
            total = total @ chain(t.length_cm[start:idx], t.area_cm2[start:idx], w, air)
            start = idx
        if j is not None and j != skip and idx < last:
            total = total @ shunt(_branch_admittance(tract.branches[j], w, air))
    return total


def nostril_transfer(tract: Tract, f_hz: np.ndarray, air: Air) -> np.ndarray:
    """(F,) complex U_nostrils / U_glottis: the volume velocity out of the radiating branch (the nasal tract)
    per unit glottal flow; zeros when the tract has none.  The lips' and the nostrils' flows add in the
    sound (:func:`radiated_pressure` of their sum)."""
    w = 2.0 * np.pi * np.maximum(np.asarray(f_hz, dtype=float), 1e-3)
    nasal = [j for j, b in enumerate(tract.branches) if b.radiating]
    if not nasal:
        return np.zeros(len(w), dtype=complex)
    j = nasal[0]
    t, cut = tract.plan()
    at = next(idx for idx, k in cut if k == j)
    before = _chain_between(tract, w, air, 0, at, j)  # glottis to the port
    after = _chain_between(tract, w, air, at, len(t.length_cm), j)  # the port to the lips
    b = tract.branches[j]
    y_nose = _branch_admittance(b, w, air)
    y_j = 1.0 / input_impedance(after, radiation_impedance(tract.tube.area_cm2[-1], w, air)) + y_nose
    p_j = 1.0 / (before[:, 1, 0] + before[:, 1, 1] * y_j)  # per unit glottal flow
    k_n = tract_chain(Tract(b.tube, list(b.branches)), w, air) if b.branches else \
        chain(b.tube.length_cm, b.tube.area_cm2, w, air)
    z_n = radiation_impedance(b.tube.area_cm2[-1], w, air)
    return p_j * y_nose / (k_n[:, 1, 0] * z_n + k_n[:, 1, 1])
