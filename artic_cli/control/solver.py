"""From spatial targets to muscle force sets through the EP maps (the paper's section V, Fig. 12).

A target names a jaw position, one *crucial* feature (a control point that
must reach a place, within a tolerance) and *indecisive* features (places the
other control points should approach, with weights).  The solver

1. takes the EP maps at the jaw position (stored, or derived from the typical
   map by the dynamic map);
2. finds every force set that puts the crucial control point on its target:
   along single-muscle EP vectors (within the tolerance), inside two-muscle
   contour nets and inside each co-contraction level of the three-muscle
   groups (bilinear interpolation in each net cell, inverted exactly);
3. keeps those and picks the one with the least cost
   ``force_weight * sum F^2 + distance_weight * sum w_i |p_i - target_i|^2``
   over the indecisive features (the paper's choice of the co-contraction
   level in Fig. 12).

Only settled EPs are used: a net cell or vector segment with an unsettled
corner is skipped.  With no candidate the target is unreachable: the error
names the nearest reachable point and its distance.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Annotated, Literal

import numpy as np

from pydantic import Field, field_validator

from ..validation import (DEFAULT_MAX_FORCE_N, ForceN, FormantHz, NonNegative, Point2, Positive, PositionCm, SafeName,
                          Strict, increasing, parse)
from ..errors import ArticError, UnreachableTarget
from .epmap import CONTROL_POINTS, JawMaps, Net

POINT = Literal["tip", "dorsum"]


class JawSpec(Strict):
    forces_n: dict[Literal["JO", "JC"], ForceN] | None = None
    opening_cm: PositionCm | None = None  # incisor height relative to rest


class Crucial(Strict):
    point: POINT
    at_cm: Point2
    tolerance_cm: Positive = 0.05


class Indecisive(Strict):
    point: POINT
    at_cm: Point2
    weight: NonNegative = 1.0


Pct = Annotated[float, Field(gt=0, le=50, allow_inf_nan=False)]


class AcousticGoal(Strict):
    """A vowel's formants: F1 and F2 must come within ``tolerance_pct``; F3 (optional) is approached."""

    formants_hz: Annotated[list[FormantHz], Field(min_length=2, max_length=3)]
    tolerance_pct: Pct | Annotated[list[Pct], Field(min_length=2, max_length=2)] = 10.0  # one, or F1's and F2's
    f3_weight: NonNegative = 0.3  # Bark^-2 relative to F1-F2's, in the choice among candidates

    @property
    def tolerance(self) -> np.ndarray:
        """(2,) F1's and F2's tolerance as fractions."""
        t = self.tolerance_pct if isinstance(self.tolerance_pct, list) else [self.tolerance_pct] * 2
        return np.asarray(t, dtype=float) / 100.0

    @field_validator("formants_hz")
    @classmethod
    def _increasing(cls, v):
        return increasing(v, "formants must increase (F1 < F2 < F3)")


class Constriction(Strict):
    """The area a place of the tract must have: a closure (0) or a channel.  ``place`` names a region of the
    tract's area law (``vocal_tract.area_law``: alveolar, hard palate, velum, ...); the place's area is its
    narrowest section's.  A closure counts at or below ``tolerance_cm2``; a channel within it of its area."""

    place: str
    area_cm2: Annotated[float, Field(ge=0, le=5, allow_inf_nan=False)]
    tolerance_cm2: Annotated[float, Field(gt=0, le=1, allow_inf_nan=False)] = 0.01

    def met(self, area_cm2: float) -> bool:
        return bool(np.isfinite(area_cm2) and abs(area_cm2 - self.area_cm2) <= self.tolerance_cm2)


TongueClass = Literal["high-front", "high-central", "high-back", "mid-front", "mid-central", "mid-back", "low-front",
                      "low-central", "low-back"]


