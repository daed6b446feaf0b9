"""The midsagittal vocal tract: its inner and outer contours, and the grid lines across it.

The outer contour is fixed in the head frame: the lower posterior pharyngeal wall, the contact wall's
midsagittal pharynx and palate (velum included), the upper incisor.  The inner contour moves: the larynx
front and the epiglottis (moved forward and back with the tongue root's lowest node, the vallecula, a share
``larynx_follows_root`` at the epiglottis tip tapering to none at the glottis, kept clear of the posterior
wall), the tongue's midsagittal surface from the root to the tip, a bridge from the tip to the lower
incisor edge, and the lower incisor, which with the lower lip moves with the mandible.

The grid is fixed too: lines normal to a smoothed reference midline (the spine, glottis to incisors) in the
manner of Maeda's grid, so every frame of a simulation has the same sections, and the distances along
each line are what the area function turns into areas.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import VocalTract, WallGeometry
from ..geometry.mesh import resample_polyline


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
    """Midsagittal points (n, 2) moved by a rigid motion of 3-D space (R (3,3), t (3,)), taken at z = 0;
    with R (F, 3, 3) and t (F, 3), every frame's: (F, n, 2)."""
    p = np.column_stack([points, np.zeros(len(points))])
    if np.ndim(rotation) == 3:
        return (np.einsum("fij,nj->fni", rotation, p) + translation[:, None, :])[..., :2]
    return (p @ rotation.T + translation)[:, :2]


def larynx_front(vt: VocalTract, root_shift_cm: np.ndarray | None, frames: int,
                 back_wall_cm: np.ndarray | None = None) -> np.ndarray:
    """The larynx front of F frames (F, n, 2): its drawn outline (glottis first) moved along x by the tongue
    root's displacement from rest (the x of (F, 2)) times a share rising linearly with height from 0 at the
    glottis to ``larynx_follows_root`` at the epiglottis tip.  The root pulls the epiglottis forward (the
    hyoepiglottic ligament) and pushes it back (it lies against the vallecula); pushed back, a point stops
    ``larynx_wall_gap_cm`` in front of the posterior wall ``back_wall_cm`` ((m, 2), top to bottom), or where
    it was drawn if that is nearer."""
    base = np.asarray(vt.larynx_front_cm, float)
    out = np.broadcast_to(base, (frames, len(base), 2))
    if root_shift_cm is None or vt.larynx_follows_root == 0.0:
        return out
    y = base[:, 1]
    share = vt.larynx_follows_root * np.clip((y - y[0]) / max(y[-1] - y[0], 1e-9), 0.0, 1.0)
    x = base[None, :, 0] + share[None, :] * np.asarray(root_shift_cm, float)[:, None, 0]
    if back_wall_cm is not None:
        wall = np.asarray(back_wall_cm, float)
        order = np.argsort(wall[:, 1])
        limit = np.interp(y, wall[order, 1], wall[order, 0]) + vt.larynx_wall_gap_cm
        x = np.maximum(x, np.minimum(limit, base[:, 0])[None, :])
    return np.stack([x, np.broadcast_to(y, x.shape)], axis=2)


def moving_parts(vt: VocalTract, tongue_cm: np.ndarray, rotation: np.ndarray, translation: np.ndarray,
                 root_shift_cm: np.ndarray | None = None, back_wall_cm: np.ndarray | None = None
                 ) -> dict[str, np.ndarray]:
    """The moving parts of F frames, (F, n, 2) each: the tongue surface (root to tip, from a tip-first
    (F, n, 2) surface), the lower incisor and the lower lip (the mandible's R (F, 3, 3), t (F, 3)), the
    larynx front (the root's displacement from rest (F, 2), None: at rest; the posterior wall it keeps
    clear of)."""
    tongue = np.asarray(tongue_cm, float)[:, ::-1]
    return {"tongue": tongue,
            "lower_incisor": apply_rigid(np.asarray(vt.lower_incisor_cm, float), rotation, translation),
            "lower_lip": apply_rigid(np.asarray(vt.lower_lip_cm, float), rotation, translation),
            "larynx_front": larynx_front(vt, root_shift_cm, len(tongue), back_wall_cm)}


