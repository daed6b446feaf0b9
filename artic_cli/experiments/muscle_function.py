"""Muscle function from scattered starts (the paper's section IV.A.1, Figs. 5 and 6).

Starting points: from the rest posture, a combination of three muscles (for
example GGp-GGm-GGa) held for 120 ms at every triple of six force levels
(4 combinations x 6^3 = 864 starts).  From each start all forces are released
and one muscle pulls at 4 N for 150 ms; the end points of the tip and the
dorsum show where each muscle drives them whatever the start.  As in the
paper the wall is left out (``muscle_function.contact``); the mandible is
free, or held at its rest as the EP maps hold it (``muscle_function.hold_jaw``).

Each distinct start force set is one task (its 120-ms run and the ten 150-ms
drives; the combinations share muscles, so 864 starts are 726 distinct ones),
run in parallel and cached like the EP maps (:mod:`artic_cli.stages.muscle_function`).
This module is the physics of one start.
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass

import numpy as np

from .. import units
from ..config import Config, ConfigView, parse_config
from ..control.equilibrium import control_for, watch_nodes
from ..geometry.mesh import Mesh
from ..geometry.wall import WallSurface
from ..mechanics.model import ARTICULATOR_SECTIONS, Model, build_articulator
from ..mechanics.jaw_hold import fresh_start, hold_jaw
from ..mechanics.simulate import hold, settle

_CACHE: dict[str, tuple[Model, object]] = {}


def model_and_rest(key: str, cfg_json: str, mesh: Mesh, wall: WallSurface) -> tuple[Model, object]:
    """The articulator (wall contact as ``muscle_function.contact`` says, the mandible held at its rest if
    ``muscle_function.hold_jaw``) and its rest, once per process."""
    if key not in _CACHE:
        cfg = parse_config(json.loads(cfg_json), "<muscle-function config>")
        model = build_articulator(ConfigView(cfg, ARTICULATOR_SECTIONS), mesh, wall, contact=cfg.muscle_function.contact)
        rest = settle(model)
        if cfg.muscle_function.hold_jaw:
            model, rest = hold_jaw(model, rest.x), fresh_start(rest)
        _CACHE.clear()
        _CACHE[key] = (model, rest)
    return _CACHE[key]


def starts(cfg: Config) -> list[tuple[int, tuple[float, ...]]]:
    spec = cfg.muscle_function
    return [(c, lv) for c in range(len(spec.start_combinations))
            for lv in itertools.product(spec.start_levels_n, repeat=len(spec.start_combinations[c]))]


def run_start(key: str, start_forces: tuple, start_ms: float, muscles: tuple[str, ...], drive_n: float,
              drive_ms: float, cfg_json: str, mesh: Mesh, wall: WallSurface) -> dict:
    """One start (``start_forces``: canonical (muscle, N) pairs) and every muscle's drive from it (cm)."""
    model, rest = model_and_rest(key, cfg_json, mesh, wall)
    watch = watch_nodes(model)
    forces = dict(start_forces)
    h = hold(model, rest, control_for(model, forces), units.ms_to_s(start_ms), watch, units.ms_to_s(start_ms))
    start = h.state
    ends = []
    for m in muscles:
        d = hold(model, start, control_for(model, {m: drive_n}), units.ms_to_s(drive_ms), watch,
                 units.ms_to_s(drive_ms))
        ends.append(d.state.x[watch])
    return {"start": start.x[watch].copy(), "ends": np.array(ends)}


@dataclass
class MuscleFunction:
    muscles: list[str]
    combinations: list[list[str]]
    combo: np.ndarray  # (S,) index of each start's combination
    start_forces: np.ndarray  # (S, 3) N
    starts: np.ndarray  # (S, 3, 3): tip, dorsum, jaw (cm)
    ends: np.ndarray  # (M, S, 3, 3)
    rest: np.ndarray  # (3, 3)
    drive_n: float
    drive_ms: float


def convergence(mf: MuscleFunction) -> list[dict]:
    """Per muscle and control point: start spread, end spread (cm) and the mean end displacement from rest."""
    rows = []
    for k, m in enumerate(mf.muscles):
        for c, cp in enumerate(("tip", "dorsum")):
            s = mf.starts[:, c, :2]
            e = mf.ends[k, :, c, :2]
            rows.append({"muscle": m, "point": cp, "start_spread_cm": float(np.sqrt(s.var(axis=0).sum())),
                         "end_spread_cm": float(np.sqrt(e.var(axis=0).sum())),
                         "mean_end_from_rest_cm": [float(v) for v in e.mean(axis=0) - mf.rest[c, :2]]})
    return rows
