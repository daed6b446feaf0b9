"""The places of the tract: the regions of its area law (larynx ... alveolar) and the lips, each a run of the
area function's sections; a place's area is its narrowest section's."""

from __future__ import annotations

import numpy as np

from ..config import VocalTract
from ..errors import ArticError
from .outline import tract_grid


def section_places(vt: VocalTract) -> tuple[np.ndarray, tuple[str, ...]]:
    """(S,) each area-function section's place index, glottis first, the lip tube last; the places' names."""
    names = tuple(r.name for r in vt.area_law) + ("lips",)
    region = np.concatenate([tract_grid(vt).region, np.full(vt.lip_sections, len(names) - 1)])
    return region.astype(int), names


def place_index(names: tuple[str, ...], place: str, source: str = "constriction.place") -> int:
    if place not in names:
        raise ArticError(f"{source}: '{place}' is not a place of the tract; places: {', '.join(names)}")
    return names.index(place)


def place_area(area_cm2: np.ndarray, region: np.ndarray, index: int) -> np.ndarray:
    """(...) the narrowest area (cm^2) among the sections of place ``index`` of areas (..., S)."""
    a = np.asarray(area_cm2, float)
    if a.shape[-1] != len(region):
        raise ArticError(f"an area function of {a.shape[-1]} sections does not fit the tract's {len(region)} "
                         "(other vocal-tract grid or lip sections); rebuild the acoustic maps")
    return a[..., region == index].min(axis=-1)
