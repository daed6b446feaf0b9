"""Solving targets on EP maps: a target in, a force set out (with checks and refinement), one or a batch."""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..config import read_yaml
from ..errors import ArticError, UnreachableTarget
from .dynamic import DynamicMap, derive
from .epmap import EPMaps, JawMaps, canonical
from .solver import Candidate, TargetSpec, parse_target, solve_on

TOP = 5  # candidates listed in the output
REFINE_REACH_CM = 0.1  # with --refine and no candidate on target, ones this close may start the correction
REFINE_TRIES = 3  # candidates --refine may try in turn


@dataclass
class Context:
    """What a target is solved on: the EP maps and (optionally) the dynamic map, with their content hashes."""

    maps: EPMaps
    dm: DynamicMap | None
    maps_sha256: str = ""
    dynamic_sha256: str | None = None


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


def solve(ctx: Context, target: TargetSpec, simulator=None, verify: bool = False, refine: bool = False,
          budget: int = 8) -> dict:
    """Solve one target; returns the result document (plain data, units in the keys)."""
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
            # correct the cheapest candidate; if it cannot get there, the next ones, within the budget
            left, best, tried = budget - 1, None, []
            for k, cand in enumerate(cands[:REFINE_TRIES]):
                first = reached if k == 0 else None
                if k > 0 and left < 2:
                    break
                r = do_refine(simulator, jm, jaw_forces, cand, target.crucial.point, goal,
                              target.crucial.tolerance_cm, budget=left, first=first)
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


def load_target(path: Path | str) -> TargetSpec:
    return parse_target(read_yaml(path, "target file"), str(path))


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