class TongueHighest(Strict):
    """Where an acoustic target's tongue is highest, against the model's rest tongue's highest point: high at
    least ``margin_cm`` above it, low as far below, front / back as far before / behind it; mid and central ask
    nothing.  Each cm short costs as an indecisive feature's cm (``distance_weight``)."""

    tongue: TongueClass
    margin_cm: Annotated[float, Field(ge=0, le=2, allow_inf_nan=False)] = 0.15

    def shortfall_cm(self, top: np.ndarray, rest_top: np.ndarray) -> np.ndarray:
        """(..., 2) how far (x, y cm, >= 0) highest points ``top`` (..., 2) fall short of the class."""
        height, frontness = self.tongue.split("-")
        d = np.asarray(top, float) - np.asarray(rest_top, float)
        out = np.zeros_like(d)
        signs = ({"front": 1.0, "back": -1.0}.get(frontness), {"high": 1.0, "low": -1.0}.get(height))  # x, y
        for axis, sign in enumerate(signs):
            if sign is not None:  # mid and central ask nothing
                out[..., axis] = np.maximum(self.margin_cm - sign * d[..., axis], 0.0)
        return out


class Lips(Strict):
    area_cm2: Annotated[float, Field(gt=0, le=10, allow_inf_nan=False)]
    length_cm: Annotated[float, Field(gt=0, le=4, allow_inf_nan=False)]


# lip tubes by name (VocalTractLab's JD3 vowels, the sections its lips make: /o/ 1.53 cm, 0.40-0.82 cm^2;
# /u/ 1.91 cm, 0.33-0.41 cm^2; /e/ /i/ 0.53-0.55 cm, 1.2-2.5 cm^2; /a/ 0.54 cm, 2.7-2.84 cm^2); "compressed"
# is Japanese /u/'s, narrow without protrusion (the default length; docs/inventory.md, "Vowels"); "neutral" is
# the config's default
LIP_SHAPES = {"rounded": Lips(area_cm2=0.6, length_cm=1.5), "compressed": Lips(area_cm2=0.5, length_cm=1.0),
              "spread": Lips(area_cm2=2.5, length_cm=0.55), "open": Lips(area_cm2=2.8, length_cm=0.55)}


class TargetSpec(Strict):
    name: SafeName = "target"  # becomes the solution's file name
    jaw: JawSpec = JawSpec(forces_n={"JO": 0.5})
    crucial: Crucial | None = None  # a place for a control point, or ...
    acoustic: AcousticGoal | None = None  # ... formants (a vowel), or ...
    constriction: Constriction | None = None  # ... the area at a place of the tract: one of the three
    indecisive: list[Indecisive] = []
    tongue_highest: TongueHighest | None = None  # acoustic targets: where the tongue is highest (a vowel's class)
    lips: Lips | Literal["neutral", "rounded", "compressed", "spread", "open"] | None = None  # acoustic targets only
    velum_port_cm2: Annotated[float, Field(ge=0, le=5, allow_inf_nan=False)] | None = None
    force_weight: NonNegative = 1.0  # per N^2
    distance_weight: NonNegative = 100.0  # per cm^2

    @property
    def needs_tract(self) -> bool:
        """Whether the target is judged on the vocal tract (formants or a place's area), not on a point."""
        return self.acoustic is not None or self.constriction is not None

    def lip_tube(self, default: tuple[float, float]) -> tuple[float, float]:
        """(area cm^2, length cm) of the target's lips; ``default``: the config's."""
        lips = LIP_SHAPES.get(self.lips) if isinstance(self.lips, str) else self.lips
        return default if lips is None else (lips.area_cm2, lips.length_cm)


def parse_target(data: object, source: str = "<target>", max_force_n: float = DEFAULT_MAX_FORCE_N) -> TargetSpec:
    t = parse(TargetSpec, data, source, "target (with 'crucial', 'acoustic' or 'constriction', and 'jaw', "
              "'indecisive')",
              "fix the target and rerun",
              context={"max_force_n": max_force_n})
    if sum(x is not None for x in (t.crucial, t.acoustic, t.constriction)) != 1:
        raise ArticError(f"{source}: give either 'crucial' (a control point's place), 'acoustic' (formants) or "
                         "'constriction' (a place's area), one of them")
    if t.crucial is None and t.jaw.forces_n is None:
        raise ArticError(f"{source}: key 'jaw': an acoustic or constriction target needs jaw.forces_n of a mapped "
                         "jaw position (the acoustic maps hold the EPs' shapes only there)")
    if t.acoustic is None and t.tongue_highest is not None:
        raise ArticError(f"{source}: key 'tongue_highest' belongs to acoustic targets (a vowel's formants); remove "
                         "it or give 'acoustic'")
    if t.crucial is not None and (t.lips is not None or t.velum_port_cm2 is not None):
        raise ArticError(f"{source}: keys 'lips' and 'velum_port_cm2' belong to acoustic targets; remove them or "
                         "give 'acoustic' instead of 'crucial'")
    if (t.jaw.forces_n is None) == (t.jaw.opening_cm is None):
        raise ArticError(f"{source}: key 'jaw': give either forces_n (JO or JC, N) or opening_cm")
    if t.jaw.forces_n is not None and t.jaw.forces_n.get("JO", 0) > 0 and t.jaw.forces_n.get("JC", 0) > 0:
        raise ArticError(f"{source}: key 'jaw.forces_n': give JO or JC, not both")
    points = ([t.crucial.point] if t.crucial is not None else []) + [i.point for i in t.indecisive]
    if len(set(points)) != len(points):
        raise ArticError(f"{source}: key 'indecisive': each control point once"
                         + (f" (the crucial one is {t.crucial.point})" if t.crucial is not None else ""))
    return t


