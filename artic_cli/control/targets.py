"""Solving targets on EP maps: a target in, a force set out (with checks and refinement), one or a batch."""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..config import read_yaml
from ..errors import ArticError, UnreachableTarget
from ..validation import DEFAULT_MAX_FORCE_N
from .dynamic import DynamicMap, derive
from .epmap import EPMaps, JawMaps, canonical
from .solver import Candidate, TargetSpec, parse_target, solve_on

TOP = 5  # candidates listed in the output
REFINE_REACH_CM = 0.1  # with --refine and no candidate on target, ones this close may start the correction
REFINE_TRIES = 3  # candidates --refine may try in turn
# a formant refinement goes on, within its budget, until F1 and F2 are within this share of their tolerance:
# the sound measured by Praat differs from the transfer function by a few per cent (docs/modelling.md, Vowels)
AIM = 0.5


@dataclass
class Context:
    """What a target is solved on: the EP maps and (optionally) the dynamic map, with their content hashes;
    for acoustic targets ``formants(jaw, lip_area_cm2, lip_length_cm, velum_port_cm2)`` gives the formants
    of every EP at a mapped jaw position (``FormantNets``), and ``lips_default`` the config's lip tube."""

    maps: EPMaps
    dm: DynamicMap | None
    maps_sha256: str = ""
    dynamic_sha256: str | None = None
    formants: Callable[[str, float, float, float], dict] | None = None
    lips_default: tuple[float, float] = (3.0, 1.0)  # area cm^2, length cm
    port_default: float = 0.0  # cm^2
    acoustic_sha256: str | None = None  # the acoustic maps' content, when they gave the formants
    areas: Callable[[str], dict] | None = None  # constriction targets: jaw -> net key -> (*grid, S) areas, cm^2
    places: tuple | None = None  # (S,) each section's place index and the places' names
    tops: Callable[[str], dict] | None = None  # jaw -> net key -> (*grid, 2) the EPs' tongue highest points, cm


def jaw_maps(ctx: Context, target: TargetSpec) -> tuple[JawMaps, dict[str, float], float, str]:
    """Maps at the target's jaw position, its jaw forces, incisor height and how the maps were obtained."""
    maps = ctx.maps
    if target.jaw.forces_n is not None:
        want = canonical(dict(target.jaw.forces_n))
        for name, jm in maps.jaws.items():
            if canonical(jm.forces) == want and (jm.pair or jm.group):
                return jm, dict(jm.forces), float(jm.rest[2, 1]), f"simulated maps of jaw position {name}"
        if ctx.dm is None:
            raise ArticError(f"target '{target.name}': jaw forces {dict(target.jaw.forces_n)} need the dynamic map; "
                             "run 'artic dynamic-map' first")
        height = ctx.dm.height_for(dict(target.jaw.forces_n))
        forces = {k: float(v) for k, v in target.jaw.forces_n.items() if v > 0}
    else:
        if ctx.dm is None:
            raise ArticError(f"target '{target.name}': a jaw opening needs the dynamic map; run 'artic dynamic-map'")
        height = ctx.dm.rest_height + target.jaw.opening_cm
        forces = forces_for_height(ctx.dm, height)
    jm = derive(maps, ctx.dm, height)
    for name, stored in maps.jaws.items():  # simulated vectors where the jaw position was mapped
        if canonical(stored.forces) == canonical(forces):
            jm.single = stored.single
            jm.rest = stored.rest
    return jm, forces, height, f"typical map carried to incisor height {height:.3f} cm by the dynamic map"


def forces_for_height(dm: DynamicMap, height: float) -> dict[str, float]:
    signed = np.array([f.get("JC", 0.0) - f.get("JO", 0.0) for f in dm.jaw_forces])
    order = np.argsort(dm.height)
    h, s = dm.height[order], signed[order]
    if height < h[0] - 1e-9 or height > h[-1] + 1e-9:
        raise ArticError(f"jaw opening outside the mapped range ({h[0] - dm.rest_height:+.3f} to "
                         f"{h[-1] - dm.rest_height:+.3f} cm from rest); give one inside")
    v = float(np.interp(height, h, s))
    return {"JC": v} if v > 0 else ({"JO": -v} if v < 0 else {})


