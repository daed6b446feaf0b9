"""Dynamic EP maps (the paper's section IV.B.3, Table IV).

The nine jaw-dependent maps look like the typical one (JO 0.5 N) rotated and
shifted with the jaw.  For each jaw position and control point we fit, by 2-D
Procrustes over every settled single-muscle EP, the rotation about the typical
cloud's centroid and the translation that carry the typical map onto the
simulated one.  The fitted angles and shifts, tabulated against the jaw's
incisor height, give the map for *any* jaw position by interpolation
(``derive``).  Table IV's errors are the mean distances between the derived
and the simulated EPs; we also report them leave-one-out (the jaw position's
own fit withheld, so the transform is truly predicted), which the paper does
not.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import ArticError
from .epmap import EPMaps, JawMaps, Net

CPS = ("tip", "dorsum")
PAPER_TABLE_IV = {"JC_3": (0.407, 0.037, 0.030), "JC_1.5": (0.210, 0.026, 0.024), "JC_0.5": (0.090, 0.021, 0.020),
                  "rest": (0.0, 0.024, 0.019), "JO_0.5": (-0.160, 0.0, 0.0), "JO_1.2": (-0.374, 0.021, 0.018),
                  "JO_2.5": (-0.761, 0.049, 0.041), "JO_4": (-1.097, 0.084, 0.066), "JO_6": (-1.425, 0.123, 0.091)}


def rotation(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def procrustes_2d(p: np.ndarray, q: np.ndarray) -> tuple[float, np.ndarray]:
    """Angle and shift with q ~ R(angle) (p - mean p) + mean p + shift, least squares (p, q: (n, 2))."""
    a, b = p - p.mean(axis=0), q - q.mean(axis=0)
    theta = float(np.arctan2((a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum(), (a * b).sum()))
    return theta, q.mean(axis=0) - p.mean(axis=0)


def jaw_angle(reference: np.ndarray, now: np.ndarray) -> float:
    """Sagittal rotation (rad, + counter-clockwise seen from +z, i.e. closing) of the mandible nodes."""
    return procrustes_2d(reference[:, :2], now[:, :2])[0]


@dataclass
class DynamicMap:
    typical: str
    jaws: list[str]
    jaw_forces: list[dict]
    height: np.ndarray  # (J,) incisor height of each jaw position's rest, cm
    angle: np.ndarray  # (J,) jaw rotation from the typical position, rad
    theta: np.ndarray  # (J, 2) map rotation per control point, rad
    shift: np.ndarray  # (J, 2, 2) cm
    centre: np.ndarray  # (2, 2) the typical cloud's centroid per control point, cm
    error_mean: np.ndarray  # (J, 2) cm
    error_max: np.ndarray  # (J, 2) cm
    loo_error_mean: np.ndarray  # (J, 2) cm (nan for the typical position)
    points: np.ndarray  # (J,) EPs compared
    rest_height: float  # the 'rest' jaw position's incisor height, cm

    def transform(self, jaw_height: float, exclude: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(theta (2,), shift (2, 2)) at an incisor height, piecewise linear between the fitted positions
        (linear beyond the end ones)."""
        keep = [k for k in range(len(self.jaws)) if k != exclude]
        h = self.height[keep]
        order = np.argsort(h)
        h = h[order]
        th = self.theta[keep][order]
        sh = self.shift[keep][order]
        k = int(np.clip(np.searchsorted(h, jaw_height) - 1, 0, len(h) - 2))
        w = (jaw_height - h[k]) / (h[k + 1] - h[k])
        return th[k] + w * (th[k + 1] - th[k]), sh[k] + w * (sh[k + 1] - sh[k])

    def apply(self, xy: np.ndarray, cp: int, theta: float, shift: np.ndarray) -> np.ndarray:
        return (xy - self.centre[cp]) @ rotation(theta).T + self.centre[cp] + shift

    def height_for(self, jaw_forces: dict[str, float]) -> float:
        """Incisor height of a jaw position given as JO / JC force, by interpolation over the stored ones."""
        signed = [f.get("JC", 0.0) - f.get("JO", 0.0) for f in self.jaw_forces]
        want = jaw_forces.get("JC", 0.0) - jaw_forces.get("JO", 0.0)
        if want < min(signed) or want > max(signed):
            raise ArticError(f"jaw force {jaw_forces} lies outside the mapped jaw positions "
                             f"(JO up to {-min(signed):g} N, JC up to {max(signed):g} N); give one inside")
        order = np.argsort(signed)
        return float(np.interp(want, np.array(signed)[order], self.height[order]))


def _pairs(typ: JawMaps, other: JawMaps, cp: int) -> tuple[np.ndarray, np.ndarray]:
    p, q = [], []
    for m, net in typ.single.items():
        if m not in other.single:
            continue
        o = other.single[m]
        n = min(len(net.levels[0]), len(o.levels[0]))
        ok = net.converged[:n] & o.converged[:n] & np.isclose(net.levels[0][:n], o.levels[0][:n])
        p.append(net.x[:n][ok, cp, :2])
        q.append(o.x[:n][ok, cp, :2])
    return np.concatenate(p), np.concatenate(q)