@dataclass
class Candidate:
    family: str  # single, pair, group
    name: str  # map name
    forces: dict[str, float]  # N
    predicted: dict[str, list[float]]  # control point -> (x, y) cm
    crucial_error: float  # cm
    cost: float
    detail: dict = field(default_factory=dict)  # cell and local coordinates (for refinement)


def settled_run(net: Net) -> int:
    """How many levels of a vector, from 0 N up, settled (a vector is used up to its first unsettled EP)."""
    bad = np.flatnonzero(~net.converged)
    return int(bad[0]) if len(bad) else len(net.converged)


def polyline_nearest(pts: np.ndarray, target: np.ndarray):
    """Nearest point of a polyline (n, 2) to target: (distance, segment, fraction)."""
    a, b = pts[:-1], pts[1:]
    ab = b - a
    t = np.clip(((target - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-30), 0, 1)
    d = np.linalg.norm(a + t[:, None] * ab - target, axis=1)
    k = int(np.argmin(d))
    return float(d[k]), k, float(t[k])


def bilinear(c: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """c: (..., 4, d) corners (00, 10, 01, 11); u, v: (...)."""
    u, v = u[..., None], v[..., None]
    return (1 - u) * (1 - v) * c[..., 0, :] + u * (1 - v) * c[..., 1, :] + (1 - u) * v * c[..., 2, :] + u * v * c[..., 3, :]


def invert_cells(corners: np.ndarray, target: np.ndarray, iters: int = 12):
    """Solve bilinear(u, v) = target in every cell (C, 4, 2) by Newton from the centre.

    Returns u, v, residual (C,); a solution counts where u, v lie in [0, 1]."""
    u = np.full(len(corners), 0.5)
    v = np.full(len(corners), 0.5)
    p00, p10, p01, p11 = (corners[:, k] for k in range(4))
    for _ in range(iters):
        r = bilinear(corners, u, v) - target
        du = (1 - v)[:, None] * (p10 - p00) + v[:, None] * (p11 - p01)
        dv = (1 - u)[:, None] * (p01 - p00) + u[:, None] * (p11 - p10)
        det = du[:, 0] * dv[:, 1] - du[:, 1] * dv[:, 0]
        det = np.where(np.abs(det) < 1e-14, 1e-14, det)
        u = u - (dv[:, 1] * r[:, 0] - dv[:, 0] * r[:, 1]) / det
        v = v - (-du[:, 1] * r[:, 0] + du[:, 0] * r[:, 1]) / det
        u, v = np.clip(u, -0.5, 1.5), np.clip(v, -0.5, 1.5)
    res = np.linalg.norm(bilinear(corners, u, v) - target, axis=1)
    return u, v, res


def good_cells(good: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ii, jj) of the cells of a 2-D grid whose four corners are ``good`` (na, nb)."""
    na, nb = good.shape
    ii, jj = (g.ravel() for g in np.meshgrid(np.arange(na - 1), np.arange(nb - 1), indexing="ij"))
    ok = good[ii, jj] & good[ii + 1, jj] & good[ii, jj + 1] & good[ii + 1, jj + 1]
    return ii[ok], jj[ok]


def cell_corners(a: np.ndarray, ii: np.ndarray, jj: np.ndarray) -> np.ndarray:
    """(C, 4, ...) the values of ``a`` (na, nb, ...) at each cell's corners, in the order 00, 10, 01, 11."""
    return np.stack([a[ii, jj], a[ii + 1, jj], a[ii, jj + 1], a[ii + 1, jj + 1]], axis=1)


def _cells(net2: np.ndarray, conv: np.ndarray):
    """Cells of a 2-D grid (na, nb, 3, 3) of EPs whose four corners settled: indices and corners (C, 4, 2, 2)."""
    ii, jj = good_cells(conv)
    return ii, jj, cell_corners(net2, ii, jj)[..., :2, :2]  # tip and dorsum, x and y


def mapped_nets(jm: JawMaps, values: dict):
    """The 2-D nets of a jaw position with a value per EP (``values``: "pair/A+B" | "group/I+A+B" -> (*grid,
    ...)): (family, name, muscles, fixed (independent muscle, level N) or None, the two varied levels, EPs,
    settled, values), each co-contraction level of a group as its own net (level 0 is its pair net)."""
    for name, net in jm.pair.items():
        v = values.get(f"pair/{name}")
        if v is not None:
            yield "pair", name, net.muscles, None, net.levels, net.x, net.converged, v
    for name, net in jm.group.items():
        v = values.get(f"group/{name}")
        if v is None:
            continue
        for k in range(1, len(net.levels[0])):
            yield ("group", name, net.muscles, (net.muscles[0], float(net.levels[0][k])), net.levels[1:],
                   net.x[k], net.converged[k], v[k])


def indecisive_cost(target: TargetSpec, forces: dict[str, float], pred: np.ndarray) -> float:
    """force_weight * sum F^2 + distance_weight * sum w |p - target|^2 over the indecisive features;
    pred: (2, 2) predicted tip and dorsum (x, y)."""
    f = target.force_weight * sum(v * v for v in forces.values())
    d = sum(i.weight * float(np.sum((pred[CONTROL_POINTS.index(i.point)] - np.asarray(i.at_cm)) ** 2))
            for i in target.indecisive)
    return float(f + target.distance_weight * d)


class Problem:
    """A spatial target on the maps of one jaw position."""

    def __init__(self, jm: JawMaps, target: TargetSpec, reach: float | None = None):
        self.jm = jm
        self.t = target
        self.reach = target.crucial.tolerance_cm if reach is None else reach
        self.c = CONTROL_POINTS.index(target.crucial.point)
        self.goal = np.asarray(target.crucial.at_cm, dtype=float)

    def cost(self, forces: dict[str, float], pred: np.ndarray) -> float:
        return indecisive_cost(self.t, forces, pred)

    def _candidate(self, family, name, forces, pred, detail) -> Candidate:
        forces = {k: float(v) for k, v in forces.items() if v > 1e-12}
        err = float(np.linalg.norm(pred[self.c] - self.goal))
        return Candidate(family=family, name=name, forces=forces,
                         predicted={cp: [float(pred[k, 0]), float(pred[k, 1])] for k, cp in enumerate(("tip", "dorsum"))},
                         crucial_error=err, cost=self.cost(forces, pred), detail=detail)

    def singles(self) -> list[Candidate]:
        out = []
        for m, net in self.jm.single.items():
            stop = settled_run(net)
            if stop < 2:
                continue
            pts = net.x[:stop, :2, :2]
            d, k, frac = polyline_nearest(pts[:, self.c], self.goal)
            if d > self.reach:
                continue
            lv = net.levels[0]
            force = lv[k] + frac * (lv[k + 1] - lv[k])
            pred = pts[k] + frac * (pts[k + 1] - pts[k])
            out.append(self._candidate("single", m, {m: force}, pred, {"segment": k, "fraction": frac}))
        return out

    def _nets(self):
        for name, net in self.jm.pair.items():
            yield "pair", name, net.muscles, None, net.levels, net.x, net.converged
        for name, net in self.jm.group.items():
            for k in range(1, len(net.levels[0])):  # level 0 of a group is its pair net
                yield ("group", name, net.muscles, (net.muscles[0], float(net.levels[0][k])),
                       net.levels[1:], net.x[k], net.converged[k])

    def nets(self) -> list[Candidate]:
        out = []
        for family, name, muscles, fixed, levels, x, conv in self._nets():
            ii, jj, corners = _cells(x, conv)
            if not len(ii):
                continue
            u, v, _ = invert_cells(corners[:, :, self.c], self.goal)
            # outside a cell, its nearest edge point (Newton's solution clipped) may still be within tolerance
            u, v = np.clip(u, 0.0, 1.0), np.clip(v, 0.0, 1.0)
            res = np.linalg.norm(bilinear(corners[:, :, self.c], u, v) - self.goal, axis=1)
            inside = res <= self.reach
            for k in np.flatnonzero(inside):
                a, b = muscles[-2], muscles[-1]
                la, lb = levels
                fa = la[ii[k]] + u[k] * (la[ii[k] + 1] - la[ii[k]])
                fb = lb[jj[k]] + v[k] * (lb[jj[k] + 1] - lb[jj[k]])
                forces = {a: fa}
                forces[b] = forces.get(b, 0.0) + fb
                if fixed is not None:
                    forces[fixed[0]] = forces.get(fixed[0], 0.0) + fixed[1]
                pred = bilinear(corners[k].reshape(1, 4, 4), np.array([u[k]]), np.array([v[k]]))[0].reshape(2, 2)
                label = name if fixed is None else f"{name} ({fixed[0]} {fixed[1]:g} N)"
                out.append(self._candidate(family, label, forces, pred,
                                           {"cell": [int(ii[k]), int(jj[k])], "uv": [float(u[k]), float(v[k])],
                                            "net": name, "fixed": fixed}))
        return out

    def nearest_reachable(self) -> tuple[np.ndarray, float, str]:
        """Closest point of the mapped region to the crucial target (vectors exactly, net cells sampled)."""
        best = (None, np.inf, "")
        for m, net in self.jm.single.items():
            pts = net.x[: settled_run(net), self.c, :2]
            if len(pts) < 2:
                continue
            d, k, frac = polyline_nearest(pts, self.goal)
            if d < best[1]:
                best = (pts[k] + frac * (pts[k + 1] - pts[k]), d, f"vector {m}")
        s = np.linspace(0, 1, 9)
        uu, vv = (g.ravel() for g in np.meshgrid(s, s, indexing="ij"))
        for family, name, _, fixed, _, x, conv in self._nets():
            _, _, corners = _cells(x, conv)
            if not len(corners):
                continue
            c = np.repeat(corners[:, :, self.c][:, None], len(uu), axis=1)  # (C, S, 4, 2)
            p = bilinear(c, np.broadcast_to(uu, c.shape[:2]), np.broadcast_to(vv, c.shape[:2]))
            d = np.linalg.norm(p - self.goal, axis=-1)
            k = np.unravel_index(np.argmin(d), d.shape)
            if d[k] < best[1]:
                best = (p[k], float(d[k]), f"{family} {name}")
        return best


@dataclass
class Solution:
    target: TargetSpec
    jaw_forces: dict[str, float]
    jaw_height_cm: float
    chosen: Candidate
    candidates: list[Candidate]  # every candidate, cheapest first
    maps_note: str


def solve_on(jm: JawMaps, target: TargetSpec, reach: float | None = None) -> list[Candidate]:
    """Every candidate force set on these maps that reaches the crucial feature, cheapest first.

    ``reach`` (default: the crucial tolerance) is how close a candidate's predicted point must come; a
    refinement by simulation may start from candidates a little farther out."""
    tol = target.crucial.tolerance_cm
    reach = tol if reach is None else max(reach, tol)
    p = Problem(jm, target, reach)
    found = p.singles() + p.nets()
    cands = sorted([c for c in found if c.crucial_error <= tol], key=lambda c: c.cost)
    if not cands:  # none on target by the maps: the near ones, nearest first, for a refinement to correct
        cands = sorted([c for c in found if c.crucial_error <= reach], key=lambda c: (c.crucial_error, c.cost))
    if not cands:
        point, dist, where = p.nearest_reachable()
        if point is None:
            raise UnreachableTarget(f"target '{target.name}': no settled EP maps to search")
        err = UnreachableTarget(
            f"target '{target.name}': {target.crucial.point} at ({target.crucial.at_cm[0]:.3f}, "
            f"{target.crucial.at_cm[1]:.3f}) cm is not reachable at this jaw position; the nearest reachable point "
            f"is ({point[0]:.3f}, {point[1]:.3f}) cm ({where}), {dist:.3f} cm away")
        err.nearest_cm = float(dist)  # how far the nearest reachable point is (a caller may settle for it)
        err.nearest_point_cm = [float(point[0]), float(point[1])]
        raise err
    return cands