def _num(v) -> float:
    return round(float(v), 4)


def _cand(c: Candidate) -> dict:
    return {"family": c.family, "map": c.name, "forces_n": {k: _num(v) for k, v in c.forces.items()},
            "predicted_cm": {k: [_num(x) for x in v] for k, v in c.predicted.items()},
            "crucial_error_cm": _num(c.crucial_error), "cost": _num(c.cost)}


def mapped_jaw(ctx: Context, target: TargetSpec) -> tuple[str, JawMaps]:
    """The mapped jaw position whose forces are the target's (acoustic targets need the EPs' shapes)."""
    want = canonical(dict(target.jaw.forces_n or {}))
    for name, jm in ctx.maps.jaws.items():
        if canonical(jm.forces) == want:
            return name, jm
    have = ", ".join(f"{n} ({' '.join(f'{k} {v:g} N' for k, v in jm.forces.items()) or 'no force'})"
                     for n, jm in ctx.maps.jaws.items())
    raise ArticError(f"target '{target.name}': jaw forces {dict(target.jaw.forces_n or {})} are not a mapped jaw "
                     f"position; an acoustic target needs one of: {have}")


def _formant_doc(target: TargetSpec, f_hz, extra: dict | None = None) -> dict:
    from .acoustic_solver import errors_pct, within

    d = {"formants_hz": [_num(v) for v in f_hz], "errors_pct": errors_pct(target, f_hz),
         "within_tolerance": within(target, f_hz)}
    if extra:
        d.update(extra)
    return d


def _voiced_candidate(c: Candidate) -> dict:
    d = _cand(c)
    d.pop("crucial_error_cm")
    d = dict(d, predicted_formants_hz=[_num(v) for v in c.detail["formants_hz"]], bark_error=_num(c.crucial_error))
    if "tongue_top_cm" in c.detail:
        d["predicted_tongue_top_cm"] = [_num(v) for v in c.detail["tongue_top_cm"]]
    return d


def solve_acoustic(ctx: Context, target: TargetSpec, voicer=None, verify: bool = False, refine: bool = False,
                   budget: int = 8) -> dict:
    """An acoustic target: candidates from the EPs' formants, checked (``verify``) or corrected (``refine``)
    by ``voicer.voice(jaw_forces, forces, lips, port) -> dict(formants_hz, reached_cm, area_function)``."""
    from .acoustic_solver import nearest_candidate, solve_acoustic_on

    if ctx.formants is None:
        raise ArticError(f"target '{target.name}': acoustic targets need the formants of the maps' EPs; give "
                         "--acoustic-maps (from 'artic acoustic-map') or --mesh and --config")
    jaw, jm = mapped_jaw(ctx, target)
    lips = target.lip_tube(ctx.lips_default)
    port = ctx.port_default if target.velum_port_cm2 is None else float(target.velum_port_cm2)
    formants = ctx.formants(jaw, lips[0], lips[1], port)
    head = {"target": target.name,
            "jaw": {"forces_n": {k: _num(v) for k, v in jm.forces.items()}, "incisor_height_cm": _num(jm.rest[2, 1]),
                    "maps": f"simulated maps of jaw position {jaw}"},
            "acoustic": {"formants_hz": [float(v) for v in target.acoustic.formants_hz],
                         "tolerance_pct": target.acoustic.tolerance_pct},
            "lips": {"area_cm2": _num(lips[0]), "length_cm": _num(lips[1])}, "velum_port_cm2": _num(port)}
    tops = None
    if target.tongue_highest is not None and ctx.tops is not None:
        tops = (ctx.tops(jaw), ctx.tops.rest)
        head["tongue_highest"] = {"tongue": target.tongue_highest.tongue, "margin_cm": target.tongue_highest.margin_cm,
                                  "rest_top_cm": [_num(v) for v in tops[1]]}
    try:
        cands = solve_acoustic_on(jm, target, formants, widen=refine, tops=tops)
    except UnreachableTarget as err:  # the answer is still the nearest force set the maps know
        near = nearest_candidate(jm, target, formants, tops=tops)
        if near is not None:
            err.answer = dict(head, nearest=_voiced_candidate(near))
            if (verify or refine) and voicer is not None:  # ... and what it really gives
                v = voicer.voice(dict(jm.forces), near.forces, lips, port)
                err.answer["verified"] = _formant_doc(target, v["formants_hz"], {
                    "forces_n": {k: _num(f) for k, f in near.forces.items()}, "reached_cm": v["reached_cm"],
                    "area_function": v["area_function"], "simulations": 1})
        raise
    doc = dict(head, chosen=_voiced_candidate(cands[0]), candidates=[_voiced_candidate(c) for c in cands[:TOP]],
               candidates_considered=len(cands))
    if not (verify or refine):
        return doc
    voiced = lambda forces: voicer.voice(dict(jm.forces), forces, lips, port)  # noqa: E731
    first = voiced(cands[0].forces)
    doc["verified"] = _formant_doc(target, first["formants_hz"], {"reached_cm": first["reached_cm"],
                                                                  "area_function": first["area_function"],
                                                                  "simulations": 1})
    if refine:
        doc["refined"] = _refine_acoustic(jm, target, cands, formants, voiced, first, budget)
    return doc


