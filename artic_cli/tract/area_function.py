"""Area functions from midsagittal contours: distances along the grid lines, areas by power laws.

On each grid line the tract is the stretch between the inner contour's last crossing and the outer wall's
first crossing (s measured from the spine toward the wall); a tongue beyond the wall (contact) reads
distance 0, a closure.  Contact is a point: a tongue surface node on the wall (within ``touch_cm``) lies
between two grid lines, where no line sees it, and the straight chords to its neighbours leave a gap of
about 0.1 mm on the lines beside it; so the two lines either side of such a node read distance 0 too (the
tract is closed where the tongue touches, wherever the lines fall).  The area is A = alpha d^beta with one
(alpha, beta) per region (Heinz & Stevens 1965; the regions' coefficients are the config's).  Each grid
line is one section, as long as half the midline's distance to its neighbours on each side, so the section
lengths add up to the midline's length; the lip tube (a control: length and area) follows as the last
sections.  Everything is vectorised over frames: contours (F, S, 2, 2) as segments.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .outline import Grid

_EPS = 1e-12


def segments(polylines) -> np.ndarray:
    """(S, 2, 2): every segment of the polylines (n, 2), as (start, end) points; for polylines of F frames
    (F, n, 2), (F, S, 2, 2)."""
    axis = np.ndim(polylines[0]) - 2
    take = lambda p, a, b: p[:, a:b] if axis else p[a:b]  # noqa: E731
    return np.concatenate([np.stack([take(p, None, -1), take(p, 1, None)], axis=axis + 1)
                           for p in polylines if p.shape[axis] > 1], axis=axis)


def crossings(grid: Grid, segs: np.ndarray) -> np.ndarray:
    """s (cm) where each grid line crosses each segment, NaN where it does not: (F, L, S) for segments
    (F, S, 2, 2)."""
    a = segs[:, :, 0, :]
    e = segs[:, :, 1, :] - a
    o, n = grid.origin[None, :, None, :], grid.normal[None, :, None, :]
    ao = a[:, None] - o  # (F, L, S, 2)
    e = e[:, None]
    den = n[..., 0] * e[..., 1] - n[..., 1] * e[..., 0]
    ok = np.abs(den) > _EPS
    den = np.where(ok, den, 1.0)
    s = (ao[..., 0] * e[..., 1] - ao[..., 1] * e[..., 0]) / den
    u = (ao[..., 0] * n[..., 1] - ao[..., 1] * n[..., 0]) / den
    hit = ok & (u >= 0.0) & (u <= 1.0) & (np.abs(s) <= grid.reach_cm)
    return np.where(hit, s, np.nan)


def wall_distance(grid: Grid, outer: np.ndarray) -> np.ndarray:
    """s of the outer wall's first crossing on the wall side of each line, (L,); NaN where the line misses
    the wall."""
    s = crossings(grid, outer[None])[0]
    s = np.where(s > 0.0, s, np.inf)
    first = s.min(axis=1)
    return np.where(np.isfinite(first), first, np.nan)


def inner_distance(grid: Grid, inner: np.ndarray, wall_s: np.ndarray, penetration_cm: float) -> np.ndarray:
    """s of the inner contour's last crossing below the wall (up to ``penetration_cm`` beyond it), (F, L);
    +inf where the line crosses the inner contour only farther beyond the wall (the tongue is through it: a
    closure); NaN where the line meets no inner contour at all."""
    s = crossings(grid, inner)
    below = np.where(s < wall_s[None, :, None] + penetration_cm, s, np.nan)
    with np.errstate(all="ignore"):
        last = np.nanmax(np.where(np.isnan(below), -np.inf, below), axis=2)
    beyond = np.isfinite(s).any(axis=2)
    return np.where(np.isfinite(last), last, np.where(beyond, np.inf, np.nan))


def point_segment_distance(points: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """(..., n) distance (cm) from each point (..., n, 2) to the nearest of the segments (S, 2, 2)."""
    a, e = segs[:, 0, :], segs[:, 1, :] - segs[:, 0, :]
    rel = points[..., None, :] - a  # (..., n, S, 2)
    u = np.clip((rel * e).sum(-1) / np.maximum((e * e).sum(-1), _EPS), 0.0, 1.0)
    return np.linalg.norm(rel - u[..., None] * e, axis=-1).min(axis=-1)


def touched_lines(grid: Grid, points: np.ndarray, outer: np.ndarray, touch_cm: float) -> np.ndarray:
    """(F, L) bool: for each of the points (F, n, 2) within ``touch_cm`` of the outer contour (S', 2, 2), the
    two grid lines either side of it (the nearest line whose stretch 0 <= s <= reach passes it and its
    neighbour across the point): a contact closes the stretch between them, and a contact sliding from one
    stretch to the next keeps a line closed all the way (areas between frames are interpolated)."""
    f, n = points.shape[:2]
    out = np.zeros((f, grid.n_lines), bool)
    if touch_cm <= 0 or n == 0:
        return out
    near = point_segment_distance(points, outer) <= touch_cm  # (F, n)
    if not near.any():
        return out
    fr, k = np.nonzero(near)
    rel = points[fr, k][:, None, :] - grid.origin[None]  # (P, L, 2)
    s = (rel * grid.normal).sum(-1)
    side = rel[..., 0] * grid.normal[:, 1] - rel[..., 1] * grid.normal[:, 0]  # signed distance across the line
    off = np.where((s >= 0.0) & (s <= grid.reach_cm), np.abs(side), np.inf)
    line = np.argmin(off, axis=1)
    rows = np.arange(len(line))
    ok = np.isfinite(off[rows, line])
    up = np.minimum(line + 1, grid.n_lines - 1)
    across = np.where(np.sign(side[rows, up]) != np.sign(side[rows, line]), up, np.maximum(line - 1, 0))
    out[fr[ok], line[ok]] = True
    out[fr[ok], across[ok]] = True
    return out


def power_law(distance_cm: np.ndarray, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """A = alpha d^beta (cm^2), 0 for d <= 0."""
    d = np.maximum(distance_cm, 0.0)
    return alpha * d ** beta


def section_lengths(midline: np.ndarray) -> np.ndarray:
    """(F, L) lengths: half the distance to each neighbour along the midline (F, L, 2); they sum to the
    midline's length."""
    seg = np.linalg.norm(np.diff(midline, axis=1), axis=2)  # (F, L-1)
    pad = np.zeros((len(midline), 1))
    return 0.5 * (np.concatenate([pad, seg], axis=1) + np.concatenate([seg, pad], axis=1))


@dataclass(frozen=True)
class AreaFunctions:
    """Area functions of F frames: N = grid lines + lip sections, glottis first (cm, cm^2)."""

    length_cm: np.ndarray  # (F, N)
    area_cm2: np.ndarray  # (F, N)
    region: np.ndarray  # (N,) region index; the lip tube's sections are len(names) - 1
    region_names: tuple[str, ...]
    distance_cm: np.ndarray  # (F, L) inner-to-wall distance on each line
    inner_s_cm: np.ndarray  # (F, L)
    wall_s_cm: np.ndarray  # (L,)
    midline_cm: np.ndarray  # (F, L, 2)

    @property
    def tract_length_cm(self) -> np.ndarray:
        return self.length_cm.sum(axis=1)

    def constriction(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per frame: the smallest area (cm^2), its section's centre from the glottis (cm), its region index."""
        k = np.argmin(self.area_cm2, axis=1)
        rows = np.arange(len(k))
        centre = np.cumsum(self.length_cm, axis=1) - 0.5 * self.length_cm
        return self.area_cm2[rows, k], centre[rows, k], self.region[k]


def area_functions(grid: Grid, inner: np.ndarray, outer: np.ndarray, alpha: np.ndarray, beta: np.ndarray,
                   region_names: tuple[str, ...], lip_length_cm: np.ndarray, lip_area_cm2: np.ndarray,
                   lip_sections: int, penetration_cm: float, touch_points: np.ndarray | None = None,
                   touch_cm: float = 0.0) -> AreaFunctions:
    """From inner contours (F, S, 2, 2), the fixed outer contour (S', 2, 2), the law's per-region
    coefficients and the lip controls (F,) to the area functions; the two lines either side of each of
    ``touch_points`` (F, n, 2: the tongue's surface nodes) within ``touch_cm`` of the wall read a closure.
    Lines that miss a contour give NaN distances (the caller says which)."""
    wall_s = wall_distance(grid, outer)
    inner_s = inner_distance(grid, inner, wall_s, penetration_cm)
    with np.errstate(invalid="ignore"):
        d = np.maximum(wall_s[None, :] - inner_s, 0.0)
    if touch_points is not None:
        d = np.where(touched_lines(grid, np.asarray(touch_points, float), outer, touch_cm) & np.isfinite(d), 0.0, d)
    mid_s = np.minimum(0.5 * (np.minimum(inner_s, wall_s[None, :]) + wall_s[None, :]), wall_s[None, :])
    midline = grid.origin[None] + mid_s[..., None] * grid.normal[None]
    area = power_law(d, alpha[grid.region][None, :], beta[grid.region][None, :])
    length = section_lengths(midline)
    f = len(inner)
    lip_len = np.repeat((np.asarray(lip_length_cm, float) / lip_sections)[:, None], lip_sections, axis=1)
    lip_area = np.repeat(np.asarray(lip_area_cm2, float)[:, None], lip_sections, axis=1)
    names = tuple(region_names) + ("lips",)
    region = np.concatenate([grid.region, np.full(lip_sections, len(names) - 1)])
    return AreaFunctions(length_cm=np.concatenate([length, lip_len.reshape(f, -1)], axis=1),
                         area_cm2=np.concatenate([area, lip_area.reshape(f, -1)], axis=1), region=region,
                         region_names=names, distance_cm=d, inner_s_cm=inner_s, wall_s_cm=wall_s,
                         midline_cm=midline)


def band_areas(grid: Grid, inners: list[np.ndarray], outers: list[np.ndarray], z_cm: np.ndarray,
               inner_mid_s: np.ndarray, wall_mid_s: np.ndarray) -> np.ndarray:
    """The cross-section of the band |z| <= z_cm[-1] from the distances in parasagittal planes: inner
    contours (F, S, 2, 2) and outer ones (S', 2, 2) per plane at ``z_cm`` (the first, 0, is the midsagittal
    one), A = 2 int d(z) dz by the trapezoid rule (the model is symmetric); (F, L) cm^2.  In a lateral plane
    each line takes the crossings nearest to its midsagittal ones (``inner_mid_s`` (F, L), ``wall_mid_s``
    (L,)): the lateral wall lies lower than the spine in the mouth, so "the first crossing beyond the spine"
    does not hold there; NaN where a plane's line misses a contour."""
    d = []
    for k, (inner, outer) in enumerate(zip(inners, outers)):
        if k == 0:
            with np.errstate(invalid="ignore"):
                d.append(np.maximum(wall_mid_s[None, :] - inner_mid_s, 0.0))
            continue
        w = crossings(grid, outer[None])[0]  # (L, S')
        wall_s = _nearest(w[None], wall_mid_s[None, :])[0]
        ref = np.where(np.isfinite(inner_mid_s), inner_mid_s, wall_mid_s[None, :])
        inner_s = _nearest(crossings(grid, inner), ref)
        with np.errstate(invalid="ignore"):
            d.append(np.maximum(wall_s[None, :] - inner_s, 0.0))
    return 2.0 * np.trapezoid(np.stack(d), np.asarray(z_cm, float), axis=0)


def _nearest(s: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """The crossing s (F, L, S) nearest to ``ref`` (F, L) per line; NaN where there is none."""
    gap = np.abs(s - ref[..., None])
    gap = np.where(np.isnan(gap), np.inf, gap)
    k = np.argmin(gap, axis=2)
    out = np.take_along_axis(s, k[..., None], axis=2)[..., 0]
    return np.where(np.isfinite(np.take_along_axis(gap, k[..., None], axis=2)[..., 0]), out, np.nan)
