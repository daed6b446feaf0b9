"""Constriction targets on the EP maps: force sets whose vocal tract has an area at a place (a closure at the
alveolar ridge, a fricative's channel).

Every EP of the maps has an area function (the acoustic maps); a place's area is its narrowest section's
(:mod:`artic_cli.tract.places`).  Along each single-muscle vector the first force (from 0 N up) whose
interpolated area meets the goal is a candidate; inside each two-muscle net and each co-contraction level of
the three-muscle groups, every settled cell is sampled (bilinear, 9 x 9) and the cheapest sample that meets
the goal is.  The cheapest candidate wins (forces^2 and the indecisive features, as the spatial solver).  A
place's area interpolates linearly between EPs only roughly (a closure is reached, not approached
smoothly): a refinement by simulation (:func:`artic_cli.control.targets.solve_constriction`) corrects it.
"""

from __future__ import annotations

import numpy as np

from ..errors import UnreachableTarget
from .epmap import JawMaps
from .solver import (Candidate, TargetSpec, bilinear, cell_corners, good_cells, indecisive_cost, mapped_nets,
                     settled_run)

AreaNets = dict  # "single/SG" | "pair/A+B" | "group/I+A+B" -> (*grid,) the place's area of the net's EPs, cm^2
SAMPLES = 9  # per side of a net cell


class ConstrictionProblem:
    """A constriction target on the maps (and the place's areas) of one jaw position."""

    def __init__(self, jm: JawMaps, target: TargetSpec, areas: AreaNets):
        self.jm, self.t, self.areas = jm, target, areas
        self.goal = target.constriction

    def candidate(self, family, name, forces, pred, area, detail) -> Candidate:
        forces = {k: float(v) for k, v in forces.items() if v > 1e-12}
        return Candidate(family=family, name=name, forces=forces,
                         predicted={cp: [float(pred[k, 0]), float(pred[k, 1])] for k, cp in enumerate(("tip", "dorsum"))},
                         crucial_error=float(abs(area - self.goal.area_cm2)), cost=indecisive_cost(self.t, forces, pred),
                         detail=dict(detail, place_area_cm2=float(area)))

    def singles(self) -> list[Candidate]:
        out = []
        for m, net in self.jm.single.items():
            a = self.areas.get(f"single/{m}")
            stop = settled_run(net)
            if a is None or stop < 1:
                continue
            a, lv, pts = a[:stop], net.levels[0][:stop], net.x[:stop, :2, :2]
            if self.goal.met(a[0]):
                out.append(self.candidate("single", m, {m: lv[0]}, pts[0], a[0], {"segment": 0, "fraction": 0.0}))
                continue
            for k in range(stop - 1):  # the first crossing into the goal's band, from 0 N up
                lo, hi = self.goal.area_cm2 - self.goal.tolerance_cm2, self.goal.area_cm2 + self.goal.tolerance_cm2
                edge = hi if a[k] > hi else lo
                if (a[k] - edge) * (a[k + 1] - edge) > 0 or a[k] == a[k + 1]:
                    continue
                frac = float(np.clip((a[k] - edge) / (a[k] - a[k + 1]), 0.0, 1.0))
                area = a[k] + frac * (a[k + 1] - a[k])
                force = lv[k] + frac * (lv[k + 1] - lv[k])
                pred = pts[k] + frac * (pts[k + 1] - pts[k])
                out.append(self.candidate("single", m, {m: force}, pred, area, {"segment": k, "fraction": frac}))
                break
        return out

    def nets_of_areas(self):
        return mapped_nets(self.jm, self.areas)

    def nets(self) -> list[Candidate]:
        out = []
        s = np.linspace(0.0, 1.0, SAMPLES)
        uu, vv = (g.ravel() for g in np.meshgrid(s, s, indexing="ij"))
        for family, name, muscles, fixed, levels, x, conv, a in self.nets_of_areas():
            ii, jj = good_cells(conv & np.isfinite(a))
            if not len(ii):
                continue
            ac = cell_corners(a[..., None], ii, jj)  # (C, 4, 1)
            near = np.abs(ac[..., 0] - self.goal.area_cm2)
            span = (ac[..., 0].min(axis=1) <= self.goal.area_cm2 + self.goal.tolerance_cm2) & (
                ac[..., 0].max(axis=1) >= self.goal.area_cm2 - self.goal.tolerance_cm2)
            for c in np.flatnonzero(span | (near.min(axis=1) <= self.goal.tolerance_cm2)):
                area = bilinear(np.repeat(ac[c][None], len(uu), axis=0), uu, vv)[:, 0]
                ok = np.abs(area - self.goal.area_cm2) <= self.goal.tolerance_cm2
                if not ok.any():
                    continue
                la, lb = levels
                a_, b_ = muscles[-2], muscles[-1]
                fa = la[ii[c]] + uu * (la[ii[c] + 1] - la[ii[c]])
                fb = lb[jj[c]] + vv * (lb[jj[c] + 1] - lb[jj[c]])
                total = fa ** 2 + fb ** 2 + np.where(ok, 0.0, np.inf)
                k = int(np.argmin(total))
                forces = {a_: float(fa[k])}
                forces[b_] = forces.get(b_, 0.0) + float(fb[k])
                if fixed is not None:
                    forces[fixed[0]] = forces.get(fixed[0], 0.0) + fixed[1]
                cp = cell_corners(x[..., :2, :2], ii[c:c + 1], jj[c:c + 1]).reshape(1, 4, 4)
                pred = bilinear(cp, uu[k:k + 1], vv[k:k + 1])[0].reshape(2, 2)
                label = name if fixed is None else f"{name} ({fixed[0]} {fixed[1]:g} N)"
                out.append(self.candidate(family, label, forces, pred, area[k],
                                           {"cell": [int(ii[c]), int(jj[c])], "uv": [float(uu[k]), float(vv[k])],
                                            "net": name, "fixed": fixed}))
        return out

    def nearest(self) -> tuple[float, str]:
        """The mapped area nearest the goal (cm^2) and where."""
        best = (np.inf, "")
        for key, a in self.areas.items():
            a = np.asarray(a, float)
            if not np.isfinite(a).any():
                continue
            d = np.nanmin(np.abs(a - self.goal.area_cm2))
            if d < abs(best[0] - self.goal.area_cm2):
                best = (float(a.ravel()[np.nanargmin(np.abs(a - self.goal.area_cm2).ravel())]), key)
        return best


def solve_constriction_on(jm: JawMaps, target: TargetSpec, areas: AreaNets) -> list[Candidate]:
    """Every candidate whose interpolated place area meets the goal, cheapest first."""
    p = ConstrictionProblem(jm, target, areas)
    cands = sorted(p.singles() + p.nets(), key=lambda c: c.cost)
    if not cands:
        area, where = p.nearest()
        g = target.constriction
        raise UnreachableTarget(f"target '{target.name}': an area of {g.area_cm2:g} cm^2 at the {g.place} is not "
                                f"reachable at this jaw position; the nearest mapped area there is {area:.3f} cm^2 "
                                f"({where})")
    return cands