def _refine_acoustic(jm, target: TargetSpec, cands: list[Candidate], formants, voiced, first: dict,
                     budget: int) -> dict:
    """Broyden steps on F1/F2 in Bark from the best candidates in turn (the first Jacobian from their map
    cells), within ``budget`` simulations in all; the best result, converged or not."""
    from ..units import hz_to_bark
    from .acoustic_solver import within
    from .verify import broyden, free_forces, map_jacobian, top_force

    goal = hz_to_bark(np.asarray(target.acoustic.formants_hz[:2], dtype=float))

    def measure(forces):
        v = voiced(forces)
        f = np.asarray(v["formants_hz"], dtype=float)[:2]
        feat = hz_to_bark(f) if np.all(np.isfinite(f)) else np.full(2, -10.0)  # a closed tract: far off
        return feat, v

    def feature(family, name, x):
        return hz_to_bark(formants[f"{family}/{name}"][..., :2])

    left, best, tried = budget - 1, None, []
    # a candidate that starts outside the tolerance gets a share of the budget and then the next one its turn
    # (the maps can mislead about a cell: they hold the jaw, the answer is checked with it free); the first,
    # if its simulation already lies within the tolerance, the whole budget to bring it to the aim
    share = max(3, budget // 2 - 1)
    for k, cand in enumerate(cands[:REFINE_TRIES]):
        if k > 0 and left < 2:
            break
        free = free_forces(cand)
        turn = left if k == 0 and within(target, first["formants_hz"]) else min(left, share)
        r = broyden(measure, map_jacobian(jm, cand, free, feature), cand.forces, free, goal,
                    lambda e, v: within(target, v["formants_hz"], AIM), turn,
                    first=(measure(cand.forces) if k > 0 else (hz_to_bark(np.asarray(first["formants_hz"][:2])), first)),
                    upper=top_force(jm))
        left -= r.simulations + (1 if k > 0 else 0)
        tried.append(f"{cand.family} {cand.name}")
        if best is None or r.error < best[0].error:
            best = (r, cand)
        if within(target, r.extra["formants_hz"]):
            break
    r, cand = best
    return _formant_doc(target, r.extra["formants_hz"], {
        "from": f"{cand.family} {cand.name}", "candidates_tried": tried,
        "forces_n": {k: _num(v) for k, v in r.forces.items()}, "reached_cm": r.extra["reached_cm"],
        "area_function": r.extra["area_function"], "bark_error": _num(r.error), "simulations": budget - left,
        "converged": within(target, r.extra["formants_hz"])})


def solve(ctx: Context, target: TargetSpec, simulator=None, verify: bool = False, refine: bool = False,
          budget: int = 8) -> dict:
    """Solve one target; returns the result document (plain data, units in the keys)."""
    if target.acoustic is not None:
        return solve_acoustic(ctx, target, simulator, verify, refine, budget)
    if target.constriction is not None:
        from .constriction import solve_constriction

        return solve_constriction(ctx, target, simulator, verify, refine, budget)
    jm, jaw_forces, height, how = jaw_maps(ctx, target)
    cands = solve_on(jm, target, REFINE_REACH_CM if refine else None)
    chosen = cands[0]
    doc = {"target": target.name, "jaw": {"forces_n": {k: _num(v) for k, v in jaw_forces.items()}, "incisor_height_cm": _num(height),
                                          "maps": how},
           "crucial": {"point": target.crucial.point, "at_cm": [float(v) for v in target.crucial.at_cm],
                       "tolerance_cm": target.crucial.tolerance_cm},
           "chosen": _cand(chosen), "candidates": [_cand(c) for c in cands[:TOP]],
           "candidates_considered": len(cands)}
    if verify or refine:
        from .verify import refine as do_refine

        goal = np.asarray(target.crucial.at_cm, dtype=float)
        c = ("tip", "dorsum").index(target.crucial.point)
        reached = simulator.reach(jaw_forces, chosen.forces)
        err = float(np.linalg.norm(reached[c, :2] - goal))
        doc["verified"] = {"reached_cm": {"tip": [_num(v) for v in reached[0, :2]],
                                          "dorsum": [_num(v) for v in reached[1, :2]]},
                           "crucial_error_cm": _num(err), "simulations": 1}
        if refine:
            # correct the cheapest candidate; if it cannot get there in its share of the budget, the next
            # ones: a cell the maps mislead about (the answer is checked with the jaw free, the maps held it)
            # would otherwise spend every simulation creeping
            left, best, tried = budget - 1, None, []
            share = max(3, budget // 2 - 1)
            for k, cand in enumerate(cands[:REFINE_TRIES]):
                first = reached if k == 0 else None
                if k > 0 and left < 1:  # one simulation still tells whether a candidate lands within tolerance
                    break
                r = do_refine(simulator, jm, jaw_forces, cand, target.crucial.point, goal,
                              target.crucial.tolerance_cm, budget=min(left, share), first=first)
                left -= r.simulations
                tried.append(f"{cand.family} {cand.name}")
                if best is None or r.error < best[0].error:
                    best = (r, cand)
                if r.error <= target.crucial.tolerance_cm:
                    break
            r, cand = best
            doc["refined"] = {"from": f"{cand.family} {cand.name}", "candidates_tried": tried,
                              "forces_n": {k: _num(v) for k, v in r.forces.items()},
                              "reached_cm": {"tip": [_num(v) for v in r.reached[0, :2]],
                                             "dorsum": [_num(v) for v in r.reached[1, :2]]},
                              "crucial_error_cm": _num(r.error), "simulations": budget - left,
                              "converged": bool(r.error <= target.crucial.tolerance_cm)}
    return doc


def load_target(path: Path | str, max_force_n: float = DEFAULT_MAX_FORCE_N) -> TargetSpec:
    return parse_target(read_yaml(path, "target file"), str(path), max_force_n)


# --- batches -----------------------------------------------------------------------------------------

BATCH_COLUMNS = ("name", "crucial", "crucial_x_cm", "crucial_y_cm")
OPTIONAL_COLUMNS = ("tolerance_cm", "indecisive", "indecisive_x_cm", "indecisive_y_cm", "weight", "jaw_JO_n",
                    "jaw_JC_n", "jaw_opening_cm")


def read_batch(path: Path | str) -> list[TargetSpec]:
    path = Path(path)
    if not path.is_file():
        raise ArticError(f"batch file not found: {path}; give an existing CSV")
    rows = list(csv.DictReader(io.StringIO(path.read_text())))
    if not rows:
        raise ArticError(f"{path}: no targets (a header line and one row per target)")
    missing = [c for c in BATCH_COLUMNS if c not in rows[0]]
    if missing:
        raise ArticError(f"{path}: missing column '{missing[0]}'; columns: {', '.join(BATCH_COLUMNS)} "
                         f"(optional: {', '.join(OPTIONAL_COLUMNS)})")
    unknown = [c for c in rows[0] if c not in BATCH_COLUMNS + OPTIONAL_COLUMNS]
    if unknown:
        raise ArticError(f"{path}: unknown column '{unknown[0]}'; optional columns: {', '.join(OPTIONAL_COLUMNS)}")
    out = []
    for k, r in enumerate(rows, start=2):
        def num(key):
            v = (r.get(key) or "").strip()
            if not v:
                return None
            try:
                x = float(v)
            except ValueError:
                raise ArticError(f"{path}, line {k}: column '{key}' must be a number, got {v!r}") from None
            if not math.isfinite(x):
                raise ArticError(f"{path}, line {k}: column '{key}' must be finite, got {v!r}")
            return x

        data = {"name": r["name"] or f"row{k}",
                "crucial": {"point": r["crucial"], "at_cm": [num("crucial_x_cm"), num("crucial_y_cm")]}}
        if num("tolerance_cm") is not None:
            data["crucial"]["tolerance_cm"] = num("tolerance_cm")
        if (r.get("indecisive") or "").strip():
            data["indecisive"] = [{"point": r["indecisive"].strip(),
                                   "at_cm": [num("indecisive_x_cm"), num("indecisive_y_cm")],
                                   **({"weight": num("weight")} if num("weight") is not None else {})}]
        if num("jaw_opening_cm") is not None:
            data["jaw"] = {"opening_cm": num("jaw_opening_cm")}
        elif num("jaw_JO_n") is not None or num("jaw_JC_n") is not None:
            data["jaw"] = {"forces_n": {k2: num(f"jaw_{k2}_n") for k2 in ("JO", "JC") if num(f"jaw_{k2}_n")}}
        out.append(parse_target(data, f"{path}, line {k}"))
    return out


def _solve_row(ctx: Context, target: TargetSpec, sim_args, verify: bool, refine: bool, budget: int) -> dict:
    sim = None
    if verify or refine:
        from .verify import Simulator

        sim = Simulator(*sim_args)
    try:
        return solve(ctx, target, sim, verify, refine, budget)
    except UnreachableTarget as err:
        return {"target": target.name, "unreachable": str(err)}


def solve_batch(ctx: Context, targets: list[TargetSpec], jobs: int = 2, sim_args=None, verify: bool = False,
                refine: bool = False, budget: int = 8, progress=None) -> list[dict]:
    """Every target of a batch; with ``verify``/``refine`` in parallel (``sim_args``: what
    :class:`~artic_cli.control.verify.Simulator` is built from in each worker)."""
    from ..parallel import Sweep, run_sweep

    if not (verify or refine):  # map look-ups only: cheaper in this process than shipping the maps
        out = []
        for k, t in enumerate(targets):
            out.append(_solve_row(ctx, t, None, False, False, budget))
            if progress:
                progress(k + 1, len(targets))
        return out
    calls = [(ctx, t, sim_args, verify, refine, budget) for t in targets]
    return run_sweep(_solve_row, calls, Sweep(jobs=jobs, progress=progress)).results


def batch_csv(results: list[dict]) -> str:
    cols = ["target", "status", "family", "map", "forces_n", "tip_x_cm", "tip_y_cm", "dorsum_x_cm", "dorsum_y_cm",
            "cost", "verified_error_cm", "refined_error_cm", "simulations", "message"]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols)
    w.writeheader()
    for d in results:
        if "unreachable" in d:
            w.writerow({"target": d["target"], "status": "unreachable", "message": d["unreachable"]})
            continue
        ch = d["chosen"]
        forces = d.get("refined", {}).get("forces_n", ch["forces_n"])
        w.writerow({"target": d["target"], "status": "ok", "family": ch["family"], "map": ch["map"],
                    "forces_n": ";".join(f"{k}={v:g}" for k, v in forces.items()),
                    "tip_x_cm": ch["predicted_cm"]["tip"][0], "tip_y_cm": ch["predicted_cm"]["tip"][1],
                    "dorsum_x_cm": ch["predicted_cm"]["dorsum"][0], "dorsum_y_cm": ch["predicted_cm"]["dorsum"][1],
                    "cost": ch["cost"], "verified_error_cm": d.get("verified", {}).get("crucial_error_cm"),
                    "refined_error_cm": d.get("refined", {}).get("crucial_error_cm"),
                    "simulations": d.get("refined", d.get("verified", {})).get("simulations")})
    return buf.getvalue()