def inner_polylines(vt: VocalTract, moving: dict[str, np.ndarray]) -> list[np.ndarray]:
    """The inner contour of F frames as polylines (F, n, 2): larynx front, tongue (root to tip), the bridge
    from the tip to the lower incisor edge, the lower incisor."""
    tongue, incisor, larynx = moving["tongue"], moving["lower_incisor"], moving["larynx_front"]
    bridge = np.stack([tongue[:, -1], incisor[:, 0]], axis=1)
    return [larynx, tongue, bridge, incisor]


@dataclass(frozen=True)
class Outline:
    """The tract's contours in one frame (cm): polylines, each (n, 2)."""

    inner: tuple[np.ndarray, ...]
    outer: tuple[np.ndarray, ...]
    drawn: dict  # every part by name, for figures


def split_at_x(p: np.ndarray, x: float) -> tuple[np.ndarray, np.ndarray]:
    """A polyline (n, 2) whose x falls along it cut where it crosses ``x``: the part before (x >= ``x``) and the
    part after, both holding the crossing point."""
    after = np.flatnonzero(p[:, 0] < x)
    if len(after) == 0 or after[0] == 0:
        return (p, p[-1:]) if len(after) == 0 else (p[:1], p)
    i = int(after[0])
    w = (p[i - 1, 0] - x) / (p[i - 1, 0] - p[i, 0])
    cut = p[i - 1] + w * (p[i] - p[i - 1])
    return np.vstack([p[:i], cut]), np.vstack([cut, p[i:]])


def outer_contour(vt: VocalTract, wall: WallGeometry) -> dict[str, np.ndarray]:
    """The fixed outer parts: lower pharyngeal wall, the contact wall's midsagittal pharynx, velum and hard
    palate (as the contact wall has them: its outlines resampled, so the tongue touches the tract's wall where it
    touches the contact wall), the velopharyngeal port's line (the oral tract's top behind the velum), the upper
    incisor."""
    mid = wall_at(wall, min(sl.z_cm for sl in wall.slices))
    hard, soft = split_at_x(mid["palate"], vt.hard_palate_end_x_cm)
    return {"pharynx": np.vstack([mid["pharynx"], np.asarray(vt.pharynx_lower_cm, float)]),
            "velum": soft, "port": np.asarray(vt.velum_port_line_cm, float), "hard_palate": hard,
            "upper_incisor": np.asarray(vt.upper_incisor_cm, float)}


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


def wall_at(wall: WallGeometry, z: float, points: int | None = None) -> dict[str, np.ndarray]:
    """The contact wall's outlines (palate with velum, pharynx) at lateral offset ``z`` (cm), linear between
    the config's slices, each resampled by arc length to ``points`` points (default: the wall's own
    ``points_per_outline``, so the outline is the contact wall's)."""
    points = wall.points_per_outline if points is None else points
    slices = sorted(wall.slices, key=lambda sl: sl.z_cm)
    zs = np.array([sl.z_cm for sl in slices])
    if not zs[0] <= z <= zs[-1]:
        raise ValueError(f"z = {z} cm is outside the wall's slices ({zs[0]}-{zs[-1]} cm)")
    if len(slices) == 1:
        return {part: resample_polyline(getattr(slices[0], part), points) for part in ("palate", "pharynx")}
    j = int(np.clip(np.searchsorted(zs, z, side="right") - 1, 0, len(zs) - 2))
    w = (z - zs[j]) / (zs[j + 1] - zs[j])
    out = {}
    for part in ("palate", "pharynx"):
        a = resample_polyline(getattr(slices[j], part), points)
        b = resample_polyline(getattr(slices[j + 1], part), points)
        out[part] = (1 - w) * a + w * b
    return out


def outer_at(vt: VocalTract, wall: WallGeometry, z: float) -> tuple[np.ndarray, ...]:
    """The fixed outer contour's polylines in the plane at ``z`` (cm)."""
    fixed = outer_contour(vt, wall)
    if z == 0.0:
        return tuple(fixed.values())
    side = wall_at(wall, z)
    return (np.vstack([side["pharynx"], np.asarray(vt.pharynx_lower_cm, float)]), side["palate"], fixed["port"],
            fixed["upper_incisor"])
