"""Equilibrium-position (EP) maps: the paper's section IV.B.

An EP is where the tongue tip, the dorsum and the jaw come to rest when a set
of muscle forces is held (300 ms from the rest posture of a jaw position, the
jaw force held throughout).  A map is a family of EPs:

* single-muscle EP vectors: one muscle (or group such as T-SL) at increasing
  force levels, at every jaw position;
* two-muscle contour nets: a grid of force pairs (Fig. 8, right);
* three-muscle co-contraction groups: an independent muscle at a few
  co-contraction levels, each with a two-muscle net (section V.A).

Every EP is one task (jaw position, muscle forces), computed by
:mod:`artic_cli.control.equilibrium`; this module says which tasks a spec
needs (:func:`plan`), puts their results together (:func:`assemble`) and
reads Table III off them.  The sweep, its cache and the file live in
:mod:`artic_cli.stages.epmap`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..config import Config, EPMapSpec
from ..errors import ArticError
from ..geometry.anatomy import JAW_MUSCLES, TONGUE_MUSCLES, check_muscle_names
from ..mechanics.model import CONTROL_POINTS
from .equilibrium import EP, Forces, add_forces, canonical

__all__ = ["CONTROL_POINTS", "EP", "EPMaps", "Forces", "JawMaps", "Net", "Task", "add_forces", "assemble",
           "canonical", "check_spec", "contribution_factors", "drivable_names", "monotonic_exceptions", "pairs",
           "plan"]


@dataclass(frozen=True)
class Task:
    jaw: str
    forces: Forces  # tongue muscles (N), the jaw position's forces not included


# --- the specification -----------------------------------------------------------------------------

def drivable_names(cfg: Config) -> list[str]:
    return [*TONGUE_MUSCLES, *JAW_MUSCLES, *cfg.muscles.groups]


def pairs(spec: EPMapSpec) -> list[tuple[str, str]]:
    """The two-muscle nets, tip and dorsum lists merged (a net gives both control points)."""
    seen, out = set(), []
    for a, b in [*spec.pairs_tip, *spec.pairs_dorsum]:
        if frozenset((a, b)) not in seen:
            seen.add(frozenset((a, b)))
            out.append((a, b))
    return out


def check_spec(cfg: Config) -> None:
    """Every name in the map spec exists: one ArticError naming the first that does not."""
    spec = cfg.epmap
    valid = drivable_names(cfg)
    where = [("epmap.muscles", spec.muscles)]
    where += [("epmap.pairs_tip", p) for p in spec.pairs_tip] + [("epmap.pairs_dorsum", p) for p in spec.pairs_dorsum]
    where += [("epmap.groups", [g.independent, *g.pair]) for g in spec.groups]
    where += [(f"epmap.jaw_positions.{name}", list(forces)) for name, forces in spec.jaw_positions.items()]
    for key, names in where:
        check_muscle_names(names, valid, key)
    for key, names in (("epmap.typical_jaw", [spec.typical_jaw]), ("epmap.net_jaw_positions", spec.net_jaw_positions)):
        check_muscle_names(names, list(spec.jaw_positions), key, "jaw position")
    if 0.0 not in spec.levels_n:
        raise ArticError("config: epmap.levels_n must include 0.0 (the rest of each vector)")


def plan(spec: EPMapSpec) -> list[Task]:
    """Every EP the spec needs, each once (a pair net's axes are single-muscle EPs, and so on)."""
    tasks: dict[Task, None] = {}

    def add(jaw: str, forces: dict[str, float]) -> None:
        key = canonical(forces)
        if key:  # all zero: the jaw position's rest, computed separately
            tasks[Task(jaw, key)] = None

    for jaw in spec.jaw_positions:
        for m in spec.muscles:
            for f in spec.levels_n:
                add(jaw, {m: f})
    grid = [0.0, *spec.pair_levels_n]
    for jaw in spec.net_jaw_positions:
        for a, b in pairs(spec):
            for fa in grid:
                for fb in grid:
                    add(jaw, add_forces({a: fa}, {b: fb}))
        for g in spec.groups:
            for fi in [0.0, *spec.group_levels_n]:
                for fa in grid:
                    for fb in grid:
                        add(jaw, add_forces({g.independent: fi}, {g.pair[0]: fa}, {g.pair[1]: fb}))
    return list(tasks)


@dataclass
class Net:
    """EPs over a grid of forces: ``x[..., c, :]`` is control point c (tip, dorsum, jaw) in cm."""

    muscles: tuple[str, ...]
    levels: tuple[np.ndarray, ...]  # force levels (N) of each muscle, axis by axis
    x: np.ndarray  # (*grid, 3, 3)
    converged: np.ndarray  # (*grid,)
    drift_cm: np.ndarray  # (*grid,)
    shapes: np.ndarray | None = None  # (*grid, N, 3) every node at each EP, cm (float32)


@dataclass
class JawMaps:
    forces: dict[str, float]
    rest: np.ndarray  # (3, 3)
    single: dict[str, Net]
    pair: dict[str, Net] = field(default_factory=dict)
    group: dict[str, Net] = field(default_factory=dict)
    mandible: np.ndarray | None = None  # (K, 3) the mandible's nodes at this jaw position's rest, cm
    rest_shape: np.ndarray | None = None  # (N, 3) every node at this jaw position's rest, cm


@dataclass
class EPMaps:
    jaws: dict[str, JawMaps]
    typical_jaw: str
    attrs: dict = field(default_factory=dict)
    model_rest: np.ndarray | None = None  # (N, 3) the model's rest (bones' motions are measured from it), cm
    mandible_nodes: np.ndarray | None = None  # node indices of the mandible

    def unconverged(self) -> list[str]:
        out = []
        for jname, jm in self.jaws.items():
            for fam in ("single", "pair", "group"):
                for name, net in getattr(jm, fam).items():
                    n = int((~net.converged).sum())
                    if n:
                        out.append(f"{jname}/{fam}/{name}: {n} of {net.converged.size}")
        return out


def assemble(spec: EPMapSpec, rests: dict[str, np.ndarray], eps: dict,
             mandibles: dict[str, np.ndarray] | None = None, rest_shapes: dict[str, np.ndarray] | None = None
             ) -> EPMaps:
    def get(jaw: str, forces: dict[str, float]):
        key = canonical(forces)
        if not key:
            return rests[jaw], 0.0, True, None if rest_shapes is None else rest_shapes[jaw]
        r = eps[(jaw, key)]
        return r["x"], r["drift_cm"], r["converged"], r.get("shape")

    def net(jaw: str, muscles: tuple[str, ...], levels: tuple) -> Net:
        shape = tuple(len(lv) for lv in levels)
        x = np.zeros(shape + (3, 3))
        conv = np.zeros(shape, dtype=bool)
        drift = np.zeros(shape)
        shapes = None
        for idx in np.ndindex(*shape):
            xi, d, c, sh = get(jaw, add_forces(*({m: lv[i]} for m, lv, i in zip(muscles, levels, idx))))
            x[idx], drift[idx], conv[idx] = xi, d, c
            if sh is not None:
                if shapes is None:
                    shapes = np.zeros(shape + sh.shape, dtype=np.float32)
                shapes[idx] = sh
        return Net(muscles=muscles, levels=tuple(np.asarray(lv, dtype=float) for lv in levels), x=x,
                   converged=conv, drift_cm=drift, shapes=shapes)

    jaws = {}
    grid = [0.0, *spec.pair_levels_n]
    for jaw, jf in spec.jaw_positions.items():
        jm = JawMaps(forces=dict(jf), rest=rests[jaw],
                     single={m: net(jaw, (m,), (spec.levels_n,)) for m in spec.muscles},
                     mandible=None if mandibles is None else mandibles[jaw],
                     rest_shape=None if rest_shapes is None else rest_shapes[jaw])
        if jaw in spec.net_jaw_positions:
            for a, b in pairs(spec):
                jm.pair[f"{a}+{b}"] = net(jaw, (a, b), (grid, grid))
            for g in spec.groups:
                jm.group[f"{g.independent}+{g.pair[0]}+{g.pair[1]}"] = net(
                    jaw, (g.independent, *g.pair), ([0.0, *spec.group_levels_n], grid, grid))
        jaws[jaw] = jm
    return EPMaps(jaws=jaws, typical_jaw=spec.typical_jaw)


def contribution_factors(maps: EPMaps, jaw: str) -> dict:
    """Table III: EP-vector amplitude from 0 to the top force, normalised by the largest, per control point."""
    jm = maps.jaws[jaw]
    amp = {m: [float(np.linalg.norm(n.x[-1, c] - n.x[0, c])) for c in (0, 1)] for m, n in jm.single.items()}
    top = [max(a[c] for a in amp.values()) or 1.0 for c in (0, 1)]
    return {"jaw": jaw, "amplitude_cm": amp,
            "factor": {m: [a[0] / top[0], a[1] / top[1]] for m, a in amp.items()}}


MONOTONIC_TOL_CM = 0.005


def monotonic_exceptions(maps: EPMaps) -> list[str]:
    """EP vectors whose distance from rest ever falls as the force rises (beyond 0.005 cm)."""
    out = []
    for jname, jm in maps.jaws.items():
        for m, n in jm.single.items():
            for c, cp in enumerate(("tip", "dorsum")):
                dist = np.linalg.norm(n.x[:, c] - n.x[0, c], axis=1)
                drop = np.flatnonzero(np.diff(dist) < -MONOTONIC_TOL_CM)
                for k in drop:
                    out.append(f"{jname} {m} {cp}: {dist[k]:.3f} -> {dist[k + 1]:.3f} cm from rest between "
                               f"{n.levels[0][k]:g} and {n.levels[0][k + 1]:g} N")
    return out


