"""The speaker's tract: the config's ``vocal_tract`` section and the geometry of it that does not move."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import Config, VocalTract
from ..errors import ArticError
from .area_function import segments
from .outline import Grid, outer_at, outer_contour, tract_grid

TRACT_SECTIONS = ("speaker", "vocal_tract")  # what a simulation's tracts read of the config


def speaker_tract(cfg: Config) -> VocalTract:
    """The config's vocal tract; a one-line error when the config has none."""
    vt = cfg.vocal_tract
    if vt is None:
        raise ArticError("the config has no 'vocal_tract' section; add one (see configs/default.yaml)")
    return vt


@dataclass(frozen=True)
class Fixed:
    """What does not move: the grid and the outer contour's segments in each plane (cm)."""

    grid: Grid
    outer: dict[float, np.ndarray]  # z -> (S, 2, 2)
    drawn: dict[str, np.ndarray]


_FIXED: dict[tuple, tuple] = {}


def fixed_geometry(vt: VocalTract, cfg_wall, planes_z: tuple[float, ...] = (0.0,)) -> Fixed:
    """The fixed geometry, built once per tract, wall and set of planes (the config objects are kept with
    it, so their ids stay theirs)."""
    key = (id(vt), id(cfg_wall), tuple(planes_z))
    if key not in _FIXED:
        fixed = outer_contour(vt, cfg_wall)
        drawn = dict(fixed, upper_lip=np.asarray(vt.upper_lip_cm, float),
                     velum_nasal=np.asarray(vt.velum_nasal_surface_cm, float))
        outer = {float(z): segments(list(outer_at(vt, cfg_wall, float(z)))) for z in planes_z}
        if len(_FIXED) > 8:
            _FIXED.clear()
        _FIXED[key] = (Fixed(grid=tract_grid(vt), outer=outer, drawn=drawn), vt, cfg_wall)
    return _FIXED[key][0]
