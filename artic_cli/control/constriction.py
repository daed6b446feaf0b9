"""Solving a constriction target: candidates on the maps (:mod:`.constriction_solver`), checked by simulation
(the forces held as ``artic simulate`` runs them, the area function of where they take the tongue) and
refined along the candidate's own forces.

A place's area changes with the forces' size in one direction: a closure that the maps' EPs (the jaw held)
only approach is met by pressing on, a channel that comes out too wide or too narrow by a little more or
less.  The refinement scales the candidate's tongue forces (its jaw forces kept) by a factor s: up by
doubling until the area meets or passes the goal (at most the muscles' largest force), then by bisection to
the smallest factor that meets it (a stop presses just enough, as a virtual target beyond the wall does for
speakers: Loefqvist & Gracco 1997).  The factor is the computed counterpart of an utterance's hand-set
``press``.
"""

from __future__ import annotations

import numpy as np

from ..errors import ArticError, UnreachableTarget
from ..tract.places import place_area, place_index
from .constriction_solver import ConstrictionProblem, solve_constriction_on
from .solver import Candidate, TargetSpec

TOP = 5
WIDEN = 3  # with refinement and no candidate on the goal: this many nearest start it


def _num(v) -> float:
    return round(float(v), 6)


def _cand(c: Candidate) -> dict:
    return {"family": c.family, "map": c.name, "forces_n": {k: _num(v) for k, v in c.forces.items()},
            "predicted_cm": {k: [_num(x) for x in v] for k, v in c.predicted.items()},
            "place_area_cm2": _num(c.detail["place_area_cm2"]), "cost": _num(c.cost)}


def nearest_candidates(jm, target: TargetSpec, areas: dict, count: int = WIDEN) -> list[Candidate]:
    """Where to start a refinement when no candidate meets the goal: on each vector the least force (above
    0 N: a force that can be scaled) whose place area comes nearest the goal, nearest first."""
    from .solver import settled_run

    p = ConstrictionProblem(jm, target, areas)
    g = target.constriction
    out = []
    for m, net in jm.single.items():
        a = areas.get(f"single/{m}")
        stop = settled_run(net)
        if a is None or stop < 2:
            continue
        err = np.abs(np.asarray(a[1:stop], float) - g.area_cm2)
        if not np.isfinite(err).any():
            continue
        k = 1 + int(np.nanargmin(err))
        out.append(p.candidate("single", m, {m: float(net.levels[0][k])}, net.x[k, :2, :2], float(a[k]),
                                {"segment": k, "fraction": 0.0}))
    out += _nearest_on_nets(p, g.area_cm2)
    return sorted(out, key=lambda c: (round(c.crucial_error, 3), c.cost))[:count]


def _nearest_on_nets(p: ConstrictionProblem, goal: float) -> list[Candidate]:
    """On each two-muscle net and co-contraction level: the settled EP (not the one of no force) whose place
    area comes nearest the goal."""
    out = []
    for family, name, muscles, fixed, levels, x, conv, a in p.nets_of_areas():
        err = np.where(conv & np.isfinite(a), np.abs(a - goal), np.inf)
        err[0, 0] = np.inf
        if not np.isfinite(err).any():
            continue
        i, j = np.unravel_index(int(np.argmin(err)), err.shape)
        forces = {muscles[-2]: float(levels[0][i])}
        forces[muscles[-1]] = forces.get(muscles[-1], 0.0) + float(levels[1][j])
        if fixed is not None:
            forces[fixed[0]] = forces.get(fixed[0], 0.0) + fixed[1]
        label = name if fixed is None else f"{name} ({fixed[0]} {fixed[1]:g} N)"
        out.append(p.candidate(family, label, forces, x[i, j, :2, :2], float(a[i, j]), {"node": [int(i), int(j)]}))
    return out


