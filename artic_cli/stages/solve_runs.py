"""Solving many targets and replaying answers: the orchestration around the solve stage (its files are
:mod:`artic_cli.stages.solve`'s).  ``solve_batch`` solves an utterance's targets (one process or several),
``solve_files`` is what ``artic solve-target`` runs, ``replay_solution`` what ``artic simulate --solution`` runs."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..config import DEFAULT_CONFIG, load_config
from ..control.solver import TargetSpec
from ..control.targets import batch_csv, load_target, read_batch
from ..control.targets import solve_batch as solve_rows
from ..errors import ArticError, UnreachableTarget
from ..io.fingerprint import digest
from ..io.store import write_text_atomic
from ..speech.plan import Answer
from ..validation import check_number
from . import loaded, paths
from .solve import add_formants, load_context, read, simulator, solve_target


def solution_path(folder: Path | str, t: TargetSpec) -> Path:
    """Where a batch keeps a target's answer: its name and the first digits of its content key."""
    return Path(folder) / f"{t.name}-{digest(t.model_dump(mode='json'))[:8]}.yaml"


def solve_batch(targets: list[TargetSpec], maps: Path | str, mesh: Path | str, acoustic_maps: Path | str | None,
                config: Path | str | None, folder: Path | str, budget: int = 8, dynamic: Path | str | None = None,
                jobs: int = 1) -> list[Answer]:
    """Solve and refine every target (each answer kept under ``folder``, up-to-date ones read back), in this
    process with the maps and simulators loaded once, or one target per process on ``jobs`` workers.  An
    unreachable target is an :class:`Answer` carrying its error; any other error is raised (the earliest
    target's)."""
    args = (maps, mesh, acoustic_maps, config, str(folder), budget, None if dynamic is None else str(dynamic))
    if jobs > 1 and len(targets) > 1:
        from joblib import Parallel, delayed

        answers = Parallel(n_jobs=min(jobs, len(targets)))(delayed(_solve_one)(t, *args) for t in targets)
        failed = [a for a in answers if isinstance(a, ArticError)]
        if failed:
            raise failed[0]
        return answers
    return _solve_here(targets, *args)


def _solve_one(t: TargetSpec, *args) -> Answer | ArticError:
    """One target in a worker process; its error is returned (the parent raises the earliest target's)."""
    try:
        return _solve_here([t], *args)[0]
    except ArticError as err:
        return err


def _solve_here(targets: list[TargetSpec], maps, mesh, acoustic_maps, config, folder: str, budget: int,
                dynamic: str | None) -> list[Answer]:
    if not targets:
        return []
    tract = any(t.needs_tract for t in targets)
    files = (maps, dynamic, mesh, acoustic_maps, config or DEFAULT_CONFIG)
    ctx = loaded.once("solve-context", lambda: _context(maps, dynamic, mesh, acoustic_maps, config, tract),
                      files, (tract,))
    voicer = loaded.once("voicer", lambda: simulator(mesh, config, voiced=True), files[2:]) if tract else None
    sim = voicer.sim if voicer is not None else loaded.once("simulator", lambda: simulator(mesh, config), files[2:])
    out = []
    for t in targets:
        path = solution_path(folder, t)
        try:
            with _solving(path):  # another worker solving the same target: wait for its answer and read it
                doc, path, _ = solve_target(t, ctx, path, voicer if t.needs_tract else sim, False, True, budget,
                                            config, sim.mesh_sha256)
            out.append(Answer(doc, path))
        except UnreachableTarget as err:
            out.append(Answer(read(path) if path.is_file() else None, path, err))
    return out


def _context(maps, dynamic, mesh, acoustic_maps, config, tract: bool):
    ctx = load_context(maps, dynamic, mesh)
    return add_formants(ctx, maps, mesh, config, acoustic_maps) if tract else ctx


def _solving(path: Path):
    """A lock on one answer's file (in the folder's ``.locks``), held while it is solved."""
    from filelock import FileLock

    locks = path.parent / ".locks"
    locks.mkdir(parents=True, exist_ok=True)
    return FileLock(locks / f"{path.name}.lock")


@dataclass
class Solved:
    """What ``artic solve-target`` solved: one target's answer, or a batch's rows written as CSV."""

    target: TargetSpec | None = None
    doc: dict | None = None
    path: Path | None = None
    up_to_date: bool = False
    rows: list[dict] | None = None  # a batch's answers


