"""Forward checks of a force set: simulate it, and (beyond the paper) refine it.

A force set from the EP maps is checked by holding it, with the jaw force,
from the jaw position's rest for the maps' duration (exactly how the maps were
made) and reading the control points.  ``refine`` then corrects the free
forces of the chosen candidate (the pair of a net, or a vector's muscle) by
quasi-Newton steps: the first Jacobian comes from the map cell the candidate
lies in, later ones from Broyden's update with each simulation.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from ..config import Config
from ..geometry.mesh import Mesh
from ..geometry.wall import WallSurface
from .. import units
from ..io.fingerprint import code_hash, digest, sections_hash
from ..mechanics.replay import held_forces, run_schedule
from ..mechanics.model import ARTICULATOR_SECTIONS, CONTROL_POINTS
from .epmap import JawMaps, add_forces, canonical
from .equilibrium import equilibrium_state, watch_nodes, worker_model, worker_rest
from .solver import Candidate

MAX_STEP_N = 1.5  # largest change of one force per refinement step


class Simulator:
    """The articulator of a mesh and config, checking force sets as ``artic simulate`` runs them: every force
    (jaw and tongue) switched on together from the rest posture and held ``solver.verify_ms`` with the jaw
    free.  ``hold_jaw`` (default ``solver.verify_hold_jaw``): the maps' condition instead, the forces held from
    the jaw position's rest with its mandible held.  The model and its rests are built once per process."""

    def __init__(self, cfg: Config, mesh: Mesh, wall: WallSurface, mesh_sha256: str, hold_jaw: bool | None = None):
        self.cfg = cfg
        self.mesh, self.wall, self.mesh_sha256 = mesh, wall, mesh_sha256
        self.hold_jaw = cfg.solver.verify_hold_jaw if hold_jaw is None else bool(hold_jaw)
        self.key = digest({"sections": sections_hash(cfg, ARTICULATOR_SECTIONS), "mesh": mesh_sha256,
                           "code": code_hash("artic_cli.control.equilibrium")})
        self.cfg_json = json.dumps(cfg.model_dump(mode="json"))

    @property
    def simulation(self) -> "Simulator":
        """The plain simulator (itself; a :class:`~.voicing.Voicer` answers with the one it wraps)."""
        return self

    def conditions(self) -> dict:
        """How this simulator checks an answer (what a solution file records, and what replays it)."""
        if self.hold_jaw:
            spec = self.cfg.epmap
            return {"jaw": "held", "start": "the jaw position's rest", "duration_ms": spec.duration_ms,
                    "extend_ms": spec.extend_ms, "dt_ms": self.cfg.simulation.dt_ms,
                    "config_sections_sha256": sections_hash(self.cfg, (*ARTICULATOR_SECTIONS, "epmap")),
                    "mesh_sha256": self.mesh_sha256}
        return {"jaw": "free", "start": "the rest posture", "duration_ms": self.cfg.solver.verify_ms,
                "dt_ms": self.cfg.simulation.dt_ms, "forces": "every force on at 0 ms, held (artic simulate)",
                "config_sections_sha256": sections_hash(self.cfg, ARTICULATOR_SECTIONS),
                "mesh_sha256": self.mesh_sha256}

    def _model(self):
        return worker_model(self.key, self.cfg_json, self.mesh, self.wall)

    def reach(self, jaw_forces: dict[str, float], forces: dict[str, float]) -> np.ndarray:
        """(3, 3) tip, dorsum, jaw (cm) where the forces take the articulators."""
        return self.shape(jaw_forces, forces)[1]

    def shape(self, jaw_forces: dict[str, float], forces: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """The whole shape (N, 3) and the control points (3, 3) where the forces take the articulators."""
        model = self._model()
        total = add_forces(dict(jaw_forces), forces)
        if self.hold_jaw:
            start = worker_rest(self.key, canonical(jaw_forces), self.cfg_json, self.mesh, self.wall)
            state, ep = equilibrium_state(model, start, total, self.cfg.epmap)
            return state.x, ep.x
        rest = worker_rest(self.key, canonical({}), self.cfg_json, self.mesh, self.wall)  # the settled rest
        duration_ms = self.cfg.solver.verify_ms
        traj = run_schedule(model, held_forces(total, duration_ms, self.cfg.muscles.max_force_n),
                            units.ms_to_s(duration_ms), start=rest)
        x = traj.x[-1]
        return x, x[watch_nodes(model)].copy()

    def model_rest(self) -> tuple[np.ndarray, np.ndarray]:
        model = self._model()
        return model.rest, np.asarray(model.node_sets["mandible"])


@dataclass
class Refinement:
    forces: dict[str, float]
    reached: np.ndarray  # (3, 3)
    error: float  # crucial-feature error, cm
    simulations: int
    history: list[dict] = field(default_factory=list)


def free_forces(candidate: Candidate) -> list[str]:
    if candidate.family == "single":
        return [candidate.name]  # (its force may be 0: the jaw position's rest)
    net = candidate.detail["net"]
    a, b = net.split("+")[-2:]
    return [a, b]


def map_jacobian(jm: JawMaps, candidate: Candidate, free: list[str], feature) -> np.ndarray:
    """d(feature)/d(free forces) (2, n) from the map around the candidate; ``feature(family, net_name, x)``
    gives the (..., 2) feature of a net's EPs (x: the net's control points)."""
    if candidate.family == "single":
        net = jm.single[free[0]]
        k = candidate.detail["segment"]
        f = feature("single", free[0], net.x)
        return ((f[k + 1] - f[k]) / (net.levels[0][k + 1] - net.levels[0][k]))[:, None]
    name = candidate.detail["net"]
    family = "pair" if name in jm.pair else "group"
    net = jm.pair.get(name) or jm.group[name]
    f, levels = feature(family, name, net.x), net.levels
    if candidate.family == "group":
        fixed = candidate.detail["fixed"][1]
        k = int(np.argmin(np.abs(levels[0] - fixed)))
        f, levels = f[k], levels[1:]
    i, j = candidate.detail["cell"]
    u, v = candidate.detail["uv"]
    p00, p10, p01, p11 = f[i, j], f[i + 1, j], f[i, j + 1], f[i + 1, j + 1]
    du = (1 - v) * (p10 - p00) + v * (p11 - p01)
    dv = (1 - u) * (p01 - p00) + u * (p11 - p10)
    return np.column_stack([du / (levels[0][i + 1] - levels[0][i]), dv / (levels[1][j + 1] - levels[1][j])])


@dataclass
class Correction:
    forces: dict[str, float]
    feature: np.ndarray  # the measured feature of the best force set
    extra: object  # what the measurement gave besides the feature (for the best force set)
    error: float  # distance of the feature from the goal
    simulations: int
    history: list[dict] = field(default_factory=list)


def top_force(jm: JawMaps) -> float:
    """The largest force the maps of a jaw position hold (a refinement stays within the mapped range)."""
    return float(max(float(np.max(lv)) for fam in (jm.single, jm.pair, jm.group) for net in fam.values()
                     for lv in net.levels))


def trust_step(jac: np.ndarray, err: np.ndarray, radius: float) -> np.ndarray:
    """The least-squares step for ``jac @ step = err``, damped (Levenberg-Marquardt) to at most ``radius``."""
    u, sv, vt = np.linalg.svd(jac, full_matrices=False)
    g = u.T @ err
    keep = sv > 1e-12 * max(sv[0], 1e-300)

    def step(mu: float) -> np.ndarray:
        return vt[keep].T @ (sv[keep] * g[keep] / (sv[keep] ** 2 + mu))

    full = step(0.0)
    if np.linalg.norm(full) <= radius:
        return full
    lo, hi = 0.0, float(sv[0] ** 2 * max(1.0, np.linalg.norm(g) / (radius * sv[0])))  # |step(hi)| <= radius
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if np.linalg.norm(step(mid)) > radius else (lo, mid)
    return step(hi)


def broyden(measure, jac: np.ndarray, forces: dict[str, float], free: list[str], goal: np.ndarray, done,
            budget: int, first=None, upper: float = np.inf) -> Correction:
    """Quasi-Newton on the free forces (kept within 0..``upper`` N) until ``done(error, extra)``:
    ``measure(forces) -> (feature, extra)`` simulates; the first Jacobian is given (from the maps), later
    ones come from Broyden's update.  Each step starts from the best force set so far and is at most
    ``radius`` N long (a trust region: first the force that would move the feature four times its error along
    the Jacobian's strongest direction, doubled after a step that lowers the error, a quarter of the step after
    one that does not), so a nearly singular map Jacobian cannot throw a close candidate far off."""
    forces = dict(forces)
    feat, extra = measure(forces) if first is None else first
    sims = 1 if first is None else 0
    err = goal - feat
    history = [{"forces_n": dict(forces), "error": float(np.linalg.norm(err))}]
    best = Correction(dict(forces), feat, extra, float(np.linalg.norm(err)), sims, history)
    strongest = float(np.linalg.norm(jac, 2))
    radius = MAX_STEP_N if strongest == 0.0 else min(MAX_STEP_N, 4.0 * best.error / strongest)
    while not done(best.error, best.extra) and sims < budget:
        forces, feat, err = dict(best.forces), best.feature, goal - best.feature
        step = np.clip(trust_step(jac, err, radius), -MAX_STEP_N, MAX_STEP_N)
        f = np.array([forces.get(m, 0.0) for m in free])
        new = np.clip(f + step, 0.0, upper)
        step = new - f
        if np.abs(step).max() < 1e-6:
            break
        trial = dict(forces)
        trial.update({m: float(v) for m, v in zip(free, new)})
        got, got_extra = measure(trial)
        sims += 1
        jac = jac + np.outer((got - feat) - jac @ step, step) / float(step @ step)  # Broyden
        e = float(np.linalg.norm(goal - got))
        history.append({"forces_n": dict(trial), "error": e})
        if e < best.error:
            best = Correction(dict(trial), got, got_extra, e, sims, history)
            radius = min(2.0 * radius, MAX_STEP_N)
        else:
            radius = 0.25 * float(np.linalg.norm(step))
    best.simulations, best.history = sims, history
    return best


def refine(sim: Simulator, jm: JawMaps, jaw_forces: dict[str, float], candidate: Candidate, crucial: str,
           goal: np.ndarray, tolerance: float, budget: int = 8, first: np.ndarray | None = None) -> Refinement:
    """Correct the candidate's free forces until the simulated crucial point is within ``tolerance``."""
    c = CONTROL_POINTS.index(crucial)
    free = free_forces(candidate)
    jac = map_jacobian(jm, candidate, free, lambda family, name, x: x[..., c, :2])

    def measure(forces):
        x = sim.reach(jaw_forces, forces)
        return x[c, :2], x

    r = broyden(measure, jac, candidate.forces, free, goal, lambda e, _: e <= tolerance, budget,
                None if first is None else (first[c, :2], first), upper=top_force(jm))
    history = [{"forces_n": h["forces_n"], "error_cm": h["error"]} for h in r.history]
    return Refinement(forces=r.forces, reached=r.extra, error=r.error, simulations=r.simulations, history=history)