def solve_constriction(ctx, target: TargetSpec, voicer=None, verify: bool = False, refine: bool = False,
                       budget: int = 8) -> dict:
    """A constriction target: candidates from the EPs' area functions, checked (``verify``) or corrected
    (``refine``) by ``voicer.voice`` (the simulated area function)."""
    from .targets import mapped_jaw

    if ctx.areas is None or ctx.places is None:
        raise ArticError(f"target '{target.name}': constriction targets need the area functions of the maps' EPs; "
                         "give --acoustic-maps (from 'artic acoustic-map') or --mesh and --config")
    g = target.constriction
    region, names = ctx.places
    index = place_index(names, g.place, f"target '{target.name}': constriction.place")
    jaw, jm = mapped_jaw(ctx, target)
    areas = {k: place_area(a, region, index) for k, a in ctx.areas(jaw).items() if k != "rest"}
    head = {"target": target.name,
            "jaw": {"forces_n": {k: _num(v) for k, v in jm.forces.items()}, "incisor_height_cm": _num(jm.rest[2, 1]),
                    "maps": f"simulated maps of jaw position {jaw}"},
            "constriction": {"place": g.place, "area_cm2": g.area_cm2, "tolerance_cm2": g.tolerance_cm2}}
    try:
        cands = solve_constriction_on(jm, target, areas)
    except UnreachableTarget as err:
        near = nearest_candidates(jm, target, areas)
        if not (refine and near and voicer is not None):
            if near:
                err.answer = dict(head, nearest=_cand(near[0]))
            raise
        cands = near  # the refinement may get there from the nearest
    doc = dict(head, chosen=_cand(cands[0]), candidates=[_cand(c) for c in cands[:TOP]],
               candidates_considered=len(cands))
    if not (verify or refine):
        return doc
    lips, port = ctx.lips_default, ctx.port_default

    def measure(forces: dict[str, float]) -> dict:
        v = voicer.voice(dict(jm.forces), forces, lips, port)
        return dict(v, place_area_cm2=float(place_area(np.asarray(v["area_function"]["area_cm2"]), region, index)))

    first = measure(cands[0].forces)
    doc["verified"] = _measured(target, cands[0].forces, first, 1)
    if refine:
        doc["refined"] = refine_constriction(target, cands, measure, first, budget, ctx_max_force(jm))
    return doc


def ctx_max_force(jm) -> float:
    """The largest force the maps sweep a muscle to (N): the top of the refinement's scaling."""
    return float(max(max(net.levels[0]) for net in jm.single.values())) if jm.single else 6.0


def _measured(target: TargetSpec, forces: dict, m: dict, simulations: int, **extra) -> dict:
    return dict({"forces_n": {k: _num(v) for k, v in forces.items()}, "place_area_cm2": _num(m["place_area_cm2"]),
                 "met": target.constriction.met(m["place_area_cm2"]), "reached_cm": m["reached_cm"],
                 "area_function": m["area_function"], "simulations": simulations}, **extra)


def refine_constriction(target: TargetSpec, cands: list[Candidate], measure, first: dict, budget: int,
                        top_n: float) -> dict:
    """Scale each candidate's forces (in turn, within ``budget`` simulations in all) to the smallest factor
    whose simulated place area meets the goal."""
    g = target.constriction
    left, best, tried = budget - 1, None, []
    for k, cand in enumerate(cands[:3]):
        if k > 0 and left < 1:
            break
        m0 = first if k == 0 else measure(cand.forces)
        left -= 0 if k == 0 else 1
        r = _scale(g, cand.forces, measure, m0, left, top_n)
        left -= r["simulations"]
        tried.append(f"{cand.family} {cand.name}")
        err = abs(r["m"]["place_area_cm2"] - g.area_cm2)
        if best is None or err < best[0]:
            best = (err, r, cand)
        if g.met(r["m"]["place_area_cm2"]):
            break
    _, r, cand = best
    return _measured(target, r["forces"], r["m"], budget - left, **{
        "from": f"{cand.family} {cand.name}", "candidates_tried": tried, "scale": _num(r["scale"]),
        "converged": g.met(r["m"]["place_area_cm2"])})


def _scale(g, forces: dict, measure, m0: dict, budget: int, top_n: float) -> dict:
    """The smallest factor on ``forces`` whose place area meets the goal (or the nearest tried)."""
    scaled = lambda s: {k: v * s for k, v in forces.items()}  # noqa: E731
    done = {1.0: m0}
    err = lambda m: m["place_area_cm2"] - g.area_cm2  # noqa: E731 - > 0: too wide
    s_max = top_n / max(max(forces.values()), 1e-9) if forces else 1.0
    used = 0
    lo, hi = None, None  # the factors either side of the goal
    s = 1.0
    while used < budget and not g.met(done[s]["place_area_cm2"]):
        e = err(done[s])
        if e > 0:
            lo = s
            s_next = 2.0 * s if hi is None else 0.5 * (s + hi)
            if s_next > s_max + 1e-9:
                if s >= s_max - 1e-9:
                    break
                s_next = s_max
        else:
            hi = s
            s_next = 0.5 * s if lo is None else 0.5 * (lo + s)
        s = round(s_next, 6)
        if s in done:
            break
        done[s] = measure(scaled(s))
        used += 1
    met = [f for f, m in done.items() if g.met(m["place_area_cm2"])]
    if met and lo is not None and min(met) > lo:  # press no harder than it takes: two halvings toward the last miss
        top = min(met)
        for _ in range(min(2, budget - used)):
            mid = round(0.5 * (lo + top), 6)
            done[mid] = measure(scaled(mid))
            used += 1
            if g.met(done[mid]["place_area_cm2"]):
                top = mid
            else:
                lo = mid
        met = [f for f, m in done.items() if g.met(m["place_area_cm2"])]
    s = min(met) if met else min(done, key=lambda f: abs(err(done[f])))
    return {"forces": scaled(s), "m": done[s], "scale": s, "simulations": used}
