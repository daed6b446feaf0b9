"""Acoustic targets on the EP maps: force sets whose vocal tract has the target's formants.

Every EP of the maps has formants (the acoustic maps, or the same computed for the target's lips and
velopharyngeal port).  The search is the spatial solver's with the crucial point replaced by (F1, F2) on the
Bark scale (Traunmueller 1990), a perceptual distance: along single-muscle vectors, inside two-muscle nets and
inside each co-contraction level of the three-muscle groups (bilinear in each cell, inverted exactly).  A
candidate counts when F1 and F2 are each within the tolerance (per cent of the target); F3, when given, is
approached.  Among those the cheapest wins: forces^2, the indecisive features' distances (as the spatial
solver), F3's Bark error and, for a ``tongue_highest``, how far the tongue's highest point (interpolated as
the formants are) falls short of its class.  Formants are interpolated linearly between EPs: a refinement by simulation
(:func:`..verify.refine_formants`) corrects what that misses.
"""

from __future__ import annotations

import numpy as np

from ..errors import UnreachableTarget
from ..units import hz_to_bark
from .epmap import JawMaps
from .solver import (Candidate, TargetSpec, bilinear, mapped_nets, polyline_nearest, settled_run, cell_corners, good_cells,
                     indecisive_cost, invert_cells)

FormantNets = dict  # "single/SG" | "pair/A+B" | "group/I+A+B" -> (*grid, K) formants of the net's EPs, Hz
TopNets = tuple  # (net key -> (*grid, 2) the EPs' tongue highest points, the model's rest's (2,)), cm


def within(target: TargetSpec, formants_hz, share: float = 1.0) -> bool:
    """F1 and F2 each within the target's tolerance (times ``share``)."""
    f = np.asarray(formants_hz, dtype=float)[:2]
    goal = np.asarray(target.acoustic.formants_hz[:2])
    return bool(np.all(np.isfinite(f)) and np.all(np.abs(f / goal - 1.0) <= share * target.acoustic.tolerance))


def errors_pct(target: TargetSpec, formants_hz) -> list[float]:
    goal = np.asarray(target.acoustic.formants_hz, dtype=float)
    f = np.asarray(formants_hz, dtype=float)[: len(goal)]
    return [round(float(100 * (a / b - 1.0)), 2) for a, b in zip(f, goal)]