def solve_files(target: Path | str | None = None, batch: Path | str | None = None, maps: Path | str = paths.EPMAPS,
                dynamic: Path | str = paths.DYNAMIC, mesh: Path | str = paths.MESH, config: Path | str | None = None,
                acoustic_maps: Path | str = paths.ACOUSTIC_MAPS, out: Path | str | None = None,
                verify: bool = False, refine: bool = False, budget: int = 8, jobs: int = 2,
                progress=None, hold_jaw: bool | None = None) -> Solved:
    """A target file, or every row of a batch CSV (written to ``out``, default data/solutions/BATCH.csv, with
    ``verify``/``refine`` on ``jobs`` workers), solved on the maps; what a target needs is loaded once: the
    dynamic map for places, the formants of every EP for acoustic targets, the simulator for checks."""
    if (target is None) == (batch is None):
        raise ArticError("give a target file or --batch CSV (one of them)")
    check_number("--budget", budget, ge=1)
    check_number("--jobs", jobs, ge=1)
    targets = read_batch(batch) if batch is not None else [load_target(target)]  # the user's file first
    acoustic = any(t.needs_tract for t in targets)
    spatial = any(not t.needs_tract for t in targets)  # acoustic targets use the mapped jaw positions only
    ctx = load_context(maps, dynamic if spatial else None, mesh if (verify or refine or acoustic) else None)
    if acoustic:
        add_formants(ctx, maps, mesh, config, acoustic_maps)
    sim = simulator(mesh, config, voiced=acoustic, hold_jaw=hold_jaw) if (verify or refine) else None
    if batch is not None:
        base = None if sim is None else sim.simulation
        args = None if base is None else (base.cfg, base.mesh, base.wall, base.mesh_sha256, base.hold_jaw)
        rows = solve_rows(ctx, targets, jobs, args, verify, refine, budget, progress)
        path = Path(out) if out is not None else paths.SOLUTIONS / f"{Path(batch).stem}.csv"
        write_text_atomic(path, batch_csv(rows))
        return Solved(path=path, rows=rows)
    doc, path, fresh = solve_target(targets[0], ctx, out, sim, verify, refine, budget, config,
                                    "" if sim is None else sim.mesh_sha256)
    return Solved(target=targets[0], doc=doc, path=path, up_to_date=fresh)


@dataclass
class Replay:
    """An answer run again as it was verified: where its forces take the control points (cm), what the
    solution recorded, and the crucial point's error (cm; None for a formant target)."""

    reached_cm: dict[str, list[float]]
    recorded_cm: dict[str, list[float]]
    crucial_error_cm: float | None
    conditions: dict
    path: Path | None = None  # the simulation file (a free-jaw replay)


def replay_solution(solution: Path | str, mesh: Path | str = paths.MESH, config: Path | str | None = None,
                    out: Path | str | None = None, hold_jaw: bool | None = None, progress=None) -> Replay:
    """Run a solution's forces as its verification ran them (``hold_jaw`` overrides the recorded condition):
    the jaw free, every force on at 0 ms from the rest posture, through ``artic simulate`` (a simulation file,
    ``out``); or the jaw held, as the maps hold it."""
    from ..mechanics.replay import held_forces
    from ..speech.plan import solution_forces
    from . import simulate as sim_stage

    doc = read(solution)
    cond = doc.get("verification")
    if not cond:
        raise ArticError(f"{solution} records no verification; solve the target with --verify or --refine")
    forces, _, which = solution_forces(doc)
    held = cond["jaw"] == "held" if hold_jaw is None else bool(hold_jaw)
    recorded = (doc.get("refined") if which == "refined" else doc.get("verified")) or {}
    path = None
    if held:
        reached = simulator(mesh, config, hold_jaw=True).reach(dict(doc["jaw"]["forces_n"]), {
            k: v for k, v in forces.items() if k not in doc["jaw"]["forces_n"]})
    else:
        cfg = load_config(config)
        path = Path(out) if out is not None else paths.SIMS / f"{Path(solution).stem}.h5"
        r = sim_stage.simulate(held_forces(forces, cond["duration_ms"], cfg.muscles.max_force_n),
                               cond["duration_ms"] / 1e3, mesh=mesh, config=config, out=path, progress=progress)
        cps = sim_stage.read(r.path).control_points
        reached = np.array([cps[n][-1] for n in ("tip", "dorsum", "jaw")])
    got = {n: [round(float(v), 4) for v in reached[k, :2]] for k, n in enumerate(("tip", "dorsum", "jaw"))}
    error = None
    if "crucial" in doc:
        error = float(np.linalg.norm(reached[("tip", "dorsum").index(doc["crucial"]["point"]), :2]
                                     - np.asarray(doc["crucial"]["at_cm"], float)))
    return Replay(reached_cm=got, recorded_cm=recorded.get("reached_cm", {}), crucial_error_cm=error,
                  conditions=dict(cond, jaw="held" if held else "free"), path=path)
