"""The area functions of F frames: shapes and controls in, sections from the glottis to the lips out."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..config import VocalTract
from ..errors import ArticError, OffGrid
from .area_function import AreaFunctions, area_functions, segments
from .band import band_area, band_planes
from .outline import Grid, inner_polylines, moving_parts
from .shapes import Shapes
from .speaker import fixed_geometry


@dataclass
class Tracts:
    """Area functions of F frames with what made them."""

    time_s: np.ndarray
    af: AreaFunctions
    controls: dict[str, np.ndarray]  # lip_area_cm2, lip_length_cm, velum_port_cm2: (F,)
    grid: Grid
    contours: dict[str, np.ndarray]  # moving parts (F, n, 2): tongue, lower_incisor, lower_lip
    fixed: dict[str, np.ndarray] = field(default_factory=dict)  # fixed parts (n, 2)
    band_area_cm2: np.ndarray | None = None  # (F, L) the central band |z| <= band_z_cm[-1] from the 3-D geometry
    band_z_cm: np.ndarray | None = None

    @property
    def n_frames(self) -> int:
        return len(self.time_s)


def tracts_of(vt: VocalTract, cfg_wall, shapes: Shapes, controls: dict[str, np.ndarray]) -> Tracts:
    """The tracts of every frame; a line that misses the tract's contours is an error naming the frame."""
    geo = fixed_geometry(vt, cfg_wall, band_planes(shapes))
    grid = geo.grid
    back = geo.drawn["pharynx"]
    moving = moving_parts(vt, shapes.tongue_cm, shapes.jaw_rotation, shapes.jaw_translation, shapes.root_shift_cm,
                          back)
    inner = segments(inner_polylines(vt, moving))
    outer = geo.outer[0.0]
    law = vt.area_law
    af = area_functions(grid, inner, outer, np.array([r.alpha for r in law]), np.array([r.beta for r in law]),
                        tuple(r.name for r in law), controls["lip_length_cm"], controls["lip_area_cm2"],
                        vt.lip_sections, vt.grid.penetration_cm, moving["tongue"], vt.grid.touch_cm)
    missing_wall = np.flatnonzero(np.isnan(af.wall_s_cm))
    if len(missing_wall):
        k = int(missing_wall[0])
        raise ArticError(f"grid line {k} ({grid.arc_cm[k]:.2f} cm from the glottis) misses the tract's wall; "
                         "move vocal_tract.grid.spine_cm inside the rest tract or raise grid.reach_cm")
    bad = np.argwhere(np.isnan(af.distance_cm))
    if len(bad):
        fr, k = (int(v) for v in bad[0])
        raise OffGrid(f"frame {fr} (t = {shapes.time_s[fr]:.3f} s): the midline cannot be traced, grid line {k} "
                         f"({grid.arc_cm[k]:.2f} cm from the glottis) meets no tongue or larynx within "
                         f"{grid.reach_cm:g} cm; the shape left the grid (raise vocal_tract.grid.reach_cm)")
    band, z = None, None
    if len(geo.outer) > 1:
        band, z = band_area(vt, geo, shapes, af, inner)
    return Tracts(time_s=shapes.time_s, af=af, controls=controls, grid=grid, contours=moving, fixed=dict(geo.drawn),
                  band_area_cm2=band, band_z_cm=z)


def port_positions(tracts: Tracts) -> np.ndarray:
    """Per frame, where the nasal branch joins: the start of the velum region, cm from the glottis."""
    names = list(tracts.af.region_names)
    if "velum" not in names:
        raise ArticError("the vocal tract has no 'velum' region in its area law; name one 'velum' in the config")
    first = int(np.argmax(tracts.af.region == names.index("velum")))
    return tracts.af.length_cm[:, :first].sum(axis=1)