class AcousticProblem:
    """An acoustic target on the maps (and formants) of one jaw position."""

    def __init__(self, jm: JawMaps, target: TargetSpec, formants: FormantNets, reach: float = 1.0,
                 tops: TopNets | None = None):
        self.jm, self.t = jm, target
        self.k = next(iter(formants.values())).shape[-1] if formants else 0  # formants per EP
        self.rest_top = None
        if target.tongue_highest is not None and tops is not None:  # the highest points ride with the formants
            nets, self.rest_top = tops
            formants = {k: np.concatenate([f, nets[k]], axis=-1) for k, f in formants.items() if k in nets}
        self.formants = formants
        goal = np.asarray(target.acoustic.formants_hz, dtype=float)
        self.goal_hz = goal
        self.goal = hz_to_bark(goal[:2])
        box = hz_to_bark(goal[:2] * (1 + target.acoustic.tolerance)) - self.goal  # the tolerance in Bark
        self.reach = reach * float(np.hypot(*box))  # cells and vectors searched within this Bark distance

    def cost(self, forces: dict[str, float], pred: np.ndarray, f_hz: np.ndarray, top: np.ndarray | None) -> float:
        c = indecisive_cost(self.t, forces, pred)
        if top is not None:
            c += self.t.distance_weight * float(np.sum(self.t.tongue_highest.shortfall_cm(top, self.rest_top) ** 2))
        if len(self.goal_hz) > 2 and np.isfinite(f_hz[2]):
            c += self.t.acoustic.f3_weight * self.t.distance_weight * float(hz_to_bark(f_hz[2]) -
                                                                            hz_to_bark(self.goal_hz[2])) ** 2
        return c

    def _candidate(self, family, name, forces, pred, f_hz, detail) -> Candidate:
        forces = {k: float(v) for k, v in forces.items() if v > 1e-12}
        f_hz, top = f_hz[: self.k], (f_hz[self.k:] if self.rest_top is not None else None)
        err = float(np.linalg.norm(hz_to_bark(f_hz[:2]) - self.goal))
        detail = dict(detail, formants_hz=[float(v) for v in f_hz])
        if top is not None:
            detail["tongue_top_cm"] = [float(v) for v in top]
        return Candidate(family=family, name=name, forces=forces,
                         predicted={cp: [float(pred[k, 0]), float(pred[k, 1])] for k, cp in enumerate(("tip", "dorsum"))},
                         crucial_error=err, cost=self.cost(forces, pred, f_hz, top), detail=detail)

    def singles(self) -> list[Candidate]:
        out = []
        for m, net in self.jm.single.items():
            f = self.formants.get(f"single/{m}")
            stop = settled_run(net)
            if f is None or stop < 2:
                continue
            f = f[:stop]
            ok = np.isfinite(f[:, :2]).all(axis=1)
            if not ok.all():  # a closed tract ends the usable part of the vector
                stop = int(np.argmin(ok)) if not ok[0] else 0
                if stop < 2:
                    continue
                f = f[:stop]
            d, k, frac = polyline_nearest(hz_to_bark(f[:, :2]), self.goal)
            if d > self.reach:
                continue
            lv = net.levels[0]
            force = lv[k] + frac * (lv[k + 1] - lv[k])
            pts = net.x[:stop, :2, :2]
            pred = pts[k] + frac * (pts[k + 1] - pts[k])
            f_hz = f[k] + frac * (f[k + 1] - f[k])
            out.append(self._candidate("single", m, {m: force}, pred, f_hz, {"segment": k, "fraction": frac}))
        return out

    def _nets(self):
        return mapped_nets(self.jm, self.formants)

    @staticmethod
    def _cells(x: np.ndarray, conv: np.ndarray, f: np.ndarray):
        """Cells whose four corners settled and have F1 and F2: indices, control-point corners (C, 4, 4) and
        formant corners (C, 4, K)."""
        ii, jj = good_cells(conv & np.isfinite(f[..., :2]).all(axis=-1))
        return ii, jj, cell_corners(x[..., :2, :2], ii, jj).reshape(len(ii), 4, 4), cell_corners(f, ii, jj)

    def nets(self) -> list[Candidate]:
        out = []
        for family, name, muscles, fixed, levels, x, conv, f in self._nets():
            ii, jj, cp, fc = self._cells(x, conv, f)
            if not len(ii):
                continue
            bark = hz_to_bark(fc[..., :2])
            u, v, _ = invert_cells(bark, self.goal)
            u, v = np.clip(u, 0.0, 1.0), np.clip(v, 0.0, 1.0)
            res = np.linalg.norm(bilinear(bark, u, v) - self.goal, axis=1)
            for k in np.flatnonzero(res <= self.reach):
                a, b = muscles[-2], muscles[-1]
                la, lb = levels
                forces = {a: la[ii[k]] + u[k] * (la[ii[k] + 1] - la[ii[k]])}
                forces[b] = forces.get(b, 0.0) + lb[jj[k]] + v[k] * (lb[jj[k] + 1] - lb[jj[k]])
                if fixed is not None:
                    forces[fixed[0]] = forces.get(fixed[0], 0.0) + fixed[1]
                uu, vv = np.array([u[k]]), np.array([v[k]])
                pred = bilinear(cp[k][None], uu, vv)[0].reshape(2, 2)
                f_hz = bilinear(fc[k][None], uu, vv)[0]
                label = name if fixed is None else f"{name} ({fixed[0]} {fixed[1]:g} N)"
                out.append(self._candidate(family, label, forces, pred, f_hz,
                                           {"cell": [int(ii[k]), int(jj[k])], "uv": [float(u[k]), float(v[k])],
                                            "net": name, "fixed": fixed}))
        return out

    def nearest(self) -> tuple[np.ndarray | None, float, str]:
        """The mapped formants (Hz) nearest the target in Bark (vectors exactly, net cells sampled)."""
        best: tuple = (None, np.inf, "")
        for m, net in self.jm.single.items():
            f = self.formants.get(f"single/{m}")
            if f is None:
                continue
            f = f[: settled_run(net)]
            f = f[np.isfinite(f[:, :2]).all(axis=1)]
            if len(f) < 2:
                continue
            d, k, frac = polyline_nearest(hz_to_bark(f[:, :2]), self.goal)
            if d < best[1]:
                best = (f[k] + frac * (f[k + 1] - f[k]), d, f"vector {m}")
        s = np.linspace(0, 1, 9)
        uu, vv = (g.ravel() for g in np.meshgrid(s, s, indexing="ij"))
        for family, name, _, fixed, _, x, conv, f in self._nets():
            _, _, _, fc = self._cells(x, conv, f)
            if not len(fc):
                continue
            c = np.repeat(fc[:, None], len(uu), axis=1)  # (C, S, 4, K)
            p = bilinear(c, np.broadcast_to(uu, c.shape[:2]), np.broadcast_to(vv, c.shape[:2]))
            d = np.linalg.norm(hz_to_bark(p[..., :2]) - self.goal, axis=-1)
            k = np.unravel_index(np.argmin(d), d.shape)
            if d[k] < best[1]:
                label = name if fixed is None else f"{name} ({fixed[0]} {fixed[1]:g} N)"
                best = (p[k], float(d[k]), f"{family} {label}")
        return best


