"""Stage ``simulate``: move the model under a schedule of muscle forces and loads; the trajectories on disk.

``run_simulation`` takes objects (a model, a schedule) and returns a :class:`Trajectory`; ``write`` and
``read`` are the file.  ``simulate`` is the file-level entry the CLI and ``make`` call.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import yaml

from .. import units
from ..config import Config, load_config
from ..errors import ArticError
from ..geometry.wall import WallSurface
from ..io.fingerprint import digest
from ..io.store import Provenance, atomic_h5, open_artifact
from ..mechanics.model import ARTICULATOR_SECTIONS, Model, build_articulator, build_model
from ..mechanics.record import Contacts, Simulation, node_parts
from ..mechanics.replay import run_schedule
from ..mechanics.simulate import Trajectory, problems
from ..schedule import Schedule, load_schedule
from ..validation import check_number
from . import mesh as mesh_stage
from . import paths
from .base import Stage, up_to_date

STAGE = Stage(name="sims", module=__name__, sections=ARTICULATOR_SECTIONS, reads=("mesh",), kind="simulation",
              hint="rerun 'artic simulate'")
TONGUE_SECTIONS = ("materials", "simulation")


def build(cfg: Config, mesh, wall: WallSurface, tongue_only: bool = False, volume_constraint: bool | None = None,
          contact: bool | None = None) -> Model:
    """The whole articulator, or the tongue alone with its fixed node sets held."""
    view = STAGE.view(cfg)
    if tongue_only:
        return build_model(mesh, view.materials.tongue, view.simulation, volume_constraint=volume_constraint)
    return build_articulator(view, mesh, wall, volume_constraint=volume_constraint, contact=contact)


def load_model(mesh_path: Path | str, config: Path | str | None = None, volume_constraint: bool | None = None,
               tongue_only: bool = False, contact: bool | None = None) -> tuple[Model, Config, WallSurface]:
    """The model of a mesh file and a config (the mesh checked against the config's speaker)."""
    cfg = load_config(config)
    m = mesh_stage.read(mesh_path, cfg)
    return build(cfg, m.mesh, m.wall, tongue_only, volume_constraint, contact), cfg, m.wall


def run_simulation(model: Model, schedule: Schedule, duration_s: float, dt_s: float, tongue_only: bool = False,
                   record_every: int = 1, source: str = "schedule",
                   progress: Callable[[int, int], None] | None = None) -> Trajectory:
    """From the rest posture (settled under gravity for the articulator), under ``schedule``."""
    return run_schedule(model, schedule, duration_s, dt_s, tongue_only, record_every, source, progress)


MIN_DT_S = 1e-6  # a step below a microsecond is a typo, not a simulation
MAX_DURATION_S = 60.0
@dataclass
class SimResult:
    path: Path
    trajectory: Trajectory | None  # None when the file was already up to date
    model: Model
    wall: WallSurface
    max_volume_change: float
    up_to_date: bool = False
    problems: list[str] = field(default_factory=list)  # why the result is not physical (its file is marked invalid)


def simulate(schedule: Path | str | Schedule, duration: float | None = None, dt: float | None = None,
             mesh: Path | str = paths.MESH, config: Path | str | None = None, out: Path | str | None = None,
             volume_constraint: bool | None = None, progress: Callable[[int, int], None] | None = None,
             tongue_only: bool = False, contact: bool | None = None, force: bool = False) -> SimResult:
    """Run the model under a schedule (a file, or one made in Python) from its rest posture; write ``out``
    (HDF5).  A file that already holds this recipe (same mesh content, config sections, schedule, options and
    code) is left alone."""
    check_number("--duration", duration, gt=0, le=MAX_DURATION_S, unit="s")
    check_number("--dt", dt, ge=MIN_DT_S, unit="s")
    cfg = load_config(config)
    made = isinstance(schedule, Schedule)
    sched = schedule if made else load_schedule(schedule, cfg.muscles.max_force_n)
    text = yaml.safe_dump(sched.model_dump(mode="json"), sort_keys=False) if made else Path(schedule).read_text()
    if made and out is None:
        raise ArticError("a schedule made in Python needs an output path (out=...)")
    if duration is None:
        if sched.duration_ms is None:
            raise ArticError(f"{schedule}: no duration; give --duration S or 'duration_ms' in the schedule")
        duration = units.ms_to_s(sched.duration_ms)
    sched.check_duration(units.s_to_ms(duration), str(schedule))
    m = mesh_stage.read(mesh, cfg)
    model = build(cfg, m.mesh, m.wall, tongue_only, volume_constraint, contact)
    h = model.options.dt if dt is None else dt
    if h > duration:
        raise ArticError(f"--dt {h:g} s is longer than the run ({duration:g} s); give a smaller --dt")
    out = Path(out) if out is not None else paths.SIMS / f"{Path(schedule).stem}.h5"
    sections = TONGUE_SECTIONS if tongue_only else ARTICULATOR_SECTIONS
    prov = STAGE.provenance(cfg, sections=sections,
                            inputs={"mesh": m.content_sha256, "schedule": digest(sched.mechanics_digest_data())},
                            params={"duration_s": duration, "dt_s": h, "tongue_only": tongue_only,
                                    "volume_constraint": model.volume_constraint, "contact": model.contact is not None,
                                    "record_every": cfg.simulation.record_every})
    if not force and up_to_date(out, prov):
        with open_artifact(out, "simulation", STAGE.hint, allow_invalid=True) as f:
            vol = float(f.attrs["max_abs_volume_change"])
            bad = [] if f.attrs.get("valid", True) else str(f.attrs.get("invalid_reason", "")).split("; ")
        return SimResult(out, None, model, m.wall, vol, up_to_date=True, problems=bad)
    traj = run_simulation(model, sched, duration, h, tongue_only, cfg.simulation.record_every, str(schedule),
                          progress)
    bad = problems(traj, model.volume_constraint)
    write(out, traj, model, prov, extra={"duration_s": duration, "schedule_yaml": text,
                                         "tongue_only": tongue_only, "valid": not bad,
                                         "invalid_reason": "; ".join(bad)})
    return SimResult(out, traj, model, m.wall, float(np.nanmax(np.abs(traj.volume_change))), problems=bad)


def write(path: Path | str, traj: Trajectory, model: Model, prov: Provenance | None = None,
          extra: dict | None = None) -> None:
    """Times, node positions and velocities (and which nodes are tongue, mandible, hyoid), control points,
    volume, energy, muscle forces and lengths, contacts; every dataset with its unit."""
    with atomic_h5(path, "simulation", prov) as f:
        f.attrs.update(extra or {})
        opt = model.options
        f.attrs.update({"dt_s": traj.stats["dt"], "scheme": opt.scheme, "newton_tol_cm": opt.tol,
                        "newton_max_iter": opt.max_iter, "refactor_rate": opt.refactor_rate,
                        "volume_constraint": model.volume_constraint, "wall_time_s": traj.stats["wall_time_s"],
                        "cpu_time_s": traj.stats["cpu_time_s"], "steps": traj.stats["steps"],
                        "factorisations": traj.stats["refactors"],
                        "newton_iterations": traj.stats["newton_iterations"],
                        "max_abs_volume_change": float(np.nanmax(np.abs(traj.volume_change)))})
        f.create_dataset("time", data=traj.time).attrs["units"] = "s"
        for name, data, unit in [("positions", traj.x, "cm"), ("velocities", traj.v, "cm/s")]:
            f.create_dataset(f"nodes/{name}", data=data, compression="gzip").attrs["units"] = unit
        f.create_dataset("nodes/rest", data=model.rest, compression="gzip").attrs["units"] = "cm (the model's rest, before gravity)"
        for part, idx in node_parts(model).items():
            f.create_dataset(f"nodes/parts/{part}", data=idx).attrs["units"] = "node indices"
        for name, idx in model.control_points().items():
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


def read(path: Path | str, allow_invalid: bool = False) -> Simulation:
    """A simulation file; one marked invalid (not physical) is refused unless ``allow_invalid``."""
    with open_artifact(path, "simulation", STAGE.hint, allow_invalid=allow_invalid) as f:
        try:
            contacts = None
            if "contacts" in f:
                g = f["contacts"]
                off = g["offsets"][()]
                nodes, force = g["nodes"][()], g["force"][()]
                contacts = Contacts(count=g["count"][()], total_force_n=g["total_force"][()],
                                    nodes=[nodes[a:b] for a, b in zip(off[:-1], off[1:])],
                                    force_n=[force[a:b] for a, b in zip(off[:-1], off[1:])])
            m = f.get("muscles")
            return Simulation(
                time_s=f["time"][()], positions_cm=f["nodes/positions"][()],
                rest_cm=f["nodes/rest"][()] if "nodes/rest" in f else None, velocities_cm_s=f["nodes/velocities"][()],
                parts={k: v[()] for k, v in f["nodes/parts"].items()},
                control_points={k: g["position"][()] for k, g in f["control_points"].items()},
                volume_change=f["volume_change"][()], inverted_bricks=f["inverted_bricks"][()],
                muscle_names=[] if m is None else [str(n) for n in m.attrs["names"]],
                muscle_force_n=None if m is None else m["force"][()],
                muscle_length_cm=None if m is None else m["length"][()], contacts=contacts,
                attrs={k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()})
        except (KeyError, ValueError, OSError) as err:
            raise ArticError(f"{path} is damaged or incomplete ({type(err).__name__}); {STAGE.hint}") from None
