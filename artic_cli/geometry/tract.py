"""The midsagittal vocal tract: its inner and outer contours, and the grid lines across it.

The outer contour is fixed in the head frame: the lower posterior pharyngeal wall, the contact wall's
midsagittal pharynx and palate (velum included), the upper incisor.  The inner contour moves: the larynx
front and the epiglottis (fixed), the tongue's midsagittal surface from the root to the tip, a bridge from
the tip to the lower incisor edge, and the lower incisor, which with the lower lip moves with the mandible.

The grid is fixed too: lines normal to a smoothed reference midline (the spine, glottis to incisors) in the
manner of Maeda's grid, so every frame of a simulation has the same sections, and the distances along
each line are what the area function turns into areas.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import VocalTract, WallGeometry
from .mesh import resample_polyline


@dataclass(frozen=True)
class Grid:
    """Grid lines p(s) = origin + s * normal, s in [-reach, reach] cm; s > 0 toward the outer wall."""

    origin: np.ndarray  # (L, 2) cm, on the spine, glottis first
    normal: np.ndarray  # (L, 2) unit
    arc_cm: np.ndarray  # (L,) along the spine from the glottis
    region: np.ndarray  # (L,) index into the area law's regions
    reach_cm: float

    @property
    def n_lines(self) -> int:
        return len(self.origin)


def _arc(p: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])


def tract_grid(vt: VocalTract) -> Grid:
    """Lines at most ``spacing_cm`` apart along the spine, normal to its tangent smoothed over
    ``smoothing_cm`` of arc."""
    g = vt.grid
    spine = np.asarray(g.spine_cm, dtype=float)
    total = _arc(spine)[-1]
    fine_step = 0.02
    fine = resample_polyline(spine, max(int(np.ceil(total / fine_step)) + 1, 3))
    tangent = np.gradient(fine, axis=0)
    half = int(round(0.5 * g.smoothing_cm / (total / (len(fine) - 1))))
    if half > 0:
        kernel = np.ones(2 * half + 1)
        padded = np.pad(tangent, ((half, half), (0, 0)), mode="edge")
        tangent = np.stack([np.convolve(padded[:, k], kernel, mode="valid") for k in range(2)], axis=1)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    n = int(np.ceil(total / g.spacing_cm)) + 1
    arc = np.linspace(0.0, total, n)
    fine_arc = _arc(fine)
    origin = np.stack([np.interp(arc, fine_arc, fine[:, k]) for k in range(2)], axis=1)
    t = np.stack([np.interp(arc, fine_arc, tangent[:, k]) for k in range(2)], axis=1)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    normal = np.stack([-t[:, 1], t[:, 0]], axis=1)  # counter-clockwise: the back wall going up, the palate going forward
    ends = np.array([r.until_cm for r in vt.area_law])
    region = np.minimum(np.searchsorted(ends, arc, side="left"), len(ends) - 1)
    return Grid(origin=origin, normal=normal, arc_cm=arc, region=region, reach_cm=float(g.reach_cm))


def apply_rigid(points: np.ndarray, rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """Midsagittal points (n, 2) moved by a rigid motion of 3-D space (R (3,3), t (3,)), taken at z = 0."""
    p = np.column_stack([points, np.zeros(len(points))])
    return (p @ rotation.T + translation)[:, :2]


@dataclass(frozen=True)
class Outline:
    """The tract's contours in one frame (cm): polylines, each (n, 2)."""

    inner: tuple[np.ndarray, ...]
    outer: tuple[np.ndarray, ...]
    drawn: dict  # every part by name, for figures


def outer_contour(vt: VocalTract, wall: WallGeometry) -> dict[str, np.ndarray]:
    """The fixed outer parts: lower pharyngeal wall, the contact wall's midsagittal pharynx, velum and hard
    palate, the velopharyngeal port's line (the oral tract's top behind the velum), the upper incisor."""
    mid = min(wall.slices, key=lambda s: s.z_cm)
    palate = np.asarray(mid.palate, dtype=float)
    hard = palate[palate[:, 0] >= vt.hard_palate_end_x_cm]
    soft = palate[palate[:, 0] <= vt.hard_palate_end_x_cm]
    return {"pharynx": np.vstack([np.asarray(mid.pharynx, float), np.asarray(vt.pharynx_lower_cm, float)]),
            "velum": soft, "port": np.asarray(vt.velum_port_line_cm, float), "hard_palate": hard, "upper_incisor": np.asarray(vt.upper_incisor_cm, float)}


def outline(vt: VocalTract, wall: WallGeometry, tongue_cm: np.ndarray, jaw: tuple[np.ndarray, np.ndarray]
            ) -> Outline:
    """The contours of one frame from the tongue's midsagittal surface (tip first, (n, 2) cm) and the
    mandible's rigid motion from its rest (R, t)."""
    fixed = outer_contour(vt, wall)
    lower_incisor = apply_rigid(np.asarray(vt.lower_incisor_cm, float), *jaw)
    lower_lip = apply_rigid(np.asarray(vt.lower_lip_cm, float), *jaw)
    larynx = np.asarray(vt.larynx_front_cm, float)
    tongue = np.asarray(tongue_cm, float)[::-1]  # root to tip
    bridge = np.vstack([tongue[-1], lower_incisor[0]])
    drawn = dict(fixed, larynx_front=larynx, tongue=tongue, lower_incisor=lower_incisor, lower_lip=lower_lip,
                 upper_lip=np.asarray(vt.upper_lip_cm, float),
                 velum_nasal=np.asarray(vt.velum_nasal_surface_cm, float))
    return Outline(inner=(larynx, tongue, bridge, lower_incisor), outer=tuple(fixed.values()), drawn=drawn)
