"""The central band of the tract: the cross-section the tongue mesh spans (|z| <= its lateral plane)."""

from __future__ import annotations

import numpy as np

from ..config import VocalTract
from .area_function import AreaFunctions, band_areas, segments
from .outline import inner_polylines, moving_parts
from .shapes import Shapes
from .speaker import Fixed


def band_planes(shapes: Shapes) -> tuple[float, ...]:
    """The planes the band is integrated over: midsagittal, half-way, the tongue's lateral plane (cm)."""
    w = shapes.lateral_z_cm
    return (0.0, 0.5 * w, w) if shapes.tongue_lateral_cm is not None and w > 0 else (0.0,)


def band_area(vt: VocalTract, geo: Fixed, shapes: Shapes, af: AreaFunctions, inner_mid: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """The cross-section of the band the tongue mesh spans (|z| <= its lateral planes) from the 3-D geometry:
    distances in the midsagittal plane (``inner_mid``: its inner segments, already built), half-way and in the
    lateral plane, integrated across."""
    z = np.array(list(geo.outer))
    side = [0.5 * (shapes.tongue_cm + shapes.tongue_lateral_cm), shapes.tongue_lateral_cm]
    inners = [inner_mid] + [segments(inner_polylines(vt, moving_parts(vt, tongue, shapes.jaw_rotation,
                                                                      shapes.jaw_translation, shapes.root_shift_cm,
                                                                      geo.drawn["pharynx"])))
                            for tongue in side]
    return band_areas(geo.grid, inners, list(geo.outer.values()), z, af.inner_s_cm, af.wall_s_cm), z