def fit_dynamic_map(maps: EPMaps) -> DynamicMap:
    if maps.typical_jaw not in maps.jaws:
        raise ArticError(f"the maps lack their typical jaw position '{maps.typical_jaw}'; rebuild with 'artic ep-map'")
    typ = maps.jaws[maps.typical_jaw]
    names = list(maps.jaws)
    if len(names) < 3:
        raise ArticError("a dynamic map needs EP maps at three jaw positions at least; add epmap.jaw_positions")
    nj = len(names)
    theta = np.zeros((nj, 2))
    shift = np.zeros((nj, 2, 2))
    centre = np.zeros((2, 2))
    emean, emax, loo = np.zeros((nj, 2)), np.zeros((nj, 2)), np.full((nj, 2), np.nan)
    npts = np.zeros(nj, dtype=int)
    height = np.array([maps.jaws[j].rest[2, 1] for j in names])
    angle = np.array([jaw_angle(typ.mandible, maps.jaws[j].mandible) if typ.mandible is not None else 0.0
                      for j in names])
    for c in (0, 1):
        p_all, _ = _pairs(typ, typ, c)
        centre[c] = p_all.mean(axis=0)
    clouds = {}
    for k, j in enumerate(names):
        for c in (0, 1):
            p, q = _pairs(typ, maps.jaws[j], c)
            clouds[(k, c)] = (p, q)
            a, b = p - centre[c], q - q.mean(axis=0)
            theta[k, c] = np.arctan2((a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum(), (a * b).sum())
            shift[k, c] = q.mean(axis=0) - (a @ rotation(theta[k, c]).T).mean(axis=0) - centre[c]
            npts[k] = len(p)
    dm = DynamicMap(typical=maps.typical_jaw, jaws=names, jaw_forces=[maps.jaws[j].forces for j in names],
                    height=height, angle=angle, theta=theta, shift=shift, centre=centre, error_mean=emean,
                    error_max=emax, loo_error_mean=loo, points=npts,
                    rest_height=float(maps.jaws["rest"].rest[2, 1]) if "rest" in maps.jaws else float(height[0]))
    for k, j in enumerate(names):
        for c in (0, 1):
            p, q = clouds[(k, c)]
            d = np.linalg.norm(dm.apply(p, c, theta[k, c], shift[k, c]) - q, axis=1)
            emean[k, c], emax[k, c] = d.mean(), d.max()
            if j != maps.typical_jaw:
                th, sh = dm.transform(height[k], exclude=k)
                loo[k, c] = np.linalg.norm(dm.apply(p, c, th[c], sh[c]) - q, axis=1).mean()
    return dm


def derive(maps: EPMaps, dm: DynamicMap, jaw_height: float) -> JawMaps:
    """The whole typical map (vectors, nets, groups) carried to a jaw position by the fitted transform."""
    typ = maps.jaws[dm.typical]
    th, sh = dm.transform(jaw_height)

    def move(net: Net) -> Net:
        x = net.x.copy()
        for c in (0, 1):
            x[..., c, :2] = dm.apply(net.x[..., c, :2], c, th[c], sh[c])
        x[..., 2, 1] += jaw_height - typ.rest[2, 1]
        return replace(net, x=x)

    rest = typ.rest.copy()
    for c in (0, 1):
        rest[c, :2] = dm.apply(typ.rest[c, :2], c, th[c], sh[c])
    rest[2, 1] = jaw_height
    return JawMaps(forces={}, rest=rest, single={m: move(n) for m, n in typ.single.items()},
                   pair={m: move(n) for m, n in typ.pair.items()}, group={m: move(n) for m, n in typ.group.items()})


def table_iv(dm: DynamicMap) -> list[dict]:
    """Rows of Table IV, ours beside the paper's (positions relative to the rest jaw)."""
    rows = []
    for k, j in enumerate(dm.jaws):
        paper = PAPER_TABLE_IV.get(j)
        rows.append({"jaw": j, "forces_n": dm.jaw_forces[k], "position_cm": float(dm.height[k] - dm.rest_height),
                     "jaw_angle_deg": float(np.degrees(dm.angle[k])),
                     "theta_deg": [float(v) for v in np.degrees(dm.theta[k])],
                     "error_tip_cm": float(dm.error_mean[k, 0]), "error_dorsum_cm": float(dm.error_mean[k, 1]),
                     "loo_tip_cm": None if np.isnan(dm.loo_error_mean[k, 0]) else float(dm.loo_error_mean[k, 0]),
                     "loo_dorsum_cm": None if np.isnan(dm.loo_error_mean[k, 1]) else float(dm.loo_error_mean[k, 1]),
                     "paper_position_cm": None if paper is None else paper[0],
                     "paper_tip_cm": None if paper is None else paper[1],
                     "paper_dorsum_cm": None if paper is None else paper[2]})
    return rows
