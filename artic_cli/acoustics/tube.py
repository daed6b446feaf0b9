"""A tube: the vocal tract as concatenated cylindrical sections, glottis to lips (cm, cm^2)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ArticError
from ..validation import AreaCm2, LengthCm, Strict, read_csv


@dataclass(frozen=True)
class Tube:
    length_cm: np.ndarray  # (n,) each section's length
    area_cm2: np.ndarray  # (n,) each section's cross-sectional area (0: a closure)

    @property
    def total_length_cm(self) -> float:
        return float(self.length_cm.sum())


def uniform(length_cm: float, area_cm2: float, sections: int = 40) -> Tube:
    return Tube(np.full(sections, length_cm / sections), np.full(sections, float(area_cm2)))


def from_pieces(*pieces: tuple[float, float], sections_per_cm: float = 2.0) -> Tube:
    """Tubes of (length cm, area cm^2) one after another, glottis first, each cut into equal sections."""
    lengths, areas = [], []
    for length, area in pieces:
        n = max(1, int(round(length * sections_per_cm)))
        lengths += [length / n] * n
        areas += [area] * n
    return Tube(np.array(lengths), np.array(areas))


class _Row(Strict):
    length_cm: LengthCm
    area_cm2: AreaCm2


def read_tube_csv(path: Path | str) -> Tube:
    """A tube file: header ``length_cm,area_cm2``, one row per section from the glottis to the lips."""
    hint = "give a CSV with header length_cm,area_cm2 and one row per section, glottis first"
    rows = read_csv(path, ["length_cm", "area_cm2"], _Row, "tube file", hint)
    if len(rows) < 2:
        raise ArticError(f"{path}: a tube needs at least two sections, got {len(rows)}; {hint}")
    return Tube(np.array([r.length_cm for r in rows]), np.array([r.area_cm2 for r in rows]))