def solve_acoustic_on(jm: JawMaps, target: TargetSpec, formants: FormantNets, widen: bool = False,
                      tops: TopNets | None = None) -> list[Candidate]:
    """Every candidate whose interpolated F1 and F2 are within tolerance, cheapest first (``tops``: the EPs'
    tongue highest points, for a target's ``tongue_highest``).  With ``widen`` (a refinement follows) and none
    within, the ones within twice the tolerance's Bark distance, nearest first."""
    p = AcousticProblem(jm, target, formants, reach=2.0 if widen else 1.0, tops=tops)
    found = p.singles() + p.nets()
    cands = sorted([c for c in found if within(target, c.detail["formants_hz"])], key=lambda c: c.cost)
    if not cands and widen:
        cands = sorted(found, key=lambda c: (c.crucial_error, c.cost))
    if not cands:
        f, dist, where = p.nearest()
        if f is None:
            raise UnreachableTarget(f"target '{target.name}': no settled EPs with formants to search")
        goal = target.acoustic.formants_hz
        raise UnreachableTarget(
            f"target '{target.name}': F1 {goal[0]:g} Hz, F2 {goal[1]:g} Hz are not reachable at this jaw position "
            f"with these lips; the nearest mapped formants are F1 {f[0]:.0f} Hz, F2 {f[1]:.0f} Hz ({where}), "
            f"{dist:.2f} Bark away (F1 {100 * (f[0] / goal[0] - 1):+.1f} %, F2 {100 * (f[1] / goal[1] - 1):+.1f} %)")
    return cands


def nearest_candidate(jm: JawMaps, target: TargetSpec, formants: FormantNets,
                      tops: TopNets | None = None) -> Candidate | None:
    """The force set whose interpolated formants come nearest the target (in Bark), however far."""
    p = AcousticProblem(jm, target, formants, reach=np.inf, tops=tops)
    found = p.singles() + p.nets()
    return min(found, key=lambda c: (c.crucial_error, c.cost)) if found else None
