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
from .mechanics.model import Model, build_articulator, build_model, rest_state
from .mechanics.simulate import Trajectory, run, settle
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


def load_model(mesh_path: Path | str, config: Path | str | None = None, volume_constraint: bool | None = None,
               tongue_only: bool = False, contact: bool | None = None) -> tuple[Model, Config, object]:
    """The whole articulator (or the tongue alone, its listed node sets held) from a mesh file."""
    cfg = load_config(config)
    mesh, wall, _ = load_mesh(mesh_path, expect=cfg)
    if tongue_only:
        model = build_model(mesh, cfg.materials.tongue, cfg.simulation, volume_constraint=volume_constraint)
    else:
        model = build_articulator(cfg, mesh, wall, volume_constraint=volume_constraint, contact=contact)
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
             progress: Callable[[int, int], None] | None = None, tongue_only: bool = False,
             contact: bool | None = None, animate: Path | str | None = None) -> SimResult:
    """Run the model under a schedule of muscle forces and loads from its rest posture; write ``out`` (HDF5)."""
    _positive("--duration", duration)
    _positive("--dt", dt)
    sched = load_schedule(schedule)
    if duration is None:
        if sched.duration_ms is None:
            raise ArticError(f"{schedule}: no duration; give --duration S or 'duration_ms' in the schedule")
        duration = units.ms_to_s(sched.duration_ms)
    sched.check_duration(units.s_to_ms(duration), str(schedule))
    model, cfg, wall = load_model(mesh, config, volume_constraint, tongue_only, contact)
    h = model.options.dt if dt is None else dt
    if h > duration:
        raise ArticError(f"--dt {h:g} s is longer than the run ({duration:g} s); give a smaller --dt")
    program = load_program(model, sched, str(schedule))
    start = rest_state(model) if tongue_only else settle(model)
    traj, _ = run(model, start, program.control_at, duration, h,
                  record_every=cfg.simulation.record_every, progress=progress)
    out = Path(out) if out is not None else Path("data/sims") / f"{Path(schedule).stem}.h5"
    write_trajectory(out, traj, model, cfg, inputs={"mesh": file_hash(mesh), "schedule": file_hash(schedule)},
                     extra={"duration_s": duration, "schedule_yaml": Path(schedule).read_text()})
    if plot:
        from .plots.simulation import plot_simulation

        plot_simulation(traj, model, wall, plot, title=f"{Path(schedule).stem}: start and end shapes")
    if animate:
        from .plots.animation import animate_simulation

        animate_simulation(traj, model, wall, animate)
    return SimResult(out, traj, model, float(np.abs(traj.volume_change).max()))


def control_point_indices(model: Model) -> dict[str, int]:
    """Tongue tip, dorsum (fifth midsagittal surface node from the tip) and jaw (lower incisor)."""
    return {name: int(model.node_sets[name][0]) for name in ("tip", "dorsum", "jaw") if name in model.node_sets}


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
        if traj.muscle_force is not None:
            g = f.create_group("muscles")
            g.attrs["names"] = list(model.muscle_names)
            g.create_dataset("force", data=units.dyn_to_newton(traj.muscle_force)).attrs["units"] = "N"
            g.create_dataset("length", data=traj.muscle_length).attrs["units"] = "cm"
        if traj.contact_count is not None:
            g = f.create_group("contacts")
            g.create_dataset("count", data=traj.contact_count)
            g.create_dataset("total_force", data=units.dyn_to_newton(traj.contact_total)).attrs["units"] = "N"
            g.create_dataset("projected", data=traj.projected)
            g.create_dataset("offsets", data=np.cumsum([0] + [len(c) for c in traj.contact_nodes]))
            g.create_dataset("nodes", data=np.concatenate(traj.contact_nodes).astype(np.int64))
            g.create_dataset("force", data=units.dyn_to_newton(np.concatenate(traj.contact_forces))).attrs["units"] = "N"
            g.attrs["layout"] = "frame k: nodes[offsets[k]:offsets[k+1]] with force[...] (N)"
