"""The pipeline stages as plain Python functions (the CLI is a thin shell).

Each stage reads the previous stage's artefacts, checks they are fresh (the
config hash they were built from), and writes its own atomically.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from . import units
from .config import Config, config_hash, load_config
from .errors import ArticError
from .geometry.mesh import tongue_mesh
from .geometry.wall import wall_surface
from .io.store import atomic_h5, file_hash, load_mesh, save_mesh
from .mechanics.loads import load_program
from .mechanics.model import Model, build_model, rest_state
from .mechanics.simulate import Trajectory, run
from .schedule import load_schedule


@dataclass
class MeshSummary:
    path: Path
    nodes: int
    bricks: int
    cylinders: int
    volume_cm3: float
    cylinder_volume_cm3: float
    wall_triangles: int


def build_mesh(config: Path | str | None = None, out: Path | str = "data/mesh.h5",
               plot: Path | str | None = None) -> MeshSummary:
    cfg = load_config(config)
    mesh = tongue_mesh(cfg.speaker.tongue)
    wall = wall_surface(cfg.speaker.wall)
    save_mesh(out, mesh, wall, cfg)
    if plot:
        from .plots.mesh import plot_mesh

        plot_mesh(mesh, wall, cfg.speaker.landmarks_cm, plot)
    return MeshSummary(Path(out), len(mesh.nodes), len(mesh.bricks), len(mesh.cylinders), mesh.volume,
                       mesh.cylinder_volume, len(wall.triangles))


def load_model(mesh_path: Path | str, config: Path | str | None = None,
               volume_constraint: bool | None = None) -> tuple[Model, Config, object]:
    cfg = load_config(config)
    mesh, wall, _ = load_mesh(mesh_path, expect=cfg)
    model = build_model(mesh, cfg.materials.tongue, cfg.simulation, volume_constraint=volume_constraint)
    return model, cfg, wall


def _positive(name: str, value: float | None) -> None:
    if value is not None and (not math.isfinite(value) or value <= 0):
        raise ArticError(f"{name} must be a positive number of seconds, got {value}")


@dataclass
class SimResult:
    path: Path
    trajectory: Trajectory
    model: Model
    max_volume_change: float


def simulate(schedule: Path | str, duration: float | None = None, dt: float | None = None,
             mesh: Path | str = "data/mesh.h5", config: Path | str | None = None, out: Path | str | None = None,
             volume_constraint: bool | None = None, plot: Path | str | None = None,
             progress: Callable[[int, int], None] | None = None) -> SimResult:
    """Run the tissue model under a load schedule; write ``out`` (HDF5)."""
    _positive("--duration", duration)
    _positive("--dt", dt)
    sched = load_schedule(schedule)
    if duration is None:
        if sched.duration_ms is None:
            raise ArticError(f"{schedule}: no duration; give --duration S or 'duration_ms' in the schedule")
        duration = units.ms_to_s(sched.duration_ms)
    sched.check_duration(units.s_to_ms(duration), str(schedule))
    model, cfg, wall = load_model(mesh, config, volume_constraint)
    h = model.options.dt if dt is None else dt
    if h > duration:
        raise ArticError(f"--dt {h:g} s is longer than the run ({duration:g} s); give a smaller --dt")
    program = load_program(model, sched)
    traj, _ = run(model, rest_state(model), program.control_at, duration, h,
                  record_every=cfg.simulation.record_every, progress=progress)
    out = Path(out) if out is not None else Path("data/sims") / f"{Path(schedule).stem}.h5"
    write_trajectory(out, traj, model, cfg, inputs={"mesh": file_hash(mesh), "schedule": file_hash(schedule)},
                     extra={"duration_s": duration, "schedule_yaml": Path(schedule).read_text()})
    if plot:
        from .plots.simulation import plot_simulation

        plot_simulation(traj, model, wall, plot, title=f"{Path(schedule).stem}: start and end shapes")
    return SimResult(out, traj, model, float(np.abs(traj.volume_change).max()))


def control_point_indices(model: Model) -> dict[str, int]:
    return {name: int(model.mesh.node_sets[name][0]) for name in ("tip", "dorsum") if name in model.mesh.node_sets}


def write_trajectory(path: Path, traj: Trajectory, model: Model, cfg: Config, inputs: dict, extra: dict) -> None:
    with atomic_h5(path, "simulation", config_hash(cfg)) as f:
        for key, val in inputs.items():
            f.attrs[f"{key}_sha256"] = val
        for key, val in extra.items():
            f.attrs[key] = val
        opt = model.options
        f.attrs.update({"dt_s": traj.stats["dt"], "scheme": opt.scheme, "newton_tol_cm": opt.tol,
                        "newton_max_iter": opt.max_iter, "refactor_rate": opt.refactor_rate,
                        "volume_constraint": model.volume_constraint, "wall_time_s": traj.stats["wall_time_s"],
                        "steps": traj.stats["steps"], "factorisations": traj.stats["refactors"],
                        "newton_iterations": traj.stats["newton_iterations"],
                        "max_abs_volume_change": float(np.abs(traj.volume_change).max())})
        ds = f.create_dataset("time", data=traj.time)
        ds.attrs["units"] = "s"
        for name, data, unit in [("positions", traj.x, "cm"), ("velocities", traj.v, "cm/s")]:
            f.create_dataset(f"nodes/{name}", data=data, compression="gzip").attrs["units"] = unit
        for name, idx in control_point_indices(model).items():
            g = f.create_group(f"control_points/{name}")
            g.attrs["node"] = idx
            g.create_dataset("position", data=traj.x[:, idx]).attrs["units"] = "cm"
            g.create_dataset("velocity", data=traj.v[:, idx]).attrs["units"] = "cm/s"
        f.create_dataset("volume", data=traj.volume).attrs["units"] = "cm^3"
        f.create_dataset("volume_change", data=traj.volume_change).attrs["units"] = "fraction of initial volume"
        f.create_dataset("energy", data=units.erg_to_joule(traj.energy)).attrs["units"] = "J (kinetic + stored, from t0)"
        f.create_dataset("work", data=units.erg_to_joule(traj.work)).attrs["units"] = "J (external loads + gravity)"
        f.create_dataset("inverted_bricks", data=traj.inverted)
        f.create_dataset("newton_iterations", data=traj.iterations)
